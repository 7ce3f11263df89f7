// The contact solver's layout: the constraint graph's colours (no two manifolds of a colour
// share a dynamic body; the bands run bottom up) and its SIMD paths (every path gives the
// same bits, under every solver).
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "pba/rigid.h"
#include "pba/rigid_scenes.h"

#include "error_of.h"

using pba::BodyType;
using pba::ColliderShape;
using pba::RigidBodySystem;
using pba::RigidSimd;
using pba::RigidSolverType;
using pba::Vec3;
using pba::test_support::error_of;

namespace {

const Vec3 kGravity{0, -9.81, 0};

// A scene that exercises every part of the solver: a pyramid (coloured blocks, full and
// partial), bouncing balls (restitution), a ball with rolling resistance (coloured; TGS puts
// it, and everything, in the overflow), a kinematic paddle through the pyramid's side, a
// spinning box, a spinning cube and nine spinning capsules (the splitting, the round and the axisymmetric bodies' exact turns, each also with
// the library's sines beyond pi/8 a half step), forces and impulses, and a sleeping group woken
// later.
std::vector<pba::RigidBodyId> mixed_scene(RigidBodySystem& s) {
  auto out = pba::rigid_scenes::square_pyramid(s, 5);
  for (int i = 0; i < 4; ++i)
    out.push_back(s.create({.pose = {{4.0 + i, 1.0 + 0.5 * i, 0}},
                            .shapes = {{.shape = ColliderShape::sphere(0.3), .material = {.restitution = 0.25 * i, .friction = 0.4}}}}));
  out.push_back(s.create({.pose = {{-4, 0.3, 1}}, .linear_velocity = {2, 0, 0},
                          .shapes = {{.shape = ColliderShape::sphere(0.3), .rolling_resistance = 0.2}}}));
  s.create({.type = BodyType::Kinematic, .pose = {{-3, 0.5, -3}}, .linear_velocity = {1, 0, 0},
            .angular_velocity = {0, 0.5, 0}, .shapes = {{.shape = ColliderShape::box({0.2, 0.4, 1})}}});
  out.push_back(s.create({.pose = {{0, 9, 4}}, .angular_velocity = {0, 300, 40},
                          .shapes = {{.shape = ColliderShape::box({0.3, 0.2, 0.5})}}}));
  s.create({.pose = {{4, 12, 4}}, .angular_velocity = {-500, 200, 300}, .shapes = {{.shape = ColliderShape::box(Vec3(0.2))}}});
  for (int i = 0; i < 9; ++i)
    s.create({.pose = {{-8, 1.0 + 0.5 * i, 2.0 * i}}, .angular_velocity = {40.0 * i * i, 3, -20},
              .shapes = {{.shape = ColliderShape::capsule(0.3, 0.2)}}});
  out.push_back(s.create({.pose = {{6, 0.25, 4}}, .shapes = {{.shape = ColliderShape::box(Vec3(0.25))}}}));
  return out;
}

std::uint64_t run_mixed(RigidSolverType solver, RigidSimd path, int steps) {
  RigidBodySystem s({.contacts = {.solver = solver}});
  s.set_simd(path);
  const auto bodies = mixed_scene(s);
  for (int i = 0; i < steps; ++i) {
    if (i == 30) s.apply_impulse(bodies[3], {5, 0, 0}, s.center_of_mass(bodies[3]) + Vec3(0, 0.3, 0));
    if (i % 7 == 0) s.apply_force(bodies[10], {0, 20, 3}, s.center_of_mass(bodies[10]) + Vec3(0.2, 0, 0));
    if (i == 90) s.wake(bodies.back());  // asleep by then
    s.step(1.0 / 60, kGravity);
  }
  return s.hash();
}

// the paths this CPU runs
std::vector<RigidSimd> paths() {
  std::vector<RigidSimd> out;
  for (const RigidSimd p : {RigidSimd::Scalar, RigidSimd::Avx2, RigidSimd::Avx512}) {
    RigidBodySystem s;
    if (error_of([&] { s.set_simd(p); }).empty()) out.push_back(p);
  }
  return out;
}

}  // namespace

// The scalar path, AVX2 and AVX-512 do the same arithmetic in every lane: the same bits after
// 150 steps of the mixed scene, under each solver (XPBD's passes are scalar, but its free
// motion runs on the paths too).
TEST(RigidSimd, EveryPathGivesTheSameBits) {
  const std::vector<RigidSimd> all = paths();
  ASSERT_FALSE(all.empty());
  EXPECT_EQ(all.front(), RigidSimd::Scalar);
  for (const RigidSolverType solver : pba::kRigidSolvers) {
    const std::uint64_t scalar = run_mixed(solver, RigidSimd::Scalar, 150);
    for (const RigidSimd p : all)
      EXPECT_EQ(run_mixed(solver, p, 150), scalar) << to_string(solver) << " on " << to_string(p);
  }
}

// The same with a thin static slab (1 cm half thickness) in the scene and a larger speculative
// distance: the broad phase then grows each body's boxes by its own share of the reach
// (contact_pairs.cpp, update_proxies), and the AVX2 fours take only the bodies whose share is
// the setting whatever their turn (the pyramid's 0.5 m cubes; not the 5 cm ones dropped on the
// slab, nor the slab): the same bits and the same pairs on every path.
TEST(RigidSimd, EveryPathGivesTheSameBitsWhereBodiesTakeTheirShareOfTheReach) {
  auto run = [](RigidSimd path) {
    RigidBodySystem s({.contacts = {.speculative_distance = 0.2}});
    s.set_simd(path);
    mixed_scene(s);
    s.create({.type = BodyType::Static, .pose = {{0, 3, -6}}, .shapes = {{.shape = ColliderShape::box({3, 0.01, 3})}}});
    for (int i = 0; i < 12; ++i)
      s.create({.pose = {{-2.0 + 0.4 * i, 3.5 + 0.1 * i, -6.0 + 0.2 * (i % 5)}}, .angular_velocity = {i, 2, -i},
                .shapes = {{.shape = i % 2 ? ColliderShape::sphere(0.05) : ColliderShape::box(Vec3(0.05))}}});
    std::vector<std::size_t> pairs;
    for (int i = 0; i < 120; ++i) s.step(1.0 / 60, kGravity), pairs.push_back(s.profile().shape_pairs);
    return std::pair{s.hash(), pairs};
  };
  const auto scalar = run(RigidSimd::Scalar);
  for (const RigidSimd p : paths()) {
    const auto other = run(p);
    EXPECT_EQ(other.first, scalar.first) << to_string(p);
    EXPECT_EQ(other.second, scalar.second) << to_string(p);
  }
}

// A rain of balls thrown sideways onto the ground and onto each other, every third one with
// rolling resistance: colours of more than 8 one-point manifolds (the AVX2 path solves such a
// block's two halves together), on the ground (side a not written) and between balls (both
// sides), landing while sliding (the rounds, in one half or both) and rolling. The same bits on
// every path, under each solver; `widest` is the most one-point manifolds a colour held.
namespace {
std::uint64_t run_balls(RigidSolverType solver, RigidSimd path, int& widest) {
  RigidBodySystem s({.contacts = {.solver = solver}});
  s.set_simd(path);
  pba::rigid_scenes::ground(s, 0.6);
  for (int i = 0; i < 72; ++i)
    s.create({.pose = {{0.7 * (i % 9), 0.35 + 0.7 * (i / 9) + 0.01 * (i % 5), 0.7 * ((i / 3) % 3)}},
              .linear_velocity = {1.5 - 0.4 * (i % 7), -0.5 * (i % 4), 0.3 * (i % 3)},
              .shapes = {{.shape = ColliderShape::sphere(0.3), .rolling_resistance = i % 3 == 0 ? 0.1 : 0.0}}});
  widest = 0;
  for (int step = 0; step < 120; ++step) {
    s.step(1.0 / 60, kGravity);
    std::map<int, int> ones;
    for (std::size_t k = 0; k < s.manifold_count(); ++k) {
      const pba::RigidManifoldInfo m = s.manifold(k);
      if (m.color >= 0 && m.points == 1) widest = std::max(widest, ++ones[m.color]);
    }
  }
  return s.hash();
}
}  // namespace

TEST(RigidSimd, BlocksOfOnePointManifoldsGiveTheSameBitsOnEveryPath) {
  for (const RigidSolverType solver : pba::kRigidSolvers) {
    int widest = 0;
    const std::uint64_t scalar = run_balls(solver, RigidSimd::Scalar, widest);
    if (solver == RigidSolverType::SoftStep) {
      EXPECT_GT(widest, 8);
    }
    for (const RigidSimd p : paths())
      EXPECT_EQ(run_balls(solver, p, widest), scalar) << to_string(solver) << " on " << to_string(p);
  }
}

// Forty 1 m boxes dropped flat side by side (from 1.5 m, thrown down at 0, 2 or 5 m/s), each
// in its own lane along x, two of every three moving sideways at 1 to 8 m/s (mu = 0.5, e = 0):
// they land together, so the ground's colour holds forty four-point manifolds (blocks of 16,
// whose halves the AVX2 path solves together, and one of 8) of which most land while sliding in
// the same substep (the rounds; the AVX2 path's such lanes wait for them to the colour's end,
// eight at a time, beside the lanes that land straight; a ball resting apart makes every
// step pass a colour a call, where they wait). The same bits on every path, under
// each solver; and each box, alone on its part of the ground, stops where Coulomb's law puts it
// (the bounds and their reasons: RigidFriction.ABoxLandingFlatWhileSlidingStopsWhereCoulombSays)
namespace {
struct Landing {
  std::uint64_t hash = 0;
  int widest = 0;                 // the most four-point manifolds a colour held
  std::vector<double> travel;     // each box's travel along its direction from its touch (m)
  std::vector<double> height;     // each box's centre's height at the end (m)
};
constexpr int kLandingBoxes = 40;
constexpr double kLandingMu = 0.5, kLandingDrop = 2.0;
double landing_vx(int i) { return i % 3 == 0 ? 0.0 : 1.0 + 7.0 * (i % 8) / 7.0; }
double landing_vy(int i) { return 2.5 * (i % 3 == 1 ? 0 : i % 3 == 2 ? 1 : 2); }
double landing_sign(int i) { return i % 2 ? -1.0 : 1.0; }
double touch_time(double vy) { return (-vy + std::sqrt(vy * vy + 2 * 9.81 * (kLandingDrop - 0.5))) / 9.81; }

Landing run_landing(RigidSolverType solver, RigidSimd path) {
  RigidBodySystem s({.contacts = {.solver = solver}});
  s.set_simd(path);
  pba::rigid_scenes::ground(s, kLandingMu);
  std::vector<pba::RigidBodyId> boxes;
  for (int i = 0; i < kLandingBoxes; ++i)
    boxes.push_back(s.create({.pose = {{0, kLandingDrop, 3.0 * i}},
                              .linear_velocity = {landing_sign(i) * landing_vx(i), -landing_vy(i), 0},
                              .shapes = {{.shape = ColliderShape::box(Vec3(0.5)), .material = {.restitution = 0, .friction = kLandingMu}}}}));
  // a ball resting on the ground apart: its one-point manifold has the solver pass each colour
  // in its own call every step (without it the forward steps passed every colour in one call,
  // where no lane waits, and only the backward steps deferred)
  s.create({.pose = {{0, 0.5, -10}}, .shapes = {{.shape = ColliderShape::sphere(0.5)}}});
  Landing out;
  for (int step = 0; step < 180; ++step) {
    s.step(1.0 / 60, kGravity);
    std::map<int, int> fours;
    for (std::size_t k = 0; k < s.manifold_count(); ++k) {
      const pba::RigidManifoldInfo m = s.manifold(k);
      if (m.color >= 0 && m.points > 1) out.widest = std::max(out.widest, ++fours[m.color]);
    }
  }
  for (int i = 0; i < kLandingBoxes; ++i) {
    const Vec3 p = s.center_of_mass(boxes[i]);
    out.travel.push_back(landing_sign(i) * p.x - landing_vx(i) * touch_time(landing_vy(i)));
    out.height.push_back(p.y);
  }
  out.hash = s.hash();
  return out;
}
}  // namespace

TEST(RigidSimd, BoxesLandingWhileSlidingTogetherGiveTheSameBitsOnEveryPath) {
  const double g = 9.81, dt = 1.0 / 60;
  for (const RigidSolverType solver : pba::kRigidSolvers) {
    const Landing scalar = run_landing(solver, RigidSimd::Scalar);
    if (solver == RigidSolverType::SoftStep) {
      EXPECT_GT(scalar.widest, 32);
    }
    const RigidBodySystem settings({.contacts = {.solver = solver}});
    const double h = solver == RigidSolverType::SequentialImpulse ? dt : dt / settings.settings().substeps;
    for (int i = 0; i < kLandingBoxes; ++i) {
      const double vx = landing_vx(i), land = landing_vy(i) + g * touch_time(landing_vy(i));
      const double slide = std::pow(std::max(vx - kLandingMu * land, 0.0), 2) / (2 * kLandingMu * g);
      const double least = std::pow(std::max(vx - kLandingMu * (land + g * dt), 0.0), 2) / (2 * kLandingMu * g) - vx * h / 2;
      if (vx > 0) {  // (the straight landings are the lanes that do not slide: only on their faces below)
        EXPECT_LE(scalar.travel[i], slide + 1.5 * vx * dt) << to_string(solver) << " box " << i;
        EXPECT_GE(scalar.travel[i], least - 1.5 * vx * dt) << to_string(solver) << " box " << i;
      }
      EXPECT_NEAR(scalar.height[i], 0.5, 0.01) << to_string(solver) << " box " << i;  // on its face
    }
    for (const RigidSimd p : paths()) {
      const Landing other = run_landing(solver, p);
      EXPECT_EQ(other.hash, scalar.hash) << to_string(solver) << " on " << to_string(p);
      EXPECT_EQ(other.widest, scalar.widest) << to_string(solver) << " on " << to_string(p);
    }
  }
}

// The approach speeds before the solve (prepare's, a lane type at a time) on every path: a
// unit cube rising at 3 m/s and turning at 2 rad/s about x under a ceiling, and a ball rising at
// 3 m/s, each a centimetre below it. Gravity and the passes' impulses only slow their closing
// in the step, so the step's fastest closing is at its start: the ball's 3 m/s, the cube's
// 3 + 2 x 0.5 m/s at the corners its turn lifts (its top face's corners, 0.5 m from the axis).
// Each to the approach speed's float resolution (2^-21 m/s at 4), the same bits on every path.
TEST(RigidSimd, ApproachSpeedsBeforeTheSolveAreTheClosingSpeedsOnEveryPath) {
  std::vector<double> scalar;
  for (const RigidSimd p : paths()) {
    RigidBodySystem s;
    s.set_simd(p);
    s.create({.type = BodyType::Static, .pose = {{0, 2.5, 0}}, .shapes = {{.shape = ColliderShape::box({5, 0.5, 5})}}});
    const auto cube = s.create({.pose = {{0, 1.49, 0}}, .linear_velocity = {0, 3, 0}, .angular_velocity = {2, 0, 0},
                                .shapes = {{.shape = ColliderShape::box(Vec3(0.5))}}});
    const auto ball = s.create({.pose = {{3, 1.69, 0}}, .linear_velocity = {0, 3, 0},
                                .shapes = {{.shape = ColliderShape::sphere(0.3)}}});
    s.step(1.0 / 60, kGravity);
    std::vector<double> speeds;
    int seen = 0;
    for (std::size_t k = 0; k < s.manifold_count(); ++k) {
      const pba::RigidManifoldInfo m = s.manifold(k);
      speeds.push_back(m.approach_speed);
      if (m.a == cube || m.b == cube) {
        EXPECT_EQ(m.points, 4) << to_string(p);
        EXPECT_NEAR(m.approach_speed, 4.0, 0x1p-21) << "the cube on " << to_string(p);
        ++seen;
      } else if (m.a == ball || m.b == ball) {
        EXPECT_NEAR(m.approach_speed, 3.0, 0x1p-22) << "the ball on " << to_string(p);
        ++seen;
      }
    }
    EXPECT_EQ(seen, 2) << to_string(p);
    if (scalar.empty()) scalar = speeds;
    EXPECT_EQ(speeds, scalar) << to_string(p);
  }
}

// The approach speeds of the lanes whose pair has no restitution are made when asked for, from
// the velocities the step started from and the biased passes' running minimum; those of a
// block with a restitution lane by prepare, as before. Both give the same numbers: nine cubes
// dropped turning onto the ground and onto each other (four-point lanes, the ground's and the
// cubes' between them) and three balls (one-point lanes), once without restitution and once
// with 0.5 but a threshold no approach reaches (so no lane bounces and the bodies' bits are
// the same), every manifold's approach speed equal to the bit at every step, on every path,
// under each solver that makes rows (the soft step, sequential impulses, TGS). Between two
// steps a set_velocity changes none of them (they are of the step that was), nor does a
// destroy change those of the manifolds it leaves: read again after each, the same bits.
TEST(RigidSimd, ApproachSpeedsMadeWhenAskedForAreThoseOfPrepare) {
  for (const RigidSolverType solver :
       {RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse, RigidSolverType::Tgs})
    for (const RigidSimd p : paths()) {
      const std::string what = std::string(to_string(solver)) + " " + std::string(to_string(p));
      RigidBodySystem plain({.contacts = {.solver = solver}}), bouncy({.contacts = {.solver = solver}});
      std::vector<pba::RigidBodyId> ids[2];
      for (RigidBodySystem* s : {&plain, &bouncy}) {
        std::vector<pba::RigidBodyId>& made = ids[s == &bouncy];
        s->set_simd(p);
        const double e = s == &bouncy ? 0.5 : 0.0;
        if (s == &bouncy) s->settings().restitution_threshold = 1e6;
        s->create({.type = BodyType::Static, .pose = {{0, -0.5, 0}}, .shapes = {{.shape = ColliderShape::box({20, 0.5, 20})}}});
        for (int i = 0; i < 9; ++i)
          made.push_back(s->create({.pose = {{0.3 * (i % 3), 0.6 + 1.1 * i, 0.2 * (i / 3)}, glm::angleAxis(0.1 * i, glm::normalize(Vec3(1, 2, 3)))},
                     .angular_velocity = {0.5 * (i % 2), 0, 0.3},
                     .shapes = {{.shape = ColliderShape::box(Vec3(0.5)), .material = {.restitution = e, .friction = 0.6}}}}));
        for (int i = 0; i < 3; ++i)
          made.push_back(s->create({.pose = {{4 + 1.5 * i, 0.5 + 0.7 * i, 0}}, .linear_velocity = {0.5, 0, 0},
                     .shapes = {{.shape = ColliderShape::sphere(0.3), .material = {.restitution = e, .friction = 0.6}}}}));
      }
      // every manifold's approach speed and largest normal impulse, plain's and bouncy's the same bits
      auto speeds = [&](const std::string& when) {
        EXPECT_EQ(plain.manifold_count(), bouncy.manifold_count()) << what << " " << when;
        std::vector<std::uint64_t> bits;
        for (std::size_t k = 0; k < std::min(plain.manifold_count(), bouncy.manifold_count()); ++k) {
          const pba::RigidManifoldInfo a = plain.manifold(k), b = bouncy.manifold(k);
          EXPECT_EQ(std::bit_cast<std::uint64_t>(a.approach_speed), std::bit_cast<std::uint64_t>(b.approach_speed))
              << what << " " << when << " manifold " << k;
          EXPECT_EQ(a.max_normal_impulse, b.max_normal_impulse) << what << " " << when;
          bits.push_back(std::bit_cast<std::uint64_t>(a.approach_speed));
        }
        return bits;
      };
      int compared = 0;
      for (int step = 0; step < 90; ++step) {
        plain.step(1.0 / 60, kGravity);
        bouncy.step(1.0 / 60, kGravity);
        const std::vector<std::uint64_t> after_step = speeds("step " + std::to_string(step));
        compared += static_cast<int>(after_step.size());
        if (step == 40) {
          // a cube pushed up and turned between two steps: the speeds stay those of the step
          plain.set_velocity(ids[0][4], {0, 2, 0}, {1, 0, 0});
          bouncy.set_velocity(ids[1][4], {0, 2, 0}, {1, 0, 0});
          EXPECT_EQ(speeds("after set_velocity"), after_step) << what;
          // and one destroyed (the last body moves into its place): the others' stay the same
          plain.destroy(ids[0][2]), bouncy.destroy(ids[1][2]);
          ids[0].erase(ids[0].begin() + 2), ids[1].erase(ids[1].begin() + 2);
          const std::vector<std::uint64_t> after_destroy = speeds("after destroy");
          EXPECT_LT(after_destroy.size(), after_step.size()) << what;  // its manifolds went with it
        }
      }
      EXPECT_GT(compared, 500) << what;
      for (std::size_t i = 0; i < ids[0].size(); ++i)
        EXPECT_EQ(plain.pose(ids[0][i]).position, bouncy.pose(ids[1][i]).position) << what << " body " << i;
    }
}

TEST(RigidSimd, PathsAreNamedAndBestIsResolved) {
  EXPECT_EQ(to_string(RigidSimd::Best), "best");
  EXPECT_EQ(to_string(RigidSimd::Avx512), "avx512");
  RigidBodySystem s;
  EXPECT_NE(s.simd(), RigidSimd::Best);
  s.set_simd(RigidSimd::Scalar);
  EXPECT_EQ(s.simd(), RigidSimd::Scalar);
  s.set_simd(RigidSimd::Best);
  EXPECT_EQ(s.simd(), paths().back());
}

namespace {

// colour -> the dynamic bodies of its manifolds; fails when one appears twice
void expect_colors_share_no_dynamic_body(const RigidBodySystem& s, int& colored, int& colors) {
  std::map<int, std::set<std::uint32_t>> seen;
  colored = 0;
  for (std::size_t k = 0; k < s.manifold_count(); ++k) {
    const pba::RigidManifoldInfo m = s.manifold(k);
    if (m.color < 0) continue;
    ++colored;
    for (const pba::RigidBodyId id : {m.a, m.b}) {
      if (s.type(id) != BodyType::Dynamic || !s.awake(id)) continue;
      EXPECT_TRUE(seen[m.color].insert(id.index).second)
          << "body " << id.index << " twice in colour " << m.color;
    }
  }
  colors = static_cast<int>(seen.size());
}

}  // namespace

// No two manifolds of a colour share a dynamic body (static, kinematic and sleeping bodies
// may be shared: the solver never writes them), in a pyramid, in falling boxes landing on
// each other and in the mixed scene, under the soft step and sequential impulses; and the
// colours are far fewer than the manifolds (each holds many, solved together).
TEST(RigidColors, NoTwoManifoldsOfAColourShareADynamicBody) {
  for (const RigidSolverType solver : {RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse}) {
    RigidBodySystem pyramid({.capacity = 512, .contacts = {.solver = solver, .sleep = false}});
    pba::rigid_scenes::square_pyramid(pyramid, 8);
    RigidBodySystem fall({.capacity = 512, .contacts = {.solver = solver}});
    pba::rigid_scenes::falling_boxes(fall, 5);
    RigidBodySystem mixed({.contacts = {.solver = solver}});
    mixed_scene(mixed);
    for (int i = 0; i < 90; ++i) {
      pyramid.step(1.0 / 60, kGravity), fall.step(1.0 / 60, kGravity), mixed.step(1.0 / 60, kGravity);
      int colored = 0, colors = 0;
      for (const RigidBodySystem* s : {&pyramid, &fall, &mixed}) expect_colors_share_no_dynamic_body(*s, colored, colors);
    }
    int colored = 0, colors = 0;
    expect_colors_share_no_dynamic_body(pyramid, colored, colors);
    EXPECT_EQ(colored, static_cast<int>(pyramid.manifold_count())) << to_string(solver);  // no overflow
    EXPECT_LT(colors * 10, colored) << to_string(solver);
  }
}

// The bands run bottom up: in a 6-stack each contact between boxes takes a colour after the
// one below it (the pass meets a box's support before what the box carries), and the ground's
// contact comes last; TGS (pair order, contact_solver.cpp) and XPBD do not colour.
TEST(RigidColors, StacksAreSolvedFromTheGroundUp) {
  for (const RigidSolverType solver : {RigidSolverType::SoftStep, RigidSolverType::Tgs, RigidSolverType::Xpbd}) {
    RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
    const auto boxes = pba::rigid_scenes::vertical_stack(s, 6);
    s.step(1.0 / 60, kGravity);
    // the colour of the contact under box i (i = 0: the ground's)
    std::vector<int> under(boxes.size(), -2);
    for (std::size_t k = 0; k < s.manifold_count(); ++k) {
      const pba::RigidManifoldInfo m = s.manifold(k);
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if (m.b == boxes[i] || (m.a == boxes[i] && s.type(m.b) == BodyType::Static)) under[i] = m.color;
    }
    if (solver != RigidSolverType::SoftStep) {
      for (const int c : under) EXPECT_EQ(c, -1);
      continue;
    }
    for (std::size_t i = 2; i < boxes.size(); ++i) EXPECT_GT(under[i], under[i - 1]) << to_string(solver) << " box " << i;
    EXPECT_GT(under[0], under.back()) << to_string(solver);
  }
}

namespace {

constexpr double kG = 9.81;  // (m/s^2, kGravity's)

// Balls among boxes, so that the solver's two block kinds run side by side, in the same
// colours (src/rigid/solver.h: a colour's manifolds of one point go to blocks of their own):
// a square pyramid of boxes; 20 balls rolling down a static ramp of 20 degrees side by side;
// a 5 x 5 grid of balls resting on the ground; a ball resting on top of each of 16 boxes
// (one-point manifolds between dynamic bodies, a colour of their own); four balls of
// restitution 0.5 dropped from 1 m; 16 balls with rolling resistance rolling on the ground at
// 2 m/s (one-point lanes that roll). The balls against the ground and the ramp share a colour
// with the boxes' ground contacts: four whole one-point blocks, and one ball in a
// ContactBlock's lane.
struct BallsAmongBoxes {
  static constexpr double kRadius = 0.2, kTheta = 20 * pba::kPi / 180, kDrop = 1.0, kE = 0.5, kC = 0.1, kV0 = 2;
  std::vector<pba::RigidBodyId> rolling, resting, on_boxes, bouncing, resisted, boxes;
  Vec3 down{-std::cos(kTheta), -std::sin(kTheta), 0};

  explicit BallsAmongBoxes(RigidBodySystem& s) {
    boxes = pba::rigid_scenes::square_pyramid(s, 4);  // (and the ground, mu 0.6)
    // the ramp: a static slab whose top face passes through (-30, 10, 0), tilted down towards -x
    const Vec3 up{-std::sin(kTheta), std::cos(kTheta), 0};
    const pba::Quat tilt = glm::angleAxis(kTheta, Vec3(0, 0, 1));
    const Vec3 top{-30, 10, 0};
    s.create({.type = BodyType::Static, .pose = {top - 0.5 * up, tilt},
              .shapes = {{.shape = ColliderShape::box({12, 0.5, 12}), .material = {.friction = 1}}}});
    auto ball = [&](const Vec3& at, double restitution = 0) {
      return s.create({.pose = {at}, .shapes = {{.shape = ColliderShape::sphere(kRadius),
                                                 .material = {.restitution = restitution, .friction = 1}}}});
    };
    for (int i = 0; i < 20; ++i) rolling.push_back(ball(top + kRadius * up + Vec3(0, 0, -9.5 + i)));
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) resting.push_back(ball({10.0 + i, kRadius, -2.0 + j}));
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        boxes.push_back(s.create({.pose = {{20.0 + 2 * i, 0.5, -3.0 + 2 * j}},
                                  .shapes = {{.shape = ColliderShape::box(Vec3(0.5)), .material = {.friction = 1}}}}));
        on_boxes.push_back(ball({20.0 + 2 * i, 1 + kRadius, -3.0 + 2 * j}));
      }
    for (int i = 0; i < 4; ++i) bouncing.push_back(ball({-8.0, kDrop + kRadius, -3.0 + 2 * i}, kE));
    for (int i = 0; i < 16; ++i)
      resisted.push_back(s.create({.pose = {{40, kRadius, -8.0 + i}}, .linear_velocity = {kV0, 0, 0},
                                   .angular_velocity = {0, 0, -kV0 / kRadius},
                                   .shapes = {{.shape = ColliderShape::sphere(kRadius), .material = {.friction = 0.5},
                                               .rolling_resistance = kC}}}));
  }
};

}  // namespace

// A ball in a one-point block (or in a ContactBlock's lane, beyond its colour's whole
// one-point blocks) gives the physics, next to boxes in four-point blocks: it rolls
// down a slope at (5/7) g sin(theta) (2%, as RigidFriction.ASphereRollsAtFiveSeventhsOfGSinTheta),
// its rolling resistance c slows it at (5/7) c g on level ground (1e-3, as
// RigidFriction.RollingResistanceSlowsASphereAtFiveSeventhsOfCG),
// rests on the ground and on boxes (under 1 mm/s; its centre within 0.1 mm of a radius up:
// the soft contact's sag is g / w^2, 43 um at the ground's 480 rad/s), rebounds to e^2 of
// its drop (3%, as RigidRestitution.ASphereReboundsToESquaredOfItsHeight), and the boxes'
// pyramid stands; under the soft step and TGS (which solves everything lane by lane), and
// the sequential impulses' rest (its one step of 1/60 s has neither's rolling nor bounce).
// Every SIMD path gives the same bits under every solver.
TEST(RigidSimd, OnePointBlocksKeepTheBallsPhysicsAmongBoxes) {
  for (const RigidSolverType solver : {RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse, RigidSolverType::Tgs}) {
    RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
    const BallsAmongBoxes scene(s);
    std::vector<Vec3> pyramid;
    for (const auto b : scene.boxes) pyramid.push_back(s.center_of_mass(b));
    std::vector<double> v1(scene.rolling.size()), peak(scene.bouncing.size(), 0.0), u1(scene.resisted.size());
    std::vector<char> bounced(scene.bouncing.size(), 0);
    std::size_t most_one_point = 0;
    for (int i = 0; i < 120; ++i) {
      s.step(1.0 / 60, kGravity);
      most_one_point = std::max(most_one_point, s.profile().one_point);
      if (i == 29) {
        for (std::size_t k = 0; k < scene.rolling.size(); ++k) v1[k] = glm::dot(s.linear_velocity(scene.rolling[k]), scene.down);
        for (std::size_t k = 0; k < scene.resisted.size(); ++k) u1[k] = s.linear_velocity(scene.resisted[k]).x;
      }
      for (std::size_t k = 0; k < scene.bouncing.size(); ++k) {
        const double y = s.center_of_mass(scene.bouncing[k]).y - BallsAmongBoxes::kRadius;
        if (s.linear_velocity(scene.bouncing[k]).y > 0) bounced[k] = 1;
        if (bounced[k]) peak[k] = std::max(peak[k], y);
      }
    }
    // the solvers that colour put the balls' manifolds in whole one-point blocks: of the 20 +
    // 25 + 16 + 4 against the ground and the ramp (a colour) 64, the 65th in a ContactBlock's
    // lane, and the 16 on the boxes (another colour), once all have landed
    if (solver == RigidSolverType::Tgs) EXPECT_EQ(most_one_point, 0u);
    else EXPECT_EQ(most_one_point, 80u) << to_string(solver);
    const double expected = 5.0 / 7 * kG * std::sin(BallsAmongBoxes::kTheta);
    if (solver != RigidSolverType::SequentialImpulse) {
      for (std::size_t k = 0; k < scene.rolling.size(); ++k) {
        const double a = (glm::dot(s.linear_velocity(scene.rolling[k]), scene.down) - v1[k]) / 1.5;
        EXPECT_NEAR(a, expected, 0.02 * expected) << to_string(solver) << " ball " << k;
      }
      const double rebound = BallsAmongBoxes::kE * BallsAmongBoxes::kE * BallsAmongBoxes::kDrop;
      for (std::size_t k = 0; k < scene.bouncing.size(); ++k)
        EXPECT_NEAR(peak[k], rebound, 0.03 * rebound) << to_string(solver) << " ball " << k;
      const double slowing = 5.0 / 7 * BallsAmongBoxes::kC * kG;
      for (std::size_t k = 0; k < scene.resisted.size(); ++k) {
        const double a = (u1[k] - s.linear_velocity(scene.resisted[k]).x) / 1.5;
        EXPECT_NEAR(a, slowing, 1e-3 * slowing) << to_string(solver) << " ball " << k;
      }
    }
    for (const auto b : scene.resting) {
      EXPECT_LT(glm::length(s.linear_velocity(b)), 1e-3) << to_string(solver);
      EXPECT_NEAR(s.center_of_mass(b).y, BallsAmongBoxes::kRadius, 1e-4) << to_string(solver);
    }
    for (const auto b : scene.on_boxes) {
      EXPECT_LT(glm::length(s.linear_velocity(b)), 1e-3) << to_string(solver);
      EXPECT_NEAR(s.center_of_mass(b).y, 1 + BallsAmongBoxes::kRadius, 2e-4) << to_string(solver);
    }
    for (std::size_t k = 0; k < scene.boxes.size(); ++k)
      EXPECT_LT(glm::length(s.center_of_mass(scene.boxes[k]) - pyramid[k]), 1e-3) << to_string(solver) << " box " << k;
  }
  const std::vector<RigidSimd> all = paths();
  for (const RigidSolverType solver : pba::kRigidSolvers) {
    auto run = [&](RigidSimd path) {
      RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
      s.set_simd(path);
      const BallsAmongBoxes scene(s);
      for (int i = 0; i < 90; ++i) s.step(1.0 / 60, kGravity);
      return s.hash();
    };
    const std::uint64_t scalar = run(RigidSimd::Scalar);
    for (const RigidSimd p : all) EXPECT_EQ(run(p), scalar) << to_string(solver) << " on " << to_string(p);
  }
}

// While the colours and the blocks' layout stand (a pile at rest), the solver lanes keep last
// step's bodies, write masks, inverse masses, impulse units and slop instead of gathering them
// again (RigidContacts::lanes_kept); when the layout changes they are gathered anew. Either
// way the same bits: a 5-level pyramid, balls on the ground (one-point blocks, one with rolling
// resistance), a 1 cm cube (a slop of its own, half the settings'), a box dropped on the
// pyramid at step 60 (a new body: the colours are made anew) and the settings' slop changed at
// step 100 (the kept slop would be stale), under the three solvers that fill blocks, on every
// SIMD path, with the reuse on and off; and the reuse ran (kept lanes before step 60 and after
// the slop changed, none at steps 60 and 100, none with it off).
TEST(RigidColors, KeptLanesGiveTheSameBitsAsLanesGatheredAnew) {
  for (const RigidSolverType solver : {RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse, RigidSolverType::Tgs}) {
    for (const RigidSimd path : paths()) {
      std::uint64_t hash[2] = {0, 0};
      for (const bool reuse : {false, true}) {
        RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
        s.set_simd(path);
        s.set_lane_reuse(reuse);
        pba::rigid_scenes::square_pyramid(s, 5);
        for (int i = 0; i < 3; ++i)
          s.create({.pose = {{4.0 + i, 0.3, 2}}, .shapes = {{.shape = ColliderShape::sphere(0.3), .rolling_resistance = 0.1 * i}}});
        s.create({.pose = {{-3, 0.005, 3}}, .shapes = {{.shape = ColliderShape::box(Vec3(0.005))}}});
        std::size_t kept_before = 0, kept_after = 0, kept_at_changes = 0, kept_off = 0;
        for (int i = 0; i < 150; ++i) {
          if (i == 60) s.create({.pose = {{0.3, 6, 0.2}}, .shapes = {{.shape = ColliderShape::box(Vec3(0.5))}}});
          if (i == 100) s.settings().linear_slop = 0.004;
          s.step(1.0 / 60, kGravity);
          const std::size_t kept = s.profile().lanes_kept;
          if (!reuse) kept_off += kept;
          else if (i == 60 || i == 100) kept_at_changes += kept;
          else if (i < 60) kept_before += kept;
          else if (i > 100) kept_after += kept;
        }
        hash[reuse] = s.hash();
        const std::string what = std::string(to_string(solver)) + " on " + std::string(to_string(path));
        if (reuse) {
          EXPECT_GT(kept_before, 0u) << what;
          EXPECT_GT(kept_after, 0u) << what;
          EXPECT_EQ(kept_at_changes, 0u) << what;
        } else {
          EXPECT_EQ(kept_off, 0u) << what;
        }
      }
      EXPECT_EQ(hash[1], hash[0]) << to_string(solver) << " on " << to_string(path);
    }
  }
}

// The reuse test (whether a touching pair keeps its manifolds) runs four pairs at a time on the
// SIMD paths: the same decisions, step by step, as the scalar path's, for pairs whose normal is
// kept in a's frame (boxes stacked on boxes) and in b's (boxes on a static slab created after
// them, so the dynamic body comes first in the pair), with spans of touching pairs that are not
// a multiple of four. A box slides in at 2 m/s and stops within v^2 / (2 mu g) = 0.41 m (its
// mixed friction sqrt(0.5 x 1) = 0.71 is more than mu = 0.5) while its manifold is made anew;
// once everything rests, every manifold is carried over.
TEST(RigidSimd, ManifoldsAreCarriedOverAlikeOnEveryPath) {
  std::vector<std::vector<std::size_t>> decisions;  // by path: built and reused, step after step
  std::vector<std::uint64_t> hashes;
  for (const RigidSimd p : paths()) {
    RigidBodySystem s;
    s.set_simd(p);
    const pba::SurfaceMaterial m{.restitution = 0, .friction = 0.5};
    for (int i = 0; i < 7; ++i)
      for (int level = 0; level < 1 + i % 3; ++level)
        s.create({.pose = {{1.5 * i - 4.5, 0.5 + 1.0 * level, 0}}, .shapes = {{.shape = ColliderShape::box(Vec3(0.5)), .material = m}}});
    const auto slider = s.create({.pose = {{-4, 0.5, 3}}, .linear_velocity = {2, 0, 0},
                                  .shapes = {{.shape = ColliderShape::box(Vec3(0.5)), .material = m}}});
    s.create({.type = BodyType::Static, .pose = {{0, -0.5, 0}},
              .shapes = {{.shape = ColliderShape::box({10, 0.5, 10}), .material = {.restitution = 0, .friction = 1}}}});
    std::vector<std::size_t> seen;
    std::size_t built = 0, reused = 0;
    for (int i = 0; i < 150; ++i) {
      s.step(1.0 / 60, kGravity);
      seen.push_back(s.profile().built), seen.push_back(s.profile().reused);
      built += s.profile().built, reused += s.profile().reused;
    }
    // the slider stopped within its bound, and everything rests on carried-over manifolds
    const double slid = s.center_of_mass(slider).x + 4;
    EXPECT_GT(slid, 0.0) << to_string(p);
    EXPECT_LT(slid, 2.0 * 2.0 / (2 * 0.5 * 9.81)) << to_string(p);
    EXPECT_EQ(s.profile().built, 0u) << to_string(p);
    EXPECT_EQ(s.profile().reused, s.manifold_count()) << to_string(p);
    EXPECT_GT(built, 0u) << to_string(p);
    EXPECT_GT(reused, built) << to_string(p);
    decisions.push_back(seen);
    hashes.push_back(s.hash());
  }
  for (std::size_t k = 1; k < decisions.size(); ++k) {
    EXPECT_EQ(decisions[k], decisions[0]) << to_string(paths()[k]);
    EXPECT_EQ(hashes[k], hashes[0]) << to_string(paths()[k]);
  }
}

// The free motion's double blocks (AVX-512 runs a kind's bodies 16 at a time, two blocks of
// its lanes, and the rest 8 at a time, then one by one): a rain of 48 bodies, 24 triaxial boxes
// (three half extents drawn apart) and 24 balls, each kind one double block and a block of 8,
// released at rest (all awake through their fall: 16 or more moving bodies of each kind every
// step) and run through their landing (from 10 to 14 m up: 1.43 to 1.69 s) under the soft
// step. Every path gives the same bits, pinned (so a change of the double block's offsets shows
// on a CPU that runs it).
TEST(RigidSimd, DoubleBlocksOfTheFreeMotionGiveTheSameBitsOnEveryPath) {
  std::vector<std::uint64_t> hashes;
  for (const RigidSimd p : paths()) {
    RigidBodySystem s({.contacts = {.solver = RigidSolverType::SoftStep}});
    s.set_simd(p);
    const auto bodies = pba::rigid_scenes::rain(s, 48);
    for (int i = 0; i < 120; ++i) {
      s.step(1.0 / 60, kGravity);
      if (i != 80) continue;
      for (const auto b : bodies) EXPECT_TRUE(s.awake(b)) << to_string(p);
    }
    hashes.push_back(s.hash());
  }
  for (std::size_t k = 1; k < hashes.size(); ++k) EXPECT_EQ(hashes[k], hashes[0]) << to_string(paths()[k]);
  EXPECT_EQ(hashes[0], 0x24b501ddd9c003adull);
}

// One-point blocks whose one side is a single body that no lane writes (a static ground, and
// a kinematic plate moving at 1 m/s and turning at 0.5 rad/s: its velocity rows are not zero,
// and the same in every lane); 32 balls land on it sliding at 3 m/s, so that the rounds of a
// landing while sliding run on one-point blocks (they go on from the pass's state). Each path
// gives the scalar path's bits after a second, with the 32 balls on the plate (32 one-point
// manifolds against it, two whole one-point blocks), none sunk into it by more than the slop.
TEST(RigidSimd, OnePointBlocksAgainstOneUnwrittenBodyGiveTheSameBitsOnEveryPath) {
  constexpr double kRadius = 0.2, kTop = 0.1;  // (m; the plate's top face at y = kTop)
  const double slop = pba::ContactSettings{}.linear_slop;
  auto run = [&](RigidSimd path, BodyType under, int& touching) {
    RigidBodySystem s({.contacts = {.sleep = false}});
    s.set_simd(path);
    const bool moving = under == BodyType::Kinematic;
    const ColliderShape slab = ColliderShape::box({8, kTop, 8}), ball = ColliderShape::sphere(kRadius);
    const auto plate = s.create({.type = under,
                                 .pose = {{0, 0, 0}},
                                 .linear_velocity = moving ? Vec3(1, 0, 0) : Vec3(0),
                                 .angular_velocity = moving ? Vec3(0, 0.5, 0) : Vec3(0),
                                 .shapes = {{.shape = slab, .material = {.friction = 0.5}}}});
    std::vector<pba::RigidBodyId> balls;
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 4; ++j)
        balls.push_back(s.create({.pose = {{-3.5 + i, kTop + kRadius + 0.05, -1.5 + j}}, .linear_velocity = {3, -1, 0},
                                  .shapes = {{.shape = ball, .material = {.friction = 0.5}}}}));
    for (int i = 0; i < 60; ++i) s.step(1.0 / 60, kGravity);
    touching = 0;
    for (std::size_t k = 0; k < s.manifold_count(); ++k) {
      const pba::RigidManifoldInfo m = s.manifold(k);
      if (m.points == 1 && (m.a == plate || m.b == plate)) ++touching;
    }
    for (const auto b : balls) EXPECT_GT(s.pose(b).position.y, kTop + kRadius - slop) << to_string(path);
    return s.hash();
  };
  for (const BodyType under : {BodyType::Static, BodyType::Kinematic}) {
    const char* name = under == BodyType::Static ? "static" : "kinematic";
    int touching = 0;
    const std::uint64_t scalar = run(RigidSimd::Scalar, under, touching);
    EXPECT_EQ(touching, 32) << name;
    for (const RigidSimd p : paths()) {
      EXPECT_EQ(run(p, under, touching), scalar) << to_string(p) << ", " << name;
      EXPECT_EQ(touching, 32) << to_string(p) << ", " << name;
    }
  }
}
