// pba rigid scenes: the builders that the rigid-body samples, tests and benchmarks share
// (Box2D's shared/benchmarks.c idea), so all three run the same scene. Each adds bodies to
// a RigidBodySystem and returns their handles; the sizes, spacings and frictions are the
// ones of the peer harnesses the benchmarks compare against (shared/peers/).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "pba/rigid.h"

namespace pba::rigid_scenes {

/// A static ground plane y = 0 with friction `mu` and restitution `e`.
inline RigidBodyId ground(RigidBodySystem& s, double mu = 0.5, double e = 0) {
  return s.create({.name = "ground", .type = BodyType::Static,
                   .shapes = {{.shape = ColliderShape::plane({0, 1, 0}, 0), .material = {.restitution = e, .friction = mu}}}});
}

/// A dynamic box of half extents `h` at `p` (density 1000 kg/m^3 unless given).
inline RigidBodyId box(RigidBodySystem& s, const Vec3& p, const Vec3& h, double mu = 0.5, double density = 1000,
                       const Quat& q = Quat(1, 0, 0, 0)) {
  return s.create({.pose = {p, q}, .shapes = {{.shape = ColliderShape::box(h), .density = density,
                                               .material = {.restitution = 0, .friction = mu}}}});
}

/// A vertical stack of `n` cubes of half size `half`, touching, on the ground (mu 0.5, as
/// the peers' bullet_rigid_s.cpp). Returns the cubes, bottom first.
inline std::vector<RigidBodyId> vertical_stack(RigidBodySystem& s, int n, double half = 0.5, double mu = 0.5) {
  ground(s, mu);
  std::vector<RigidBodyId> out;
  for (int i = 0; i < n; ++i) out.push_back(box(s, {0, half + 2 * half * i, 0}, Vec3(half), mu));
  return out;
}

/// A square pyramid of unit cubes, `levels` high (level i is (levels - i)^2 cubes), touching,
/// on the ground, mu 0.6 (the peers' bullet_rigid_p.cpp: 20 levels, 2870 cubes).
inline std::vector<RigidBodyId> square_pyramid(RigidBodySystem& s, int levels, double mu = 0.6) {
  ground(s, mu);
  std::vector<RigidBodyId> out;
  for (int i = 0; i < levels; ++i) {
    const int k = levels - i;
    for (int a = 0; a < k; ++a)
      for (int c = 0; c < k; ++c) out.push_back(box(s, {a - 0.5 * (k - 1), 0.5 + i, c - 0.5 * (k - 1)}, Vec3(0.5), mu));
  }
  return out;
}

/// n^3 unit cubes dropped from a grid of spacing 1.5 m starting 2 m up, mu 0.5 (the peers'
/// bullet_rigid_fall.cpp with n = 10).
inline std::vector<RigidBodyId> falling_boxes(RigidBodySystem& s, int n = 10, double mu = 0.5) {
  ground(s, mu);
  std::vector<RigidBodyId> out;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int z = 0; z < n; ++z) out.push_back(box(s, {x * 1.5 - 7, 2.0 + y * 1.5, z * 1.5 - 7}, Vec3(0.5), mu));
  return out;
}

/// A row of `n` balls of radius 0.2 m dropped from 2 m, restitution 0 ... 1 left to right.
inline std::vector<RigidBodyId> restitution_row(RigidBodySystem& s, int n = 6) {
  ground(s, 0.0, 1.0);
  std::vector<RigidBodyId> out;
  for (int i = 0; i < n; ++i) {
    const double e = n > 1 ? static_cast<double>(i) / (n - 1) : 1.0;
    out.push_back(s.create({.name = "ball e=" + std::to_string(e).substr(0, 4), .pose = {{(i - 0.5 * (n - 1)) * 0.8, 2.2, 0}},
                            .shapes = {{.shape = ColliderShape::sphere(0.2), .material = {.restitution = e, .friction = 0}}}}));
  }
  return out;
}

/// Boxes of friction mu = 0.1, 0.3, ..., on a plane tilted by `angle` (rad) about z: those with
/// mu > tan(angle) stick, the others slide down at g (sin - mu cos).
inline std::vector<RigidBodyId> friction_ramp(RigidBodySystem& s, double angle = 0.3805, int n = 5) {
  const Vec3 normal{-std::sin(angle), std::cos(angle), 0};
  s.create({.name = "ramp", .type = BodyType::Static,
            .shapes = {{.shape = ColliderShape::plane(normal, 0), .material = {.restitution = 0, .friction = 1}}}});
  const Quat q = glm::angleAxis(angle, Vec3(0, 0, 1));
  std::vector<RigidBodyId> out;
  for (int i = 0; i < n; ++i) {
    const double mu = 0.1 + 0.2 * i;
    // along the slope's upper part, side by side in z; friction mixes as sqrt(1 * mu^2) = mu
    const Vec3 p = 0.25 * normal + Vec3(std::cos(angle), std::sin(angle), 0) * 3.0 + Vec3(0, 0, (i - 0.5 * (n - 1)) * 0.9);
    out.push_back(s.create({.pose = {p, q}, .shapes = {{.shape = ColliderShape::box(Vec3(0.25)),
                                                         .material = {.restitution = 0, .friction = mu * mu}}}}));
  }
  return out;
}

/// A closed box of six static walls of thickness `wall` (m) around the cube |x|, |y|, |z| < `inner`
/// (m), with `n` bodies inside (alternately boxes of half size 0.25 m and spheres of radius
/// 0.25 m, mu 0.5, e 0.5) on a grid of spacing 1.1 m, each moving at `speed` (m/s) in a
/// direction of a fixed pseudo-random sequence (the tunnelling test: none may get out).
/// Returns the bodies inside. Throws Error when they do not fit the grid.
inline std::vector<RigidBodyId> closed_box(RigidBodySystem& s, int n, double speed, double inner = 10,
                                           double wall = 0.2) {
  const SurfaceMaterial m{.restitution = 0.5, .friction = 0.5};
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2) {
      Vec3 p(0), h(inner + wall);
      p[axis] = side * (inner + 0.5 * wall);
      h[axis] = 0.5 * wall;
      s.create({.name = "wall", .type = BodyType::Static, .pose = {p},
                .shapes = {{.shape = ColliderShape::box(h), .material = m}}});
    }
  const int per = static_cast<int>(std::floor((2 * inner - 1.1) / 1.1)) + 1;
  if (n > per * per * per) throw Error("closed_box: " + std::to_string(n) + " bodies do not fit a grid of " +
                                       std::to_string(per) + "^3 in a box of half size " + std::to_string(inner));
  std::vector<RigidBodyId> out;
  std::uint64_t x = 0x9e3779b97f4a7c15ull;
  auto uniform = [&x] {  // xorshift64*, in [-1, 1)
    x ^= x >> 12, x ^= x << 25, x ^= x >> 27;
    return static_cast<double>((x * 0x2545f4914f6cdd1dull) >> 11) * 0x1.0p-52 - 1;
  };
  for (int i = 0; i < n; ++i) {
    const Vec3 p{-inner + 0.55 + 1.1 * (i % per), -inner + 0.55 + 1.1 * ((i / per) % per),
                 -inner + 0.55 + 1.1 * (i / (per * per))};
    Vec3 d;
    do d = {uniform(), uniform(), uniform()};
    while (glm::dot(d, d) > 1 || glm::dot(d, d) < 1e-4);
    const ColliderShape shape = i % 2 ? ColliderShape::sphere(0.25) : ColliderShape::box(Vec3(0.25));
    out.push_back(s.create({.pose = {p}, .linear_velocity = speed * glm::normalize(d),
                            .shapes = {{.shape = shape, .material = m}}}));
  }
  return out;
}

}  // namespace pba::rigid_scenes
