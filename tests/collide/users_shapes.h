// Shapes for the tests of the collide module's users (particles, ropes, cloth, jelly)
// against hulls, meshes and compounds.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "pba/collide.h"

namespace pba::test_users {

/// A truncated square pyramid: base (+-1, -0.5, +-1), top (+-0.5, 0, +-0.5), so its top
/// face is y = 0; with a duplicate and a coplanar point for the hull builder.
inline std::shared_ptr<const ConvexHull> frustum_hull() {
  std::vector<Vec3> p;
  for (double sx : {-1.0, 1.0})
    for (double sz : {-1.0, 1.0}) {
      p.push_back({sx, -0.5, sz});
      p.push_back({0.5 * sx, 0.0, 0.5 * sz});
    }
  p.push_back({0.5, 0.0, 0.5});  // duplicate
  p.push_back({0.1, 0.0, 0.2});  // on the top face
  return ConvexHull::build(p, "frustum");
}

/// A regular octahedron of circumradius s about the origin (sharp corners).
inline std::shared_ptr<const ConvexHull> octahedron_hull(double s) {
  const std::vector<Vec3> p = {{s, 0, 0}, {-s, 0, 0}, {0, s, 0}, {0, -s, 0}, {0, 0, s}, {0, 0, -s}};
  return ConvexHull::build(p, "octahedron");
}

/// A flat grid of n x n square cells of side `cell` on y = 0, centred on the origin, two
/// triangles a cell, wound so their normals are +y.
inline std::shared_ptr<const TriangleMesh> grid_mesh(int n, double cell) {
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  const double x0 = -0.5 * n * cell;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) v.push_back({x0 + i * cell, 0, x0 + j * cell});
  auto at = [n](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      // (b - a) x (c - a) = +z x +x = +y
      t.push_back({at(i, j), at(i, j + 1), at(i + 1, j)});
      t.push_back({at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)});
    }
  return TriangleMesh::build(v, t, "grid");
}

/// A bowl: a square grid of n x n cells over [-w, w]^2 at height y = k (x^2 + z^2).
inline std::shared_ptr<const TriangleMesh> bowl_mesh(int n, double w, double k) {
  std::vector<Vec3> v;
  std::vector<std::array<std::uint32_t, 3>> t;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double x = -w + 2 * w * i / n, z = -w + 2 * w * j / n;
      v.push_back({x, k * (x * x + z * z), z});
    }
  auto at = [n](int i, int j) { return static_cast<std::uint32_t>(i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      t.push_back({at(i, j), at(i, j + 1), at(i + 1, j)});
      t.push_back({at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)});
    }
  return TriangleMesh::build(v, t, "bowl");
}

/// One square sheet in the plane x = 0, |y|, |z| <= 1 (two triangles, no thickness).
inline std::shared_ptr<const TriangleMesh> sheet_mesh() {
  const std::vector<Vec3> v = {{0, -1, -1}, {0, 1, -1}, {0, 1, 1}, {0, -1, 1}};
  const std::vector<std::array<std::uint32_t, 3>> t = {{0, 1, 2}, {0, 2, 3}};
  return TriangleMesh::build(v, t, "sheet");
}

/// A table: a 2 x 0.5 x 2 box top (its top face at y = 0 of the compound frame) over a
/// capsule leg and a hull foot, to exercise every child type and a nested compound.
inline std::shared_ptr<const CompoundShape> table_compound() {
  std::vector<CompoundChild> inner = {{ColliderShape::convex(octahedron_hull(0.3)), Pose{{0, -1.2, 0}}}};
  ColliderShape foot;
  foot.type = ShapeType::Compound;
  foot.compound = CompoundShape::build(inner, "foot");
  std::vector<CompoundChild> ch = {{ColliderShape::box({1, 0.25, 1}), Pose{{0, -0.25, 0}}},
                                   {ColliderShape::capsule(0.3, 0.1), Pose{{0, -0.8, 0}}},
                                   {foot, Pose{}}};
  return CompoundShape::build(ch, "table");
}

/// A static collider of shape s at (position, rotation).
inline Collider place(const ColliderShape& s, const Vec3& position, SurfaceMaterial m = {},
                      const Quat& rotation = Quat(1, 0, 0, 0)) {
  Collider c;
  c.shape = s;
  c.material = m;
  c.begin = c.end = Pose{position, rotation};
  return c;
}

/// A compound shape value.
inline ColliderShape compound_shape(std::shared_ptr<const CompoundShape> c) {
  ColliderShape s;
  s.type = ShapeType::Compound;
  s.compound = std::move(c);
  return s;
}

}  // namespace pba::test_users
