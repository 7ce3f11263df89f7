// The collision world: the colliders of a tick, validated once and flattened once for
// every client (the particle kernel in float, the soft bodies in double).
#include <algorithm>
#include <cstring>
#include <string>
#include <type_traits>

#include "pba/collide/collision_world.h"

namespace pba {

namespace detail {

namespace {

// The rotation the flat form uses. Colliders are validated unit to 1e-6; the float form
// renormalises (the particle kernel always did, and float keeps nothing of the last
// bits anyway), the double form takes the quaternion as given (the soft bodies always
// did): each client keeps the bits it had before the two shared this code.
template <class T>
Quat flat_rotation(const Quat& q) {
  if constexpr (std::is_same_v<T, float>)
    return glm::normalize(q);
  else
    return q;
}

// column-major rotation matrix, rounded to T
template <class T>
void rotation_columns(const Quat& q, T* r) {
  const Mat3 m = glm::mat3_cast(flat_rotation<T>(q));
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r[c * 3 + k] = static_cast<T>(m[c][k]);
}

// the radius about the frame origin of the ball that holds what the swept point contact
// clips against, less the point's radius: a sphere's radius, a box's corner, a capsule's
// cap, the farthest corner of a hull's or mesh's local bounds (the hull's clip box), a
// compound's farthest leaf (its offset plus its own reach)
double shape_reach(const ColliderShape& s) {
  switch (s.type) {
    case ShapeType::Sphere: return s.radius;
    case ShapeType::Box: return glm::length(s.half_extents);
    case ShapeType::Capsule: return s.half_height + s.radius;
    case ShapeType::Hull:
    case ShapeType::Mesh: {
      const Aabb b = s.type == ShapeType::Hull ? s.hull->bounds() : s.mesh->bounds();
      return glm::length(glm::max(glm::abs(b.lo), glm::abs(b.hi)));
    }
    case ShapeType::Compound: {
      double r = 0;
      for (const CompoundChild& ch : s.compound->children)
        r = std::max(r, glm::length(ch.pose.position) + shape_reach(ch.shape));
      return r;
    }
    case ShapeType::Plane: break;
  }
  return 0;
}

}  // namespace

template <class T>
FlatShape<T> flatten(const Collider& c) {
  FlatShape<T> p{};
  p.type = c.shape.type;
  p.e = static_cast<T>(c.material.restitution);
  p.mu = static_cast<T>(c.material.friction);
  // planes in world: n = R n_local / |n_local|, d = offset / |n_local| + n . origin
  const double len = glm::length(c.shape.normal);
  const Vec3 nl = c.shape.normal / len;
  const double offset = c.shape.offset / len;
  auto plane = [&](const Pose& pose, T& nx, T& ny, T& nz, T& d) {
    const Vec3 n = glm::normalize(flat_rotation<T>(pose.rotation) * nl);
    nx = static_cast<T>(n.x);
    ny = static_cast<T>(n.y);
    nz = static_cast<T>(n.z);
    d = static_cast<T>(offset + glm::dot(n, pose.position));
  };
  plane(c.begin, p.n0x, p.n0y, p.n0z, p.d0);
  plane(c.end, p.n1x, p.n1y, p.n1z, p.d1);
  // the frame's path and the shape's parameters
  p.c0x = static_cast<T>(c.begin.position.x);
  p.c0y = static_cast<T>(c.begin.position.y);
  p.c0z = static_cast<T>(c.begin.position.z);
  p.c1x = static_cast<T>(c.end.position.x);
  p.c1y = static_cast<T>(c.end.position.y);
  p.c1z = static_cast<T>(c.end.position.z);
  p.radius = static_cast<T>(c.shape.radius);
  p.hh = static_cast<T>(c.shape.half_height);
  p.hx = static_cast<T>(c.shape.half_extents.x);
  p.hy = static_cast<T>(c.shape.half_extents.y);
  p.hz = static_cast<T>(c.shape.half_extents.z);
  rotation_columns(c.begin.rotation, p.r0);
  rotation_columns(c.end.rotation, p.r1);
  // the frame's motion
  p.vx = static_cast<T>(c.velocity.x);
  p.vy = static_cast<T>(c.velocity.y);
  p.vz = static_cast<T>(c.velocity.z);
  p.wx = static_cast<T>(c.angular_velocity.x);
  p.wy = static_cast<T>(c.angular_velocity.y);
  p.wz = static_cast<T>(c.angular_velocity.z);
  p.is_static = p.n0x == p.n1x && p.n0y == p.n1y && p.n0z == p.n1z && p.d0 == p.d1 && p.c0x == p.c1x &&
                p.c0y == p.c1y && p.c0z == p.c1z && c.velocity == Vec3(0) && c.angular_velocity == Vec3(0);
  // hulls, meshes and compounds: how far the shape reaches from the origin, rounded up (a
  // float rounds by 6e-8 relative; 1e-6 covers it)
  const ShapeType t = c.shape.type;
  if (t == ShapeType::Hull || t == ShapeType::Mesh || t == ShapeType::Compound)
    p.reach = static_cast<T>(shape_reach(c.shape) * (1 + 1e-6));
  return p;
}

template FlatShape<float> flatten<float>(const Collider&);
template FlatShape<double> flatten<double>(const Collider&);

}  // namespace detail

namespace {

// same bit patterns in every field (so the same flat forms; -0 and +0 differ here)
template <class V>
bool bits(const V& a, const V& b) {
  return std::memcmp(&a, &b, sizeof(V)) == 0;
}
bool same_bits(const Collider& a, const Collider& b) {
  const ColliderShape &s = a.shape, &t = b.shape;
  return s.type == t.type && bits(s.normal, t.normal) && bits(s.offset, t.offset) && bits(s.radius, t.radius) &&
         bits(s.half_extents, t.half_extents) && bits(s.half_height, t.half_height) && s.hull == t.hull &&
         s.mesh == t.mesh && s.compound == t.compound && bits(a.material.restitution, b.material.restitution) &&
         bits(a.material.friction, b.material.friction) && bits(a.begin.position, b.begin.position) &&
         bits(a.begin.rotation, b.begin.rotation) && bits(a.end.position, b.end.position) &&
         bits(a.end.rotation, b.end.rotation) && bits(a.velocity, b.velocity) &&
         bits(a.angular_velocity, b.angular_velocity);
}

}  // namespace

CollisionWorld::CollisionWorld(const CollisionWorld& o)
    : colliders_(o.colliders_), parts_(o.parts_), part_flat_(o.part_flat_), owners_(o.owners_), flat_f_(o.flat_f_),
      flat_d_(o.flat_d_) {
  relink();
}

CollisionWorld& CollisionWorld::operator=(const CollisionWorld& o) {
  if (this == &o) return *this;
  colliders_ = o.colliders_;
  parts_ = o.parts_;
  part_flat_ = o.part_flat_;
  owners_ = o.owners_;
  flat_f_ = o.flat_f_;
  flat_d_ = o.flat_d_;
  relink();
  return *this;
}

void CollisionWorld::clear() {
  colliders_.clear();
  parts_.clear();
  part_flat_.clear();
  owners_.clear();
  flat_f_.clear();
  flat_d_.clear();
  ++revision_;
}

// a compound's leaves, depth first, each at its pose composed with the compound's; the
// velocity of a leaf's origin is that of the compound's frame at it (v + w x r)
void CollisionWorld::add_parts(const ColliderShape& s, const Collider& parent, const Pose& begin, const Pose& end) {
  for (const CompoundChild& ch : s.compound->children) {
    const Pose b = compose(begin, ch.pose), e = compose(end, ch.pose);
    if (ch.shape.type == ShapeType::Compound) {
      add_parts(ch.shape, parent, b, e);
      continue;
    }
    Collider leaf;
    leaf.shape = ch.shape;
    leaf.material = parent.material;
    leaf.begin = b;
    leaf.end = e;
    leaf.velocity = parent.velocity + glm::cross(parent.angular_velocity, e.position - parent.end.position);
    leaf.angular_velocity = parent.angular_velocity;
    parts_.push_back(leaf);
    part_flat_.push_back(detail::flatten<double>(leaf));
  }
}

void CollisionWorld::link(std::size_t i) {
  const ShapeType t = colliders_[i].shape.type;
  if (t != ShapeType::Hull && t != ShapeType::Mesh && t != ShapeType::Compound) return;
  flat_f_[i].source = flat_d_[i].source = &colliders_[i];
  if (t == ShapeType::Compound)
    flat_f_[i].parts = flat_d_[i].parts = part_flat_.data() + flat_d_[i].first_part;
}

void CollisionWorld::relink() {
  for (std::size_t j = 0; j < parts_.size(); ++j) part_flat_[j].source = &parts_[j];
  for (std::size_t i = 0; i < colliders_.size(); ++i) link(i);
}

std::size_t CollisionWorld::add(const Collider& c, std::uint32_t owner, std::string_view where) {
  // validate (the message is built only for a bad collider), then flatten once
  if (!c.ok()) c.validate(where);
  return push(c, owner);
}

std::size_t CollisionWorld::push(const Collider& c, std::uint32_t owner) {
  // the buffers the links point into, before they may grow
  const Collider* shapes_at = colliders_.data();
  const Collider* parts_at = parts_.data();
  const detail::FlatShape<double>* flats_at = part_flat_.data();
  const std::size_t first = parts_.size();
  colliders_.push_back(c);
  owners_.push_back(owner);
  flat_f_.push_back(detail::flatten<float>(c));
  flat_d_.push_back(detail::flatten<double>(c));
  if (c.shape.type == ShapeType::Compound) {
    add_parts(c.shape, c, c.begin, c.end);
    flat_f_.back().first_part = flat_d_.back().first_part = static_cast<std::uint32_t>(first);
    flat_f_.back().n_parts = flat_d_.back().n_parts = static_cast<std::uint32_t>(parts_.size() - first);
  }
  // links: all of them when a buffer moved (geometric growth: rarely), else the new ones
  if (colliders_.data() != shapes_at || parts_.data() != parts_at || part_flat_.data() != flats_at) {
    relink();
  } else {
    for (std::size_t j = first; j < parts_.size(); ++j) part_flat_[j].source = &parts_[j];
    link(colliders_.size() - 1);
  }
  ++revision_;
  return colliders_.size() - 1;
}

void CollisionWorld::assign(std::span<const Collider> colliders, std::string_view where) {
  // the same colliders as now, bit for bit (a static scene handed over each step):
  // already validated and flattened
  if (colliders.size() == colliders_.size() &&
      std::equal(colliders.begin(), colliders.end(), colliders_.begin(), same_bits) &&
      std::all_of(owners_.begin(), owners_.end(), [](std::uint32_t o) { return o == kNoOwner; }))
    return;
  clear();
  for (std::size_t i = 0; i < colliders.size(); ++i) {
    if (!colliders[i].ok()) colliders[i].validate(std::string(where) + "[" + std::to_string(i) + "]");
    push(colliders[i], kNoOwner);
  }
}

void CollisionWorld::set(std::size_t i, const Collider& c, std::string_view where) {
  if (i >= colliders_.size())
    throw Error(std::string(where) + ": collider " + std::to_string(i) + " does not exist (the world has " +
                std::to_string(colliders_.size()) + ")");
  if (!c.ok()) c.validate(where);
  // a compound's parts: in place when it has as many leaves as the old one, else appended
  // (the old ones stay unused until clear())
  const detail::FlatShape<double> old = flat_d_[i];
  colliders_[i] = c;
  flat_f_[i] = detail::flatten<float>(c);
  flat_d_[i] = detail::flatten<double>(c);
  if (c.shape.type == ShapeType::Compound) {
    const std::size_t first = parts_.size();
    add_parts(c.shape, c, c.begin, c.end);
    const std::size_t n = parts_.size() - first;
    std::size_t at = first;
    if (old.type == ShapeType::Compound && old.n_parts == n) {
      std::copy(parts_.begin() + static_cast<std::ptrdiff_t>(first), parts_.end(),
                parts_.begin() + old.first_part);
      std::copy(part_flat_.begin() + static_cast<std::ptrdiff_t>(first), part_flat_.end(),
                part_flat_.begin() + old.first_part);
      parts_.resize(first);
      part_flat_.resize(first);
      at = old.first_part;
    }
    flat_f_[i].first_part = flat_d_[i].first_part = static_cast<std::uint32_t>(at);
    flat_f_[i].n_parts = flat_d_[i].n_parts = static_cast<std::uint32_t>(n);
  }
  relink();
  ++revision_;
}

void CollisionWorld::draw(DebugDraw& draw, Color c, const DrawFlags& flags) const {
  for (const Collider& k : colliders_) k.draw(draw, c, flags);
}

}  // namespace pba
