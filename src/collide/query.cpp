// World queries: the query world's build and refit, its filters, and ray casts (closest,
// any, all, batched) through the dynamic tree. Shape casts, overlaps and distances are in
// query_shape.cpp; the traversals they share are in query_internal.h.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "pba/collide/query.h"
#include "query_internal.h"

namespace pba {

namespace query {

bool shape_ok(const ColliderShape& s) {
  auto pos = [](double v) { return fits_float(v) && v > 0; };
  switch (s.type) {
    case ShapeType::Plane: return fits_float(s.normal) && glm::length(s.normal) > 0 && fits_float(s.offset);
    case ShapeType::Sphere: return pos(s.radius);
    case ShapeType::Box: return pos(s.half_extents.x) && pos(s.half_extents.y) && pos(s.half_extents.z);
    case ShapeType::Capsule: return pos(s.radius) && fits_float(s.half_height) && s.half_height >= 0;
    case ShapeType::Hull: return s.hull != nullptr;
    case ShapeType::Mesh: return s.mesh != nullptr;
    case ShapeType::Compound: return s.compound != nullptr;
  }
  return false;
}

void check_shape(const ColliderShape& s, std::string_view where) {
  if (shape_ok(s)) return;
  s.validate(where);
  // valid, so a size beyond a float's range
  switch (s.type) {
    case ShapeType::Plane:
      require_float(s.normal, field_path(where, "normal"));
      require_float(s.offset, field_path(where, "offset"));
      break;
    case ShapeType::Sphere: require_float(s.radius, field_path(where, "radius")); break;
    case ShapeType::Box: require_float(s.half_extents, field_path(where, "half_extents")); break;
    case ShapeType::Capsule:
      require_float(s.radius, field_path(where, "radius"));
      require_float(s.half_height, field_path(where, "half_height"));
      break;
    default: break;
  }
}

bool pose_ok(const Pose& p) {
  const Quat& q = p.rotation;
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return fits_float(p.position) && std::isfinite(n) && std::abs(n - 1) <= 1e-6;
}

void check_pose(const Pose& p, std::string_view where) {
  if (pose_ok(p)) return;
  require_float(p.position, field_path(where, "position"));
  require_unit_quat(p.rotation, field_path(where, "rotation"));
}

Vec3 unit_direction(const Vec3& d, std::string_view where) {
  if (!is_finite(d)) require_finite(d, where);
  // scaled first so that huge components do not overflow the length
  const double m = std::max(std::abs(d.x), std::max(std::abs(d.y), std::abs(d.z)));
  if (!(m > 0)) throw Error(std::string(where) + ": must be non-zero, got " + format_vec3(d));
  const Vec3 s = d / m;
  return s / glm::length(s);
}

Ray checked_ray(const Ray& r, std::string_view where) {
  if (!is_finite(r.origin)) require_finite(r.origin, field_path(where, "origin"));
  if (!(std::isfinite(r.max_distance) && r.max_distance >= 0))
    require_non_negative(r.max_distance, field_path(where, "max_distance"));
  // the common case (a finite non-zero direction) builds no string; a unit one (to 4
  // ulps of its squared length) is kept as it is, so the hits equal the shapes' ray_cast()
  const double len2 = glm::dot(r.direction, r.direction);
  if (std::abs(len2 - 1) <= 1e-15) return r;
  if (is_finite(r.direction) && len2 > 0) {
    const double m = std::max(std::abs(r.direction.x), std::max(std::abs(r.direction.y), std::abs(r.direction.z)));
    const Vec3 s = r.direction / m;
    return {r.origin, s / glm::length(s), r.max_distance};
  }
  return {r.origin, unit_direction(r.direction, field_path(where, "direction")), r.max_distance};
}

void check_convex(const ColliderShape& s, const Pose& p, std::string_view where) {
  if (!s.is_convex())
    throw Error(field_path(where, "type") + ": must be a sphere, capsule, box or hull, got a " +
                std::string(to_string(s.type)));
  // the messages' strings only for bad input: a query never allocates
  if (!shape_ok(s)) check_shape(s, where);
  if (!pose_ok(p)) check_pose(p, field_path(where, "pose"));
}

}  // namespace query

// --- build -----------------------------------------------------------------------------

void QueryWorld::push(const Collider& c, std::uint32_t owner) {
  shapes_.push_back(c.shape);
  poses_.push_back(c.end);
  owners_.push_back(owner);
  filters_.push_back({});
  bounds_.push_back(pba::bounds(c.shape, c.end));
}

void QueryWorld::build(const CollisionWorld& world) {
  // the world's colliders are validated when added
  const auto cs = world.colliders();
  const auto os = world.owners();
  shapes_.clear();
  poses_.clear();
  owners_.clear();
  filters_.clear();
  bounds_.clear();
  for (std::size_t i = 0; i < cs.size(); ++i) push(cs[i], os[i]);
  refit();
}

void QueryWorld::build(std::span<const Collider> colliders, std::span<const std::uint32_t> owners,
                       std::span<const CollisionFilter> filters, std::string_view where) {
  // lengths, then each collider's shape and end pose (a message only for a bad one)
  const std::size_t n = colliders.size();
  if (!owners.empty() && owners.size() != n)
    throw Error(std::string(where) + ": owners has " + std::to_string(owners.size()) + " entries for " +
                std::to_string(n) + " colliders");
  if (!filters.empty() && filters.size() != n)
    throw Error(std::string(where) + ": filters has " + std::to_string(filters.size()) + " entries for " +
                std::to_string(n) + " colliders");
  for (std::size_t i = 0; i < n; ++i) {
    if (query::shape_ok(colliders[i].shape) && query::pose_ok(colliders[i].end)) continue;
    const std::string w = std::string(where) + "[" + std::to_string(i) + "]";
    query::check_shape(colliders[i].shape, w);
    query::check_pose(colliders[i].end, field_path(w, "end"));
  }
  // copy, then the tree
  shapes_.clear();
  poses_.clear();
  owners_.clear();
  filters_.clear();
  bounds_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    push(colliders[i], owners.empty() ? CollisionWorld::kNoOwner : owners[i]);
    if (!filters.empty()) filters_[i] = filters[i];
  }
  refit();
}

void QueryWorld::refit() {
  // a collider is in the tree when its bounds are finite (every shape but a plane)
  const std::size_t n = shapes_.size();
  auto bounded = [&](std::size_t i) { return is_finite(bounds_[i].lo) && is_finite(bounds_[i].hi); };
  bool same = leaf_.size() == n;
  for (std::size_t i = 0; same && i < n; ++i) same = (leaf_[i] != DynamicTree::kNull) == bounded(i);
  if (same) {
    // the same colliders: move each leaf (free while it stays in its fat box)
    for (std::size_t i = 0; i < n; ++i)
      if (leaf_[i] != DynamicTree::kNull) tree_.move_proxy(leaf_[i], bounds_[i]);
    flatten();
    return;
  }
  // otherwise a fresh tree, built top-down by the surface-area heuristic
  tree_.clear();
  leaf_.assign(n, DynamicTree::kNull);
  unbounded_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (bounded(i))
      leaf_[i] = tree_.create_proxy(bounds_[i], static_cast<std::uint32_t>(i));
    else
      unbounded_.push_back(static_cast<std::uint32_t>(i));
  }
  tree_.rebuild();
  flatten();
}

void QueryWorld::flatten() {
  // depth-first from the root: a node's first child is the next node, which keeps the
  // nearer half of most traversals in the same few cache lines
  flat_.clear();
  const auto nodes = tree_.nodes();
  const std::int32_t top = tree_.root();
  if (top == DynamicTree::kNull) {
    root_ = kEmpty;
    return;
  }
  auto ref = [&](std::int32_t n) {
    const DynamicTree::Node& d = nodes[static_cast<std::size_t>(n)];
    return d.is_leaf() ? ~static_cast<std::int32_t>(d.user) : n;
  };
  if (nodes[static_cast<std::size_t>(top)].is_leaf()) {
    root_ = ref(top);
    return;
  }
  // the stack holds (tree node, flat slot of its parent, which child it is)
  struct Item {
    std::int32_t node, parent, side;
  };
  Item stack[query::kStack];
  int depth = 0;
  stack[depth++] = {top, -1, 0};
  root_ = 0;
  while (depth > 0) {
    const Item it = stack[--depth];
    const DynamicTree::Node& d = nodes[static_cast<std::size_t>(it.node)];
    const auto slot = static_cast<std::int32_t>(flat_.size());
    if (it.parent >= 0) flat_[static_cast<std::size_t>(it.parent)].child[it.side] = slot;
    Node out;
    const std::int32_t c[2] = {d.child1, d.child2};
    for (int k = 0; k < 2; ++k) {
      out.box[k] = nodes[static_cast<std::size_t>(c[k])].box;
      out.child[k] = ref(c[k]);
    }
    flat_.push_back(out);
    // the second child is pushed first so the first is flattened next
    for (int k = 1; k >= 0; --k)
      if (out.child[k] >= 0) stack[depth++] = {c[k], slot, k};
  }
  // the boxes tight again: the tree's leaves are fat (cheap refits), the traversals want
  // the colliders' own bounds; children come after their parents, so a backward pass
  // merges each node's boxes before its parent reads them
  for (std::size_t k = flat_.size(); k-- > 0;) {
    Node& n = flat_[k];
    for (int side = 0; side < 2; ++side) {
      const std::int32_t c = n.child[side];
      if (c < 0) {
        n.box[side] = bounds_[static_cast<std::size_t>(~c)];
      } else {
        const Node& m = flat_[static_cast<std::size_t>(c)];
        n.box[side] = m.box[0].merged(m.box[1]);
      }
    }
  }
}

void QueryWorld::set_filter(std::size_t i, const CollisionFilter& filter) {
  if (i >= filters_.size())
    throw Error("QueryWorld.set_filter: collider " + std::to_string(i) + " out of range (size " +
                std::to_string(filters_.size()) + ")");
  filters_[i] = filter;
}

bool QueryWorld::accepts(const QueryFilter& f, std::uint32_t i) const {
  const CollisionFilter& c = filters_[i];
  if ((f.layer & c.mask) == 0 || (c.layer & f.mask) == 0) return false;
  if (f.ignore_owner != CollisionWorld::kNoOwner && owners_[i] == f.ignore_owner) return false;
  return f.accept.fn == nullptr || f.accept.fn(f.accept.context, i, owners_[i]);
}

// --- ray casts -------------------------------------------------------------------------

namespace {

QueryRayHit to_query_hit(const RayHit& h, std::uint32_t i, std::uint32_t owner) {
  return {true, h.distance, h.point, h.normal, h.feature, i, owner};
}

// true when hit (distance d, collider i) comes before `best` in the (distance, index) order
bool before(double d, std::uint32_t i, const QueryRayHit& best) {
  return !best.hit || d < best.distance || (d == best.distance && i < best.collider);
}

}  // namespace

QueryRayHit QueryWorld::ray_cast(const Ray& ray_in, const QueryFilter& filter) const {
  const Ray ray = query::checked_ray(ray_in, "QueryWorld.ray_cast(ray)");
  QueryRayHit best;
  // each candidate against the ray clipped to the best hit so far; ties to the lower index
  auto test = [&](std::uint32_t i, double max_t) {
    if (!accepts(filter, i)) return max_t;
    const RayHit h = query::ray_cast_unit(shapes_[i], poses_[i], {ray.origin, ray.direction, max_t});
    if (h.hit && before(h.distance, i, best)) best = to_query_hit(h, i, owners_[i]);
    return best.hit ? best.distance : max_t;
  };
  double max_t = ray.max_distance;
  for (std::uint32_t i : unbounded_) max_t = test(i, max_t);
  query::sweep(flat_, root_, ray.origin, ray.direction, max_t, Vec3(0.0), Vec3(0.0), test);
  return best;
}

QueryRayHit QueryWorld::ray_cast_any(const Ray& ray_in, const QueryFilter& filter) const {
  const Ray ray = query::checked_ray(ray_in, "QueryWorld.ray_cast_any(ray)");
  QueryRayHit found;
  // the first accepted hit stops the traversal
  auto test = [&](std::uint32_t i, double max_t) {
    if (!accepts(filter, i)) return max_t;
    const RayHit h = query::ray_cast_unit(shapes_[i], poses_[i], ray);
    if (!h.hit) return max_t;
    found = to_query_hit(h, i, owners_[i]);
    return -1.0;
  };
  for (std::uint32_t i : unbounded_)
    if (test(i, ray.max_distance) < 0) return found;
  query::sweep(flat_, root_, ray.origin, ray.direction, ray.max_distance, Vec3(0.0), Vec3(0.0), test);
  return found;
}

std::size_t QueryWorld::ray_cast_all(const Ray& ray_in, std::span<QueryRayHit> out, const QueryFilter& filter) const {
  const Ray ray = query::checked_ray(ray_in, "QueryWorld.ray_cast_all(ray)");
  std::size_t total = 0;
  // every accepted hit, kept in (distance, index) order, the ray never clipped
  auto less = [](const QueryRayHit& a, const QueryRayHit& b) {
    return a.distance < b.distance || (a.distance == b.distance && a.collider < b.collider);
  };
  auto test = [&](std::uint32_t i, double max_t) {
    if (!accepts(filter, i)) return max_t;
    const RayHit h = query::ray_cast_unit(shapes_[i], poses_[i], ray);
    if (h.hit) query::insert_sorted(out, total++, to_query_hit(h, i, owners_[i]), less);
    return max_t;
  };
  for (std::uint32_t i : unbounded_) test(i, ray.max_distance);
  query::sweep(flat_, root_, ray.origin, ray.direction, ray.max_distance, Vec3(0.0), Vec3(0.0), test);
  return total;
}

std::size_t QueryWorld::ray_cast(std::span<const Ray> rays, std::span<QueryRayHit> hits,
                                 const QueryFilter& filter) const {
  if (rays.size() != hits.size())
    throw Error("QueryWorld.ray_cast(rays, hits): " + std::to_string(hits.size()) + " hits for " +
                std::to_string(rays.size()) + " rays");
  // each ray in turn (a bad ray's message names its index)
  std::size_t count = 0;
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const Ray& r = rays[k];
    if (!(is_finite(r.origin) && is_finite(r.direction) && glm::dot(r.direction, r.direction) > 0 &&
          std::isfinite(r.max_distance) && r.max_distance >= 0))
      query::checked_ray(r, "QueryWorld.ray_cast(rays)[" + std::to_string(k) + "]");
    hits[k] = ray_cast(r, filter);
    count += hits[k].hit ? 1 : 0;
  }
  return count;
}

}  // namespace pba
