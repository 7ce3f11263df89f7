// The fused kernel's broad phase and storage: skipping the blocks that no collider can
// reach gives the same bits as testing every collider against every particle, with
// moving and turning surfaces, fast particles, forcers, spawns, removals and teleports;
// uniform inverse masses and radii read from a value instead of a column give the same
// bits as the column; the hot columns survive growth and copies.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <utility>
#include <vector>

#include "error_of.h"
#include "pba/particles.h"

namespace {

using pba::Collider;
using pba::ParticleDef;
using pba::ParticleSystem;
using pba::Pose;
using pba::Quat;
using pba::Vec3;
using pba::test_support::error_of;

// a fixed LCG, so every run builds the same scene
struct Rng {
  std::uint64_t s;
  double operator()() {
    s = s * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(s >> 11) * 0x1.0p-53;
  }
  double in(double lo, double hi) { return lo + (hi - lo) * (*this)(); }
};

// A collider moving from its pose at t to its pose at t + h, with the matching velocities.
Collider moving(Collider c, const Pose& p0, const Pose& p1, double h, const Vec3& spin) {
  c.begin = p0;
  c.end = p1;
  c.velocity = (p1.position - p0.position) / h;
  c.angular_velocity = spin;
  return c;
}

Quat turn(double angle, const Vec3& axis) { return glm::angleAxis(angle, glm::normalize(axis)); }

// Every kind of surface, most of them moving: a ground plane that tilts and bobs, a
// sphere on a circle, a box that rises and falls while it spins, and a static sphere.
std::vector<Collider> surfaces(double t, double h) {
  std::vector<Collider> c;
  auto ground_pose = [](double s) {
    return Pose{.position = {0, 0.3 * std::sin(2 * s), 0}, .rotation = turn(0.2 * std::sin(s), {0, 0, 1})};
  };
  c.push_back(moving(Collider::plane({0, 1, 0}, 0, {.restitution = 0.5, .friction = 0.2}), ground_pose(t),
                     ground_pose(t + h), h, {0, 0, 0.2 * std::cos(t)}));
  auto ball_pose = [](double s) { return Pose{.position = {2 * std::cos(s), 1.2, 2 * std::sin(s)}}; };
  c.push_back(moving(Collider::sphere({0, 0, 0}, 0.6, {.restitution = 0.8}), ball_pose(t), ball_pose(t + h), h, {}));
  auto box_pose = [](double s) {
    return Pose{.position = {-2, 1 + 0.5 * std::sin(3 * s), 0}, .rotation = turn(1.5 * s, {0, 1, 0.3})};
  };
  c.push_back(moving(Collider::box({0, 0, 0}, {0.8, 0.2, 0.5}, {.restitution = 0.3, .friction = 0.5}),
                     box_pose(t), box_pose(t + h), h, 1.5 * glm::normalize(Vec3(0, 1, 0.3))));
  c.push_back(Collider::sphere({3, 0.5, -3}, 0.4, {.restitution = 0.6}));
  return c;
}

// Four groups, each a run of whole blocks so that blocks differ: particles raining from
// 15-30 m (they reach the ground during the run), from 60-80 m (they do not: a free fall
// from 60 m takes 3.5 s), particles in the thick of the surfaces, and fast ones (40 m/s,
// a third of a metre per step) flying at the box from 30 m away, which the broad phase
// must catch in time.
void populate(ParticleSystem& ps, Rng& rng, bool uniform) {
  auto mass = [&] { return uniform ? 0.02 : rng.in(0.005, 0.05); };
  auto radius = [&] { return uniform ? 0.03 : rng.in(0.01, 0.06); };
  for (double lo : {15.0, 60.0})
    for (int i = 0; i < 768; ++i)
      ps.spawn({.position = {rng.in(-4, 4), rng.in(lo, 2 * lo), rng.in(-4, 4)},
                .velocity = {rng.in(-1, 1), rng.in(-3, 3), rng.in(-1, 1)},
                .mass = mass(),
                .radius = radius()});
  for (int i = 0; i < 1000; ++i)
    ps.spawn({.position = {rng.in(-4, 4), rng.in(0.2, 3), rng.in(-4, 4)},
              .velocity = {rng.in(-3, 3), rng.in(-3, 3), rng.in(-3, 3)},
              .mass = mass(),
              .radius = radius()});
  for (int i = 0; i < 600; ++i)
    ps.spawn({.position = {rng.in(-32, -30), rng.in(0.7, 1.3), rng.in(-0.4, 0.4)},
              .velocity = {40, rng.in(3, 4), 0},
              .mass = mass(),
              .radius = radius()});
}

struct StepRecord {
  std::uint64_t hash = 0;
  std::size_t contacts = 0;
  std::size_t exact_blocks = 0;
};

// Steps a scene 360 times (3 s at 120 Hz) with the broad phase on or off, changing it
// along the way as a game would (spawns, removals, teleports), and records the hash and
// the contacts after every step.
std::vector<StepRecord> run(bool broad, bool uniform, bool forcers, bool verbose = false) {
  pba::ParticleSystemDef def;
  def.capacity = 4000;
  def.forces.quadratic_drag = 0.002;
  def.forces.wind = {.velocity = {1, 0, 0.5}, .gust = 1.5, .gust_period = 0.4, .seed = 11};
  ParticleSystem ps(def);
  ps.set_broad_phase(broad);
  Rng rng{99};
  populate(ps, rng, uniform);
  std::vector<pba::Forcer> fs;
  if (forcers) {
    fs.push_back({.kind = pba::ForcerKind::Vortex, .shape = pba::ForcerShape::Cylinder,
                  .pose = {.position = {0, 2, 0}}, .radius = 2, .half_height = 2, .strength = 0.05, .pull = 0.02});
    fs.push_back({.kind = pba::ForcerKind::Fan, .pose = {.position = {-10, 1, 0}}, .half_extents = {5, 1, 1},
                  .direction = {1, 0.2, 0}, .strength = 0.2});
  }
  const double h = 1.0 / 120;
  std::vector<StepRecord> out;
  for (int i = 0; i < 360; ++i) {
    const double t = i * h;
    // the game changes the system between steps
    if (i % 40 == 17) {
      ps.spawn({.position = {rng.in(-2, 2), 6, rng.in(-2, 2)}, .velocity = {0, -5, 0}, .mass = uniform ? 0.02 : 0.03,
                .radius = uniform ? 0.03 : 0.02});
      // a teleport among the particles near the surfaces, a kick up for one raining from
      // 15-30 m (its block runs the exact path once, to be measured again)
      ps.set_position(static_cast<std::size_t>(rng.in(1536, 2536)), Vec3(rng.in(-1, 1), 0.5, rng.in(-1, 1)));
      ps.set_velocity(static_cast<std::size_t>(rng.in(0, 768)), Vec3(0, 5, 0));
    }
    if (i % 60 == 31) {
      const auto id = ps.create({.position = {0, 40, 0}});
      ps.destroy(id);
    }
    const std::vector<Collider> c = surfaces(t, h);
    ps.step(t, h, c, fs);
    out.push_back({ps.hash(), ps.contacts(), ps.exact_blocks()});
    if (verbose && i % 20 == 0) std::printf("step %d exact %zu contacts %zu\n", i, ps.exact_blocks(), ps.contacts());
  }
  return out;
}

TEST(BroadPhase, SameBitsAsTestingEveryParticle) {
  for (bool uniform : {false, true})
    for (bool forcers : {false, true}) {
      const std::vector<StepRecord> on = run(true, uniform, forcers), off = run(false, uniform, forcers);
      std::size_t contacts = 0, exact_on = 0, exact_off = 0;
      for (std::size_t i = 0; i < on.size(); ++i) {
        ASSERT_EQ(on[i].hash, off[i].hash) << "step " << i << " uniform " << uniform << " forcers " << forcers;
        ASSERT_EQ(on[i].contacts, off[i].contacts) << "step " << i;
        contacts += on[i].contacts;
        exact_on += on[i].exact_blocks;
        exact_off += off[i].exact_blocks;
      }
      // not vacuous: the surfaces were hit (thousands of responses); without the broad
      // phase all 13 blocks (3136 to 3145 particles) run the exact path every step, with it
      // the three blocks raining from 60-80 m run it only at the first step (nothing is
      // known yet) and never again, and the others skip some steps too
      EXPECT_GT(contacts, 10000u);
      EXPECT_EQ(exact_off, 360u * 13u);
      EXPECT_LE(exact_on, exact_off - 3u * 359u);
    }
}

// the fast group must be caught by the box however the broad phase bounds it: none of
// them passes x = -2 + 0.8 + r (the box's far face) in the run above. Checked directly:
TEST(BroadPhase, FastParticlesStillHitTheBox) {
  pba::ParticleSystemDef def;
  def.capacity = 512;
  def.forces.gravity = Vec3(0);
  ParticleSystem ps(def);
  for (int i = 0; i < 512; ++i)
    ps.spawn({.position = {-30 - 0.01 * i, 0, 0.001 * (i % 100) - 0.05}, .velocity = {60, 0, 0}, .mass = 1,
              .radius = 0.02});
  const Collider box = Collider::box({0, 0, 0}, {0.01, 0.5, 0.5}, {.restitution = 0});
  const double h = 1.0 / 60;  // 1 m per step, against a 2 cm wall
  std::size_t exact = 0;
  for (int i = 0; i < 60; ++i) {
    ps.step(i * h, h, std::span(&box, 1), {});
    exact += ps.exact_blocks();
    if (i == 5) {
      EXPECT_EQ(ps.exact_blocks(), 0u) << "30 m away, the blocks should be skipped";
    }
  }
  for (std::size_t i = 0; i < ps.size(); ++i) EXPECT_LT(ps.position(i).x, 0.0) << i;
  EXPECT_GT(exact, 0u);
}

// A box spinning at 120 rad/s turns a radian per step: the exact test clips the segment
// between a particle's start and end positions, each in the box's frame of its time, and
// for a particle at rest outside the box's circumscribed sphere that chord can cut into a
// corner. The broad phase must bound the turn of the frame too, or it skips those blocks.
TEST(BroadPhase, SpinningBoxSameBitsAsTestingEveryParticle) {
  const double h = 1.0 / 120, w = 120, turn_per_step = w * h;
  const Vec3 axis = glm::normalize(Vec3(1, 2, 3));
  auto run_spin = [&](bool broad) {
    pba::ParticleSystemDef def;
    def.capacity = 4096;
    def.forces.gravity = Vec3(0);
    ParticleSystem ps(def);
    ps.set_broad_phase(broad);
    // two blocks per corner of the 1 m cube (circumradius 0.866 m): particles at rest
    // 0.9 m from the centre, two and a half steps' turn ahead of the corner's direction,
    // so that in the box's frame the third step's chord (the first two steps measure the
    // blocks) runs from half a turn before the corner to half a turn past it, through the
    // corner's tip: its middle is 0.9 sqrt(cos^2 a + sin^2 a cos^2 0.5) from the centre,
    // down to 0.79 m (a the angle between the corner and the axis)
    Rng rng{17};
    for (int i = 0; i < 4096; ++i) {
      const int corner = i / 512;
      const Vec3 c = glm::normalize(Vec3(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1));
      const Vec3 p = turn(2.5 * turn_per_step + rng.in(-0.005, 0.005), axis) * (rng.in(0.9, 0.905) * c);
      ps.spawn({.position = p, .mass = 1, .radius = 0.001});
    }
    std::vector<std::uint64_t> hashes;
    std::size_t contacts = 0;
    for (int i = 0; i < 3; ++i) {
      const double t = i * h;
      const Collider box = moving(Collider::box({0, 0, 0}, {0.5, 0.5, 0.5}, {.restitution = 0}),
                                  Pose{.rotation = turn(w * t, axis)}, Pose{.rotation = turn(w * (t + h), axis)}, h,
                                  w * axis);
      ps.step(t, h, std::span(&box, 1), {});
      hashes.push_back(ps.hash());
      contacts += ps.contacts();
    }
    return std::make_pair(hashes, contacts);
  };
  const auto on = run_spin(true), off = run_spin(false);
  EXPECT_EQ(on.first, off.first);
  EXPECT_EQ(on.second, off.second);
  EXPECT_GT(off.second, 0u) << "no chord cut the box: the test tests nothing";
}

// The broad phase bounds how fast a block can move from the forces of the step: particles
// at rest, without gravity, blown at a wall 1.5 m away by a fan (1000 m/s^2) or by a
// 60 m/s wind through quadratic drag, must hit it exactly as without the broad phase.
TEST(BroadPhase, ForcersAndWindAreInTheReach) {
  for (bool fan : {true, false}) {
    auto blow = [&](bool broad) {
      pba::ParticleSystemDef def;
      def.capacity = 512;
      def.forces.gravity = Vec3(0);
      if (!fan) {
        def.forces.wind = {.velocity = {60, 0, 0}};
        def.forces.quadratic_drag = 0.01;
      }
      ParticleSystem ps(def);
      ps.set_broad_phase(broad);
      Rng rng{3};
      for (int i = 0; i < 512; ++i)
        ps.spawn({.position = {rng.in(-2, -1.5), rng.in(0, 0.5), rng.in(0, 0.5)}, .mass = 0.01, .radius = 0.01});
      std::vector<pba::Forcer> fs;
      if (fan) fs.push_back({.pose = {.position = {0, 0, 0}}, .half_extents = {5, 5, 5}, .direction = {1, 0, 0}, .strength = 10});
      const Collider wall = Collider::plane({-1, 0, 0}, 0, {.restitution = 0.5});
      const double h = 1.0 / 120;
      std::vector<std::uint64_t> hashes;
      for (int i = 0; i < 120; ++i) {
        ps.step(i * h, h, std::span(&wall, 1), fs);
        hashes.push_back(ps.hash());
      }
      for (std::size_t i = 0; i < ps.size(); ++i) EXPECT_LE(ps.position(i).x, -0.01 + 1e-5) << i;
      return hashes;
    };
    EXPECT_EQ(blow(true), blow(false)) << (fan ? "fan" : "wind");
  }
}

// Within one step the kick comes before the drift: particles at rest 2 mm above the
// ground when gravity is switched on between steps fall h^2 g = 2.7 mm in the next step
// at 60 Hz, though their speed bound at its start is 0.
TEST(BroadPhase, TheKickOfTheStepIsInTheReach) {
  auto drop = [](bool broad) {
    pba::ParticleSystemDef def;
    def.capacity = 256;
    def.forces.gravity = Vec3(0);
    ParticleSystem ps(def);
    ps.set_broad_phase(broad);
    for (int i = 0; i < 256; ++i) ps.spawn({.position = {0.01 * i, 0.012, 0}, .mass = 1, .radius = 0.01});
    const Collider ground = Collider::plane({0, 1, 0}, 0, {.restitution = 0});
    const double h = 1.0 / 60;
    ps.step(0, h, std::span(&ground, 1), {});  // weightless: measured, at rest
    ps.forces().gravity = Vec3(0, -9.81, 0);
    ps.step(h, h, std::span(&ground, 1), {});
    for (std::size_t i = 0; i < ps.size(); ++i) EXPECT_GE(ps.position(i).y, 0.01 - 1e-6) << i;
    return std::make_pair(ps.hash(), ps.contacts());
  };
  const auto on = drop(true), off = drop(false);
  EXPECT_EQ(on, off);
  EXPECT_EQ(off.second, 256u);
}

// Far from every surface no block runs the collision code; as the particles fall to the
// ground the blocks switch to the exact path, and resting on it they all stay there.
TEST(BroadPhase, SkipsFarBlocksAndSwitchesToExactNearSurfaces) {
  pba::ParticleSystemDef def;
  def.capacity = 2048;
  ParticleSystem ps(def);
  Rng rng{5};
  for (int i = 0; i < 2048; ++i)
    ps.spawn({.position = {rng.in(-5, 5), rng.in(20, 25), rng.in(-5, 5)}, .mass = 0.01, .radius = 0.02});
  const Collider ground = Collider::plane({0, 1, 0}, 0, {.restitution = 0});
  const double h = 1.0 / 120;
  // the first step measures every block (nothing known yet); then nothing is near
  ps.step(0, h, std::span(&ground, 1), {});
  EXPECT_EQ(ps.exact_blocks(), 8u);
  ps.step(h, h, std::span(&ground, 1), {});
  EXPECT_EQ(ps.exact_blocks(), 0u);
  // free fall from 20 m takes 2.02 s; after 3 s everything rests on the ground
  for (int i = 2; i < 360; ++i) ps.step(i * h, h, std::span(&ground, 1), {});
  EXPECT_EQ(ps.exact_blocks(), 8u);
  EXPECT_EQ(ps.contacts(), 2048u);
  for (std::size_t i = 0; i < ps.size(); ++i) ASSERT_GE(ps.position(i).y, 0.02 - 1e-5) << i;
}

// ---------------------------------------------------------------------------------------
// storage

// growth far past the reserved capacity keeps every value; a system moved into another
// (construction or assignment) steps exactly like one that never moved
TEST(Storage, GrowthAndMovesKeepEveryValue) {
  auto build = [] {
    pba::ParticleSystemDef def;
    def.capacity = 16;
    ParticleSystem ps(def);
    for (int i = 0; i < 5000; ++i)
      ps.spawn({.position = {i, -i, 0.5 * i}, .velocity = {1, 2, i % 7}, .mass = 1.0 + i % 3,
                .radius = 0.01 * (1 + i % 5)});
    return ps;
  };
  ParticleSystem ps = build();
  ASSERT_EQ(ps.size(), 5000u);
  EXPECT_GE(ps.capacity(), 5000u);
  for (int i = 0; i < 5000; ++i) {
    ASSERT_EQ(ps.position(i), Vec3(i, -i, static_cast<float>(0.5 * i))) << i;
    ASSERT_EQ(ps.velocity(i), Vec3(1, 2, i % 7)) << i;
    ASSERT_EQ(ps.mass(i), 1.0 / static_cast<double>(static_cast<float>(1.0 / (1.0 + i % 3)))) << i;
    ASSERT_EQ(ps.radius(i), static_cast<double>(static_cast<float>(0.01 * (1 + i % 5)))) << i;
  }
  ParticleSystem moved(build());
  ParticleSystem assigned;
  assigned = build();
  const Collider ground = Collider::plane({0, 1, 0}, -100, {.restitution = 0.5});
  for (int s = 0; s < 20; ++s) {
    for (ParticleSystem* p : {&ps, &moved, &assigned}) p->step(s / 60.0, 1 / 60.0, std::span(&ground, 1), {});
    ASSERT_EQ(moved.hash(), ps.hash()) << s;
    ASSERT_EQ(assigned.hash(), ps.hash()) << s;
  }
}

TEST(Storage, IndexOutOfRangeIsAnError) {
  ParticleSystem ps;
  ps.spawn({});
  try {
    ps.set_position(3, Vec3(0));
    FAIL();
  } catch (const pba::Error& e) {
    EXPECT_STREQ(e.what(), "ParticleSystem::set_position: particle index 3 out of range (1 particles)");
  }
  EXPECT_THROW(ps.set_velocity(1, Vec3(0)), pba::Error);
}

// The getters by index check it as the setters do. Until the fix position(i), velocity(i),
// mass, radius, age, lifetime, colour, source and emitter_at read past their columns
// (undefined behaviour) for an index out of range.
TEST(Storage, EveryAccessorByIndexRefusesOneOutOfRange) {
  ParticleSystem ps;
  ps.spawn({.position = {1, 2, 3}});
  EXPECT_EQ(ps.position(0), Vec3(1, 2, 3));
  EXPECT_EQ(error_of([&] { (void)ps.position(1); }), "ParticleSystem::position: particle index 1 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.velocity(1); }), "ParticleSystem::velocity: particle index 1 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.mass(7); }), "ParticleSystem::mass: particle index 7 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.radius(1); }), "ParticleSystem::radius: particle index 1 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.age(1); }), "ParticleSystem::age: particle index 1 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.lifetime(1); }), "ParticleSystem::lifetime: particle index 1 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.color(1); }), "ParticleSystem::color: particle index 1 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.source(1); }), "ParticleSystem::source: particle index 1 out of range (1 particles)");
  EXPECT_EQ(error_of([&] { (void)ps.emitter_at(0); }), "ParticleSystem::emitter_at: emitter slot 0 out of range (0 emitters)");
}

// A setter's Error names the call and the value: an integration method outside the enum was
// refused as "pba::Method: invalid value 99", naming no call. The method is kept.
TEST(Storage, ASetMethodOutsideTheEnumNamesTheCall) {
  ParticleSystem ps;
  ps.set_method(pba::Method::VelocityVerlet);
  EXPECT_EQ(error_of([&] { ps.set_method(static_cast<pba::Method>(99)); }),
            "ParticleSystem::set_method(m): pba::Method: invalid value 99");
  EXPECT_EQ(ps.method(), pba::Method::VelocityVerlet);
}

}  // namespace
