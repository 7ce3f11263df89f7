// pba rigid scenes: the builders that the rigid-body samples, tests and benchmarks share
// (Box2D's shared/benchmarks.c idea), so all three run the same scene. Each adds bodies to
// a RigidBodySystem and returns their handles; the sizes, spacings and frictions are the
// ones of the peer harnesses the benchmarks compare against (shared/peers/).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "pba/rigid.h"

namespace pba::rigid_scenes {

/// A static ground plane y = 0 with friction `mu` and restitution `e`.
inline RigidBodyId ground(RigidBodySystem& s, double mu = 0.5, double e = 0) {
  return s.create(
      {.name = "ground",
       .type = BodyType::Static,
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

/// The largest mass ratio the soft step holds a heavy_on_light() column at, awake, at its
/// default settings (8 substeps, 120 Hz contacts): measured 2026-12-04, the column stands 60 s
/// at 420:1 and buckles within 20 s at 440:1. A soft contact's spring is as stiff as the light
/// box's mass makes it (m w^2), whatever it carries, so the column's resistance to leaning
/// (the springs' stiffness times the box's half width squared) is fixed while the heavy
/// box's overturning moment (its weight times its height) grows with the ratio: past the
/// bound the lean grows from rounding (about 5 times a second at 1000:1). The bound goes as
/// the springs' stiffness, w^2: at 240 Hz and 16 substeps it stands at 1600:1 and falls at
/// 1800:1. The criterion is 400:1; the Mass ratio sample offers up to this.
inline constexpr double kHeavyOnLightMaxRatio = 400;

/// A heavy box on light ones: a column of three 0.5 m cubes of 125 kg on the ground and on
/// them a 1 m cube `ratio` times heavier than each (density 1000 ratio / 8), all touching,
/// mu 0.5. Returns the column, bottom first, the heavy cube last.
inline std::vector<RigidBodyId> heavy_on_light(RigidBodySystem& s, double ratio) {
  ground(s);
  std::vector<RigidBodyId> out;
  for (int i = 0; i < 3; ++i) out.push_back(box(s, {0, 0.25 + 0.5 * i, 0}, Vec3(0.25)));
  out.push_back(box(s, {0, 2.0, 0}, Vec3(0.5), 0.5, 1000.0 * ratio / 8));
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

/// Jolt's pyramid as the peers' bullet_rigid_b.cpp replicates it: `levels` (15) levels of 2 m
/// cubes, level i a square of (levels - i)^2 cubes, touching side by side, its bottom 0.5 m
/// above the level below (level i's centres at 1 + 2.5 i m; odd levels shifted by one cube so
/// that each cube lands on four), mu 0.5; 1240 cubes at 15 levels. They fall into place:
/// at rest the top cube's centre is at jolt_pyramid_rest(levels). Returns the cubes, bottom
/// level first (the top cube last).
inline std::vector<RigidBodyId> jolt_pyramid(RigidBodySystem& s, int levels = 15, double mu = 0.5) {
  ground(s, mu);
  std::vector<RigidBodyId> out;
  for (int i = 0; i < levels; ++i) {
    const double shift = i % 2;
    for (int j = i / 2; j < levels - (i + 1) / 2; ++j)
      for (int k = i / 2; k < levels - (i + 1) / 2; ++k)
        out.push_back(box(s, {-levels + 2.0 * j + shift, 1 + 2.5 * i, -levels + 2.0 * k + shift}, Vec3(1), mu));
  }
  return out;
}

/// Where the top cube of jolt_pyramid(levels) rests once every level has landed (m).
inline Vec3 jolt_pyramid_rest(int levels = 15) {
  const int i = levels - 1;
  const double x = -levels + 2.0 * (i / 2) + i % 2;
  return {x, 1 + 2.0 * i, x};
}

/// The cards of a card house (m): length (the long side), width and thickness.
struct CardSize {
  double length = 1.0;     ///< along the card's local y (m)
  double width = 0.7;      ///< along its local z (m)
  double thickness = 0.02; ///< along its local x (m)
};

/// A card tower: `levels` - 1 storeys of two A-frames (two cards leaning `lean` rad from the
/// vertical, their top edges 1 mm apart) side by side in x with a flat card across their two
/// ridges, each storey standing on the flat card below it, crowned by one A-frame on the top
/// flat card (5 levels - 3 cards; 17 at 4 levels), on the ground plane; mu `mu` on every
/// card and the ground. The A-frames of a storey are centred 0.48 m apart (their feet
/// 9 cm apart, their outer feet within the flat card above), so each flat card rests on two
/// ridges and carries the two A-frames above straight over the two below. Flat cards start
/// 1 mm above the ridges. Needs lean small enough that two A-frames fit on a card: throws
/// Error otherwise. Returns the cards from the bottom storey up, the crown's two last.
/// (Each card rests on its inner bottom edge; its outer top edge is its highest point.)
inline std::vector<RigidBodyId> card_house(RigidBodySystem& s, int levels = 4, const CardSize& card = {},
                                           double lean = 0.1745, double mu = 0.7) {
  const double L = card.length, t = card.thickness, c = std::cos(lean), sn = std::sin(lean);
  const double gap = 0.001, spacing = 0.48 * L;
  // an A-frame's feet reach this far from its ridge (outer bottom corners)
  const double half_base = L * sn + t * c + 0.5 * gap;
  if (!(levels >= 1 && 2 * half_base < spacing && 0.5 * spacing + half_base < 0.5 * L))
    throw Error("card_house: levels " + std::to_string(levels) + " and lean " + std::to_string(lean) +
                " rad: need levels >= 1 and two A-frames side by side on a card");
  ground(s, mu);
  const Vec3 half{0.5 * t, 0.5 * L, 0.5 * card.width};
  std::vector<RigidBodyId> out;
  // an A-frame with its ridge above x at the height y: its cards rest on their inner bottom edges
  auto frame = [&](double x, double y) {
    const double dx = 0.5 * t * c + 0.5 * L * sn + 0.5 * gap, cy = y + 0.5 * t * sn + 0.5 * L * c;
    out.push_back(box(s, {x - dx, cy, 0}, half, mu, 1000, glm::angleAxis(-lean, Vec3(0, 0, 1))));
    out.push_back(box(s, {x + dx, cy, 0}, half, mu, 1000, glm::angleAxis(lean, Vec3(0, 0, 1))));
  };
  double y = 0;
  for (int k = 0; k + 1 < levels; ++k) {
    frame(-0.5 * spacing, y);
    frame(0.5 * spacing, y);
    // the flat card across the two ridges: the top faces of an A-frame's cards slope down
    // to the ridge, so it rests on their outer top edges, t sin(lean) above the ridge
    const double ridge = y + L * c + t * sn;
    out.push_back(box(s, {0, ridge + gap + 0.5 * t, 0}, half, mu, 1000, glm::angleAxis(0.5 * kPi, Vec3(0, 0, 1))));
    y = ridge + gap + t;
  }
  frame(0, y);
  return out;
}

/// A deterministic uniform generator for the scenes (xorshift64*, Vigna 2016), in [0, 1).
struct SceneRandom {
  std::uint64_t x;  ///< state, never 0
  /// The next number in [0, 1).
  double next() {
    x ^= x >> 12, x ^= x << 25, x ^= x >> 27;
    return static_cast<double>((x * 0x2545f4914f6cdd1dull) >> 11) * 0x1.0p-53;
  }
};

/// A rain of `n` mixed bodies over the ground plane (mu 0.5): alternately boxes (half extents
/// each uniform in 0.15 ... 0.4 m, random orientation) and spheres (radius 0.15 ... 0.4 m,
/// rolling resistance 0.1), density 1000 kg/m^3, restitution 0, released at rest in layers of
/// c x c columns 2 m apart (c = ceil(sqrt(n / 4)), 50 for 10,000 bodies: a 100 m square), the
/// layers 2 m apart from 10 m up, each body moved by up to 0.25 m along each axis (so no two
/// start closer than 1.5 m, more than the two largest bounding radii, 2 x 0.4 sqrt(3) m).
/// They land within two seconds, in heaps where a column's bodies meet, and fall asleep.
/// Returns the bodies; throws Error for n < 0.
inline std::vector<RigidBodyId> rain(RigidBodySystem& s, int n = 10000) {
  if (n < 0) throw Error("rain: n = " + std::to_string(n) + ": the number of bodies must be >= 0");
  ground(s, 0.5);
  const int c = static_cast<int>(std::ceil(std::sqrt(n / 4.0)));
  SceneRandom r{0x853c49e6748fea9bull};
  auto jitter = [&r] { return 0.5 * r.next() - 0.25; };
  std::vector<RigidBodyId> out;
  for (int i = 0; i < n; ++i) {
    const int layer = i / (c * c), column = i % (c * c);
    const Vec3 p{2.0 * (column % c - 0.5 * (c - 1)) + jitter(), 10 + 2.0 * layer + jitter(),
                 2.0 * (column / c - 0.5 * (c - 1)) + jitter()};
    if (i % 2 == 0) {
      const Vec3 h{0.15 + 0.25 * r.next(), 0.15 + 0.25 * r.next(), 0.15 + 0.25 * r.next()};
      const Quat q =
          glm::normalize(Quat(r.next() - 0.5, r.next() - 0.5, r.next() - 0.5, r.next() - 0.5) + Quat(0.05, 0, 0, 0));
      out.push_back(box(s, p, h, 0.5, 1000, q));
    } else {
      out.push_back(s.create({.pose = {p}, .shapes = {{.shape = ColliderShape::sphere(0.15 + 0.25 * r.next()),
                                                      .material = {.restitution = 0, .friction = 0.5},
                                                      .rolling_resistance = 0.1}}}));
    }
  }
  return out;
}

/// The peers' sine terrain (bullet_rigid_c.cpp, after Jolt's ConvexVsMesh): a grid of `n` x `n`
/// cells of `cell` m (2 n^2 triangles: 20,000 at n = 100), vertex (x, z) at height
/// `height` sin(50 x / n) cos(50 z / n) (x, z the grid indices), in the mesh frame whose
/// origin is the grid's corner.
inline std::shared_ptr<const TriangleMesh> sine_terrain_mesh(int n = 100, double cell = 3, double height = 5) {
  std::vector<Vec3> v(static_cast<std::size_t>((n + 1) * (n + 1)));
  for (int x = 0; x <= n; ++x)
    for (int z = 0; z <= n; ++z)
      v[static_cast<std::size_t>(z * (n + 1) + x)] = {
          cell * x, height * std::sin(x * 50.0 / n) * std::cos(z * 50.0 / n), cell * z};
  std::vector<std::array<std::uint32_t, 3>> t;
  t.reserve(static_cast<std::size_t>(2 * n * n));
  for (int x = 0; x < n; ++x)
    for (int z = 0; z < n; ++z) {
      const auto q = static_cast<std::uint32_t>((n + 1) * z + x), m = static_cast<std::uint32_t>(n + 1);
      t.push_back({q, q + m, q + 1});
      t.push_back({q + 1, q + m, q + m + 1});
    }
  return TriangleMesh::build(v, t, "sine terrain");
}

/// The peers' convex-versus-mesh scene (bullet_rigid_c.cpp): the sine terrain (static, its
/// middle at the origin, lifted by `height` so it spans 0 ... 2 height) and 21 x 4 x 21 = 1764
/// bodies 7.5 m apart over it, one kind per layer from 15 m up, 2 m apart: boxes of half
/// extents (0.5, 0.75, 1), spheres of radius 0.5, capsules of radius 0.5 and core 1.5 m along
/// y, and square pyramids (hulls of (0, 1, 0) and (+-1, 0, 0), (0, 0, +-1)); density 1000
/// (3000, 524, 1702 and 667 kg), mu 0.5 and restitution 0.6 on every shape. Returns the bodies.
inline std::vector<RigidBodyId> convex_vs_mesh(RigidBodySystem& s, int n = 100, double cell = 3, double height = 5) {
  const SurfaceMaterial m{.restitution = 0.6, .friction = 0.5};
  const double corner = -0.5 * n * cell;
  s.create({.name = "terrain", .type = BodyType::Static, .pose = {{corner, height, corner}},
            .shapes = {{.shape = ColliderShape::triangles(sine_terrain_mesh(n, cell, height)), .material = m}}});
  const Vec3 apex[5] = {{0, 1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
  const ColliderShape kinds[4] = {ColliderShape::box({0.5, 0.75, 1.0}), ColliderShape::sphere(0.5),
                                  ColliderShape::capsule(0.75, 0.5),
                                  ColliderShape::convex(ConvexHull::build(apex, "pyramid"))};
  std::vector<RigidBodyId> out;
  for (int x = -10; x <= 10; ++x)
    for (int y = 0; y < 4; ++y)
      for (int z = -10; z <= 10; ++z)
        out.push_back(
            s.create({.pose = {{7.5 * x, 15.0 + 2 * y, 7.5 * z}}, .shapes = {{.shape = kinds[y], .material = m}}}));
  return out;
}

/// `label` followed by the coefficient `c` rounded to two decimals ("e=0.56" for 5/9): the row's
/// and the ramp's body names, which the Solver lab writes over the bodies (cutting
/// std::to_string to four characters read 5/9 as 0.55).
inline std::string coefficient_name(const std::string& label, double c) {
  char digits[32];
  std::snprintf(digits, sizeof digits, "%.2f", c);
  return label + digits;
}

/// A row of `n` balls of radius 0.2 m dropped from 2 m, restitution 0 ... 1 left to right, on
/// a ground of restitution 0 (restitutions mix by the maximum unless the settings say otherwise,
/// so each contact has its ball's).
inline std::vector<RigidBodyId> restitution_row(RigidBodySystem& s, int n = 6) {
  ground(s, 0.0, 0.0);
  std::vector<RigidBodyId> out;
  for (int i = 0; i < n; ++i) {
    const double e = n > 1 ? static_cast<double>(i) / (n - 1) : 1.0;
    out.push_back(
        s.create({.name = coefficient_name("ball e=", e),
                  .pose = {{(i - 0.5 * (n - 1)) * 0.8, 2.2, 0}},
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
    const Vec3 p =
        0.25 * normal + Vec3(std::cos(angle), std::sin(angle), 0) * 3.0 + Vec3(0, 0, (i - 0.5 * (n - 1)) * 0.9);
    out.push_back(s.create({.name = coefficient_name("box mu=", mu),
                            .pose = {p, q},
                            .shapes = {{.shape = ColliderShape::box(Vec3(0.25)),
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
