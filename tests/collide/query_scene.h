// Test helper: random query scenes (every shape type at random poses, random owners and
// layers) and brute-force references for the world queries: a loop over every collider with
// the filter rule written out again, and meshes by every triangle instead of their BVH.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "pba/collide/narrow_phase.h"
#include "pba/collide/query.h"
#include "shape_checks.h"
#include "shape_gen.h"

namespace pba::test_support {

/// Colliders with owners and filters, and the query world over them.
struct QueryScene {
  std::vector<Collider> colliders;
  std::vector<std::uint32_t> owners;
  std::vector<CollisionFilter> filters;
  QueryWorld world;
  double side = 0;  ///< the colliders' centres are in [0, side]^3 (m)
};

/// A hull from random points on an ellipsoid of semi-axes up to `size`.
inline std::shared_ptr<const ConvexHull> random_hull(std::mt19937_64& rng, double size) {
  std::uniform_real_distribution<double> u(0.3, 1.0);
  const Vec3 axes = size * Vec3(u(rng), u(rng), u(rng));
  std::vector<Vec3> pts;
  for (int i = 0; i < 24; ++i) pts.push_back(axes * random_unit(rng));
  return ConvexHull::build(pts);
}

/// `n` colliders of every type (mostly spheres, boxes and capsules; some hulls, meshes,
/// compounds; two planes) in a cube of side `side`, with owners in [0, 20) and layers in
/// the low 3 bits.
inline QueryScene make_query_scene(int n, double side, std::uint64_t seed) {
  QueryScene s;
  s.side = side;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> pos(0, side), size(0.2, 1.0), u01(0, 1);
  const IcoSphere ico = icosphere(1, 1.0);
  const auto mesh = TriangleMesh::build(ico.vertices, ico.triangles);
  const IcoSphere ground = terrain(8, side, [](double x, double z) { return 0.3 * std::sin(x) * std::cos(z); });
  const auto terrain_mesh = TriangleMesh::build(ground.vertices, ground.triangles);
  const auto compound = CompoundShape::build(
      {{ColliderShape::box(Vec3(0.6, 0.1, 0.4)), Pose{Vec3(0, 0.5, 0), Quat(1, 0, 0, 0)}},
       {ColliderShape::capsule(0.25, 0.1), Pose{Vec3(0.4, 0, 0.3), Quat(1, 0, 0, 0)}},
       {ColliderShape::sphere(0.2), Pose{Vec3(-0.4, 0, -0.3), Quat(1, 0, 0, 0)}}});
  for (int i = 0; i < n; ++i) {
    Collider c;
    const double k = u01(rng);
    if (i == 0) {
      c.shape = ColliderShape::plane(Vec3(0, 1, 0), -0.5);
    } else if (i == 1) {
      c.shape = ColliderShape::plane(Vec3(0.3, -1, 0.2), -side - 0.5);  // a tilted ceiling, normal down
    } else if (i == 2) {
      c.shape = ColliderShape::triangles(terrain_mesh);
    } else if (k < 0.3) {
      c.shape = ColliderShape::sphere(size(rng));
    } else if (k < 0.55) {
      c.shape = ColliderShape::box(Vec3(size(rng), size(rng), size(rng)));
    } else if (k < 0.8) {
      c.shape = ColliderShape::capsule(size(rng), 0.5 * size(rng));
    } else if (k < 0.9) {
      c.shape = ColliderShape::convex(random_hull(rng, 1.0));
    } else if (k < 0.95) {
      c.shape = ColliderShape::triangles(mesh);
    } else {
      c.shape.type = ShapeType::Compound;
      c.shape.compound = compound;
    }
    const Pose p{i == 2 ? Vec3(0.5 * side, -0.2, 0.5 * side) : Vec3(pos(rng), pos(rng), pos(rng)),
                 i <= 2 ? Quat(1, 0, 0, 0) : random_rotation(rng)};
    c.begin = c.end = p;
    s.colliders.push_back(c);
    s.owners.push_back(static_cast<std::uint32_t>(rng() % 20));
    const std::uint64_t layer = 1ull << (rng() % 3);
    s.filters.push_back({layer, (rng() % 4 == 0) ? (~0ull ^ 2ull) : ~0ull, 0});
  }
  s.world.build(s.colliders, s.owners, s.filters);
  return s;
}

/// The filter rule of QueryFilter, written out again.
inline bool brute_accepts(const QueryScene& s, const QueryFilter& f, std::size_t i) {
  const CollisionFilter& c = s.filters[i];
  if (!(f.layer & c.mask) || !(c.layer & f.mask)) return false;
  if (f.ignore_owner != CollisionWorld::kNoOwner && s.owners[i] == f.ignore_owner) return false;
  return !f.accept.fn || f.accept.fn(f.accept.context, static_cast<std::uint32_t>(i), s.owners[i]);
}

/// Calls f(part proxy) for every convex part of a non-plane shape: itself, a compound's
/// children, every triangle of a mesh (no BVH). `tri` holds the current triangle.
template <class F>
void brute_parts(const ColliderShape& s, const Pose& p, F&& f) {
  if (s.type == ShapeType::Compound) {
    for (const CompoundChild& c : s.compound->children) brute_parts(c.shape, compose(p, c.pose), f);
  } else if (s.type == ShapeType::Mesh) {
    for (const auto& t : s.mesh->triangles()) {
      const Vec3 tri[3] = {s.mesh->vertices()[t[0]], s.mesh->vertices()[t[1]], s.mesh->vertices()[t[2]]};
      ConvexProxy q;
      q.type = ShapeType::Mesh;
      q.triangle = tri;
      q.pose = p;
      f(q);
    }
  } else {
    f(ConvexProxy::of(s, p));
  }
}

/// Signed gap of the convex `a` above a plane shape (negative: below), and its lowest point.
inline double plane_gap(const ConvexProxy& a, const ColliderShape& plane, const Pose& p, Vec3* lowest = nullptr) {
  const Vec3 n = p.rotation * glm::normalize(plane.normal);
  const double offset = plane.offset / glm::length(plane.normal) + glm::dot(n, p.position);
  const Vec3 low = a.support(-n) - a.radius * n;
  if (lowest) *lowest = low;
  return glm::dot(n, low) - offset;
}

/// Distance between the convex `a` and any shape, by brute force over its parts.
inline double brute_distance(const ConvexProxy& a, const ColliderShape& s, const Pose& p) {
  if (s.type == ShapeType::Plane) return std::max(0.0, plane_gap(a, s, p));
  double best = 1e300;
  brute_parts(s, p, [&](const ConvexProxy& b) { best = std::min(best, gjk_distance(a, b).distance); });
  return best;
}

}  // namespace pba::test_support
