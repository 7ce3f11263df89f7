// Touch events of particle entities (issue 10, notifications): a particle entity that meets a
// collider's entity (a collider, a rigid body's shape) begins touching it, and ends when a
// tick passes without the particle kernels meeting it. The kernels record the collider at
// the impact inside the tick, so a bounce whose impact and rebound fall in one tick (every
// bounce here: the tick ends with the ball above the ground again) is reported.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "error_of.h"
#include "pba/world.h"

namespace {

using pba::ColliderShape;
using pba::EntityId;
using pba::Method;
using pba::Vec3;
using pba::World;

struct Bounce {
  int begin_tick = 0;   // the tick that reported the begin (ends at begin_tick * dt)
  int end_tick = -1;    // the tick that reported the end, -1 for none
  double speed = 0;     // approach speed (m/s)
  double apex = 0;      // highest bottom of the ball (m) over the following flight
  double gap_at_begin = 0;  // the ball's bottom above the ground at the end of the begin tick (m)
};

// A particle entity ball of radius r dropped from rest, its bottom h above a plane of
// restitution e, for `ticks` ticks of dt with method m: every touch with the ground.
std::vector<Bounce> bounce(Method m, double dt, double h, double e, double r, int ticks, EntityId* ground_out = nullptr,
                           EntityId* ball_out = nullptr) {
  World w({.stepper = {.fixed_dt = dt}});
  w.particles().set_method(m);
  const EntityId ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = ColliderShape::plane({0, 1, 0}, 0), .material = {.restitution = e, .friction = 0}});
  const EntityId ball = w.create_entity({.name = "ball", .pose = {.position = {0, h + r, 0}}});
  w.add_particle(ball, {.radius = r});
  if (ground_out) *ground_out = ground;
  if (ball_out) *ball_out = ball;
  std::vector<Bounce> out;
  for (int n = 1; n <= ticks; ++n) {
    w.step();
    const double bottom = w.pose(ball).position.y - r;
    if (!out.empty()) out.back().apex = std::max(out.back().apex, bottom);
    for (const pba::TouchBeginEvent& ev : w.touch_begin_events()) {
      // the ground (entity 0) first, the normal from it to the ball, the point on it
      EXPECT_EQ(ev.a, ground);
      EXPECT_EQ(ev.b, ball);
      EXPECT_EQ(ev.normal, Vec3(0, 1, 0));
      EXPECT_NEAR(ev.point.y, 0, 1e-6);
      EXPECT_GE(ev.approach_speed, 0);
      out.push_back({n, -1, ev.approach_speed, 0, bottom});
    }
    for (const pba::TouchEndEvent& ev : w.touch_end_events()) {
      EXPECT_EQ(ev.a, ground);
      EXPECT_EQ(ev.b, ball);
      if (!out.empty() && out.back().end_tick < 0) out.back().end_tick = n;
      else ADD_FAILURE() << "an end without a begin at tick " << n;
    }
  }
  return out;
}

// The brief's ball, with velocity Verlet (the generic integrator path), against the
// continuous closed form. Dropped from h, it meets the ground at t_1 = sqrt(2h/g) at
// v_1 = sqrt(2gh); the k-th impact (k = 0, 1, ...) is at v_k = e^k v_1 after a flight of
// 2 e^k v_1 / g. Velocity Verlet is exact under constant gravity at the ticks; the kernels
// find the impact on the chord between two ticks, which lies below the falling parabola by
// at most g dt^2 / 8, so each impact is found early by at most g dt^2 / (8 v) and its speed is
// low by at most g^2 dt^2 / (8 v); the rebound (e times that) carries the deficit into the
// next flight: B_k = e B_(k-1) + g^2 dt^2 / (8 (v_k - B_(k-1))), and the impact times are early
// by at most D_k = D_(k-1) + 2 e B_(k-1) / g + g dt^2 / (8 (v_k - B_k)). The float state adds
// rounding (1e-5 relative). Bounces at least the restitution threshold (2 g dt) fast leave
// the ground again; the first slower one rests: a begin with no end.
TEST(ParticleTouch, ABouncingBallBeginsAndEndsOncePerBounceAtTheClosedFormImpacts) {
  const double dt = 1.0 / 120, g = 9.81, h = 1, e = 0.8, r = 0.05;
  const std::vector<Bounce> b = bounce(Method::VelocityVerlet, dt, h, e, r, 600);
  const double v1 = std::sqrt(2 * g * h), threshold = 2 * g * dt;
  // the closed form's bounces: impacts until the first slower than the threshold
  int rest = 0;
  while (std::pow(e, rest) * v1 >= threshold) ++rest;
  ASSERT_EQ(b.size(), static_cast<std::size_t>(rest + 1));  // 16: e^15 v1 = 0.156 m/s < 0.164
  double t = std::sqrt(2 * h / g), v = v1, B = 0, D = 0;
  for (std::size_t k = 0; k < b.size(); ++k) {
    SCOPED_TRACE(k);
    D += 2 * e * B / g;
    B = e * B + g * g * dt * dt / (8 * (v - B));
    D += g * dt * dt / (8 * (v - B));
    // the begin is reported by the tick that holds the impact: (n - 1) dt < t <= n dt, t early by D
    EXPECT_LE((b[k].begin_tick - 1) * dt, t + 1e-9);
    EXPECT_GE(b[k].begin_tick * dt, t - D);
    EXPECT_LE(b[k].speed, v * (1 + 1e-5));
    EXPECT_GE(b[k].speed, v - B - 1e-5 * v);
    // one end after each begin, before the next; the last, resting, never ends
    if (k + 1 < b.size()) {
      EXPECT_GT(b[k].end_tick, b[k].begin_tick);
      EXPECT_LT(b[k].end_tick, b[k + 1].begin_tick);
    } else {
      EXPECT_EQ(b[k].end_tick, -1);
    }
    v *= e;
    t += 2 * v / g;
  }
  // the first impact's tick ended with the ball off the ground again, at the height the
  // rebound e v_1 reaches in the rest of the tick (tau after the impact), the impact early by
  // at most D_0 and slow by B_0: the bounce began and ended inside one tick
  const double tau = b[0].begin_tick * dt - std::sqrt(2 * h / g);
  const double B0 = g * g * dt * dt / (8 * v1), D0 = g * dt * dt / (8 * v1);
  EXPECT_GT(b[0].gap_at_begin, 0);
  EXPECT_NEAR(b[0].gap_at_begin, e * v1 * tau - g * tau * tau / 2, e * (v1 * D0 + B0 * tau) + 1e-6);
  // bounces until the bounce height e^(2k) h falls below the radius: 7 (e^14 = 0.044 < 0.05 <
  // e^12 = 0.069, far from a tie); counted from the flights' measured apexes
  const int closed = static_cast<int>(std::ceil(std::log(r / h) / (2 * std::log(e))));
  ASSERT_EQ(closed, 7);
  int counted = 0;
  while (counted < static_cast<int>(b.size()) && b[counted].apex >= r) ++counted;
  EXPECT_EQ(counted + 1, closed);
}

// The same ball with the default semi-implicit Euler (the fused kernel). From rest at a
// tick the scheme runs dt/2 ahead of the fall (y_n is the fall's height at t_n + dt/2, plus
// g dt^2 / 8), so the first impact is at t_1 - dt/2 at v_1 - g dt/2, to within the chord error
// B_0 above. A flight then loses speed: the scheme's lead of g dt t / 2 after t in the air
// lands a flight launched at w after at most 2w/g - dt, at least at w - g dt (a flight that
// starts at a tick: x_n = n dt w - g dt^2 n (n + 1) / 2 is 0 again at n = 2w/(g dt) - 1, at
// speed w - g dt); the impact's phase inside the tick decides how much of that it loses. So
// each impact speed lies between the exact e^k v_1 and the most lossy scheme's
// u_(k+1) = e u_k - g dt, and its time between the two schemes' impacts.
TEST(ParticleTouch, TheSemiImplicitEulerBallLiesBetweenTheExactFallAndTheSchemesLoss) {
  const double dt = 1.0 / 120, g = 9.81, h = 1, e = 0.8, r = 0.05;
  const std::vector<Bounce> b = bounce(Method::SemiImplicitEuler, dt, h, e, r, 600);
  const double v1 = std::sqrt(2 * g * h), threshold = 2 * g * dt;
  ASSERT_GE(b.size(), 2u);
  const double B0 = g * g * dt * dt / (8 * v1), D0 = g * dt * dt / (8 * v1);
  EXPECT_NEAR(b[0].speed, v1 - g * dt / 2, B0 + 1e-5 * v1);
  // the bounds of every impact, until both say the ball rests
  double lo = v1 - g * dt / 2, hi = v1, t_lo = std::sqrt(2 * h / g) - dt / 2, t_hi = std::sqrt(2 * h / g), B = B0,
         D = D0;
  for (std::size_t k = 0; k < b.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_LE((b[k].begin_tick - 1) * dt, t_hi + 1e-9);
    EXPECT_GE(b[k].begin_tick * dt, t_lo - D);
    EXPECT_LE(b[k].speed, hi * (1 + 1e-5));
    EXPECT_GE(b[k].speed, lo - B - 1e-5 * hi);
    // a bounce faster than the threshold ends before the next; a slower one rests
    if (k + 1 < b.size()) {
      EXPECT_GE(b[k].speed + B, threshold);
      EXPECT_GT(b[k].end_tick, b[k].begin_tick);
      EXPECT_LT(b[k].end_tick, b[k + 1].begin_tick);
    } else {
      EXPECT_LT(b[k].speed, threshold);
      EXPECT_EQ(b[k].end_tick, -1);
    }
    D += 2 * e * B / g;
    B = e * B + g * g * dt * dt / (8 * std::max(lo - B, g * dt));
    D += g * dt * dt / (8 * std::max(lo - B, g * dt));
    t_lo += 2 * e * lo / g - dt;
    t_hi += 2 * e * hi / g;
    lo = e * lo - g * dt;
    hi = e * hi;
  }
  // the bounces counted lie between the two schemes' counts of impacts down to the threshold
  std::size_t n_lo = 1, n_hi = 1;
  for (double u = v1 - g * dt / 2; u >= threshold; u = e * u - g * dt) ++n_lo;
  for (double u = v1; u >= threshold; u *= e) ++n_hi;
  EXPECT_GE(b.size(), n_lo);
  EXPECT_LE(b.size(), n_hi);
}

// A particle resting on a box (a collider entity) is in contact every tick: one begin, no
// end; lifted away, one end, and it falls back: a second begin. The contact is on the box's
// top face, at rest: approach speed at most the g dt gravity adds in a tick.
TEST(ParticleTouch, ARestingParticleBeginsOnceAndEndsWhenLifted) {
  const double dt = 1.0 / 120, g = 9.81, r = 0.05;
  World w({.stepper = {.fixed_dt = dt}});
  const EntityId ball = w.create_entity({.name = "ball", .pose = {.position = {0.2, 1 + r, 0.1}}});
  w.add_particle(ball, {.radius = r});
  const EntityId box = w.create_entity({.name = "box", .pose = {.position = {0, 0.5, 0}}});
  w.add_collider(box, {.shape = ColliderShape::box({1, 0.5, 1}), .material = {.restitution = 0.5, .friction = 0.5}});
  int begins = 0, ends = 0;
  for (int n = 0; n < 600; ++n) {
    w.step();
    for (const pba::TouchBeginEvent& ev : w.touch_begin_events()) {
      ++begins;
      EXPECT_EQ(ev.a, ball);  // the smaller index: the normal from the ball into the box
      EXPECT_EQ(ev.b, box);
      EXPECT_NEAR(ev.normal.y, -1, 1e-6);
      EXPECT_NEAR(ev.point.y, 1, 1e-6);
      EXPECT_LE(ev.approach_speed, g * dt * (1 + 1e-5));
    }
    ends += static_cast<int>(w.touch_end_events().size());
  }
  EXPECT_EQ(begins, 1);
  EXPECT_EQ(ends, 0);
  EXPECT_NEAR(w.pose(ball).position.y, 1 + r, 1e-5);  // resting on the top face
  // lifted 0.5 m: the next tick meets nothing
  w.set_pose(ball, {.position = {0.2, 1.5 + r, 0.1}});
  w.step();
  ASSERT_EQ(w.touch_end_events().size(), 1u);
  EXPECT_EQ(w.touch_end_events()[0].a, ball);
  EXPECT_EQ(w.touch_end_events()[0].b, box);
  EXPECT_TRUE(w.touch_begin_events().empty());
  // it falls back after sqrt(2 * 0.5 / g) = 0.32 s (38 ticks) at about sqrt(2 g 0.5) = 3.1 m/s
  int again = 0;
  double speed = 0;
  for (int n = 0; n < 60; ++n) {
    w.step();
    for (const pba::TouchBeginEvent& ev : w.touch_begin_events()) ++again, speed = ev.approach_speed;
  }
  EXPECT_EQ(again, 1);
  EXPECT_NEAR(speed, std::sqrt(2 * g * 0.5), g * dt);
}

// Particle entities meet every kind of collider entity: a plane, a sphere, a capsule, a hull
// (the generic point contact), a mesh and a dynamic rigid body's shape. The events name the
// collider's entity (the body's for its shape), come in pair order, and two runs give the
// same events in the same order; emitted particles landing on the same colliders add none.
struct Record {
  std::uint32_t a, b;
  double x;  // approach speed (begin) or -1 (end)
  int tick;
  bool operator==(const Record&) const = default;
};

std::vector<Record> many(int ticks, std::vector<EntityId>* colliders = nullptr) {
  World w;
  std::vector<EntityId> c;
  auto add = [&](const char* name, Vec3 at, const ColliderShape& s) {
    const EntityId e = w.create_entity({.name = name, .pose = {.position = at}});
    w.add_collider(e, {.shape = s, .material = {.restitution = 0.6, .friction = 0.2}});
    c.push_back(e);
  };
  add("ground", {0, 0, 0}, ColliderShape::plane({0, 1, 0}, 0));
  add("sphere", {-2, 0.5, 0}, ColliderShape::sphere(0.5));
  add("capsule", {0, 0.3, 0}, ColliderShape::capsule(0.6, 0.3));
  const std::vector<Vec3> tet{{-0.5, -0.5, -0.5}, {0.5, -0.5, -0.5}, {0, -0.5, 0.5}, {0, 0.5, 0}};
  add("hull", {2, 0.5, 0}, ColliderShape::convex(pba::ConvexHull::build(tet)));
  const std::vector<Vec3> quad{{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
  const std::vector<std::array<std::uint32_t, 3>> tris{{0, 2, 1}, {0, 3, 2}};
  add("mesh", {0, 0.8, 2}, ColliderShape::triangles(pba::TriangleMesh::build(quad, tris)));
  const EntityId crate = w.create_entity({.name = "crate", .pose = {.position = {0, 0.4, -2}}});
  w.add_rigid_body(crate, {.shapes = {{.shape = ColliderShape::box({0.4, 0.4, 0.4})}}});
  c.push_back(crate);
  // a rain of particle entities over each of them (from 1.1 m above its top), and a hose
  const Vec3 tops[] = {{1.5, 0, 1.5}, {-2, 1, 0}, {0, 0.9, 0}, {2, 1, 0}, {0, 0.8, 2}, {0, 0.8, -2}};
  for (int i = 0; i < 36; ++i) {
    const Vec3 top = tops[i / 6];
    const double dx = 0.07 * (i % 3) - 0.07, dz = 0.07 * ((i / 3) % 2) - 0.035;
    const EntityId p = w.create_entity({.pose = {.position = top + Vec3(dx, 1.1 + 0.05 * (i % 6), dz)}});
    w.add_particle(p, {.velocity = {0.3 * ((i % 3) - 1), 0, 0}, .radius = 0.04});
  }
  const EntityId hose = w.create_entity({.name = "hose", .pose = {.position = {0, 3, 0}}});
  w.add_emitter(hose, {.direction = {0, -1, 0}, .spread = 0.8, .rate = 400, .lifetime = 1.5});
  if (colliders) *colliders = c;
  std::vector<Record> out;
  for (int n = 1; n <= ticks; ++n) {
    w.step();
    for (const pba::TouchBeginEvent& ev : w.touch_begin_events()) out.push_back({ev.a.index, ev.b.index, ev.approach_speed, n});
    for (const pba::TouchEndEvent& ev : w.touch_end_events()) out.push_back({ev.a.index, ev.b.index, -1, n});
  }
  return out;
}

TEST(ParticleTouch, EveryColliderKindReportsInPairOrderTheSameEveryRun) {
  std::vector<EntityId> colliders;
  const std::vector<Record> one = many(240, &colliders), two = many(240);
  EXPECT_EQ(one, two);
  // which colliders the particle entities met (entity indices 6..41 are the particles, 42
  // the hose), and the order: by tick, begins then ends, each in (a, b) order
  std::vector<int> met(colliders.size(), 0);
  for (std::size_t k = 0; k < one.size(); ++k) {
    const Record& ev = one[k];
    EXPECT_LT(ev.a, ev.b);
    EXPECT_NE(ev.b, 42u);  // the emitter's particles report nothing
    for (std::size_t i = 0; i < colliders.size(); ++i)
      if (ev.a == colliders[i].index && ev.b >= 6 && ev.x >= 0) ++met[i];
    if (k > 0 && one[k - 1].tick == ev.tick && (one[k - 1].x >= 0) == (ev.x >= 0)) {
      EXPECT_LT((std::uint64_t{one[k - 1].a} << 32) | one[k - 1].b, (std::uint64_t{ev.a} << 32) | ev.b);
    }
  }
  for (std::size_t i = 0; i < colliders.size(); ++i) EXPECT_GT(met[i], 0) << "collider " << i;
}

// Recording contacts changes no bit of the physics: a system with recording on and one with
// it off end in the same state, on the fused kernel and on the generic path.
TEST(ParticleTouch, RecordingContactsChangesNoBit) {
  for (Method m : {Method::SemiImplicitEuler, Method::Rk4}) {
    std::uint64_t hashes[2];
    for (int on = 0; on < 2; ++on) {
      pba::ParticleSystem ps({.capacity = 2048, .method = m});
      ps.set_record_contacts(on == 1);
      for (int i = 0; i < 1500; ++i)
        ps.create({.position = {0.01 * (i % 40) - 0.2, 0.5 + 0.002 * i, 0.01 * (i / 40) - 0.2},
                   .velocity = {0.1, 0, 0}, .radius = 0.02});
      pba::CollisionWorld cw;
      cw.add(pba::Collider::plane({0, 1, 0}, 0, {.restitution = 0.7, .friction = 0.3}));
      pba::Collider ball = pba::Collider::sphere({0, 0.3, 0}, 0.2, {.restitution = 0.5});
      cw.add(ball);
      int contacts = 0;
      for (int n = 0; n < 300; ++n) {
        ps.step(n / 120.0, 1 / 120.0, cw, {});
        contacts += static_cast<int>(ps.contacts());
      }
      EXPECT_GT(contacts, 1000);
      hashes[on] = ps.hash();
    }
    EXPECT_EQ(hashes[0], hashes[1]) << pba::name(m);
  }
}

// What the system records per particle: the colliders met, in the order tested, nothing for
// anonymous particles; a stale handle is refused with an Error naming it.
TEST(ParticleTouch, ContactsPerParticleAndStaleHandles) {
  pba::ParticleSystem ps;
  const pba::ParticleId id = ps.create({.position = {0, 0.05, 0}, .radius = 0.05});
  ps.spawn({.position = {0.5, 0.05, 0}, .radius = 0.05});
  pba::CollisionWorld cw;
  cw.add(pba::Collider::plane({1, 0, 0}, -1));  // far: x >= -1
  cw.add(pba::Collider::plane({0, 1, 0}, 0));
  ps.step(0, 1 / 60.0, cw, {});
  EXPECT_TRUE(ps.contacts(id).empty());  // recording is off by default
  ps.set_record_contacts(true);
  ps.step(1 / 60.0, 1 / 60.0, cw, {});
  ASSERT_EQ(ps.contacts(id).size(), 1u);
  EXPECT_EQ(ps.contacts(id)[0].collider, 1u);
  EXPECT_EQ(ps.contacts(id)[0].normal, pba::Vec3f(0, 1, 0));
  // lifted: the next step meets nothing, and the last step's record is not reported
  ps.set_position(ps.index_of(id), {0, 2, 0});
  ps.step(2 / 60.0, 1 / 60.0, cw, {});
  EXPECT_TRUE(ps.contacts(id).empty());
  ps.destroy(id);
  EXPECT_NE(pba::test_support::error_of([&] { (void)ps.contacts(id); }).find("ParticleSystem::contacts"), std::string::npos);
}

// Destroying an entity while it touches ends its pairs silently (no event naming a dead
// entity), and the other particle's touch goes on.
TEST(ParticleTouch, DestroyedEntitiesEndTheirTouchesSilently) {
  World w;
  const EntityId ground = w.create_entity({.name = "ground"});
  w.add_collider(ground, {.shape = ColliderShape::plane({0, 1, 0}, 0)});
  const EntityId a = w.create_entity({.pose = {.position = {0, 0.05, 0}}});
  const EntityId b = w.create_entity({.pose = {.position = {1, 0.05, 0}}});
  w.add_particle(a, {.radius = 0.05});
  w.add_particle(b, {.radius = 0.05});
  w.step();
  ASSERT_EQ(w.touch_begin_events().size(), 2u);
  w.destroy_entity(a);
  for (int n = 0; n < 10; ++n) {
    w.step();
    EXPECT_TRUE(w.touch_begin_events().empty());
    EXPECT_TRUE(w.touch_end_events().empty());
  }
  // the ground goes: b falls, its touch ends silently too
  w.destroy_entity(ground);
  w.step();
  EXPECT_TRUE(w.touch_end_events().empty());
  EXPECT_LT(w.pose(b).position.y, 0.05);
}

// Steps w `ticks` times and returns the ticks (counted from 1) that reported a particle
// entity's one touch begin and end, -1 for none; a second of either fails the test. Each
// begin event is handed to check_begin (with w at the end of its tick); each end must be the
// particle `b`'s.
struct TouchTicks {
  int begin = -1, end = -1;
};
template <class CheckBegin>
TouchTicks one_touch(World& w, int ticks, EntityId b, CheckBegin check_begin) {
  TouchTicks t;
  for (int n = 1; n <= ticks; ++n) {
    w.step();
    for (const pba::TouchBeginEvent& ev : w.touch_begin_events()) {
      EXPECT_EQ(t.begin, -1) << "a second begin at tick " << n;
      t.begin = n;
      check_begin(ev);
    }
    for (const pba::TouchEndEvent& ev : w.touch_end_events()) {
      EXPECT_EQ(t.end, -1) << "a second end at tick " << n;
      t.end = n;
      EXPECT_EQ(ev.b, b);
    }
  }
  return t;
}

// A kinematic collider that runs into a particle at rest begins the touch at the tick the
// closed form gives, with its speed as the approach speed (the collider's velocity counts);
// an elastic hit sends the particle off at twice the collider's speed (the collider is
// infinitely heavy: v' = v_c + e (v_c - v_p) with e = 1, v_p = 0), so the touch ends the next
// tick. A sphere of radius R = 0.5 m from x0 = -2.05 m at v = 2 m/s meets a particle of
// radius r = 0.1 m at the origin when its centre reaches -(R + r): t = (2.05 - 0.6) / 2 =
// 0.725 s, inside tick 44 of 1/60 s (0.7167 to 0.7333 s).
TEST(ParticleTouch, AKinematicColliderBeginsATouchAtTheClosedFormTickWithItsSpeed) {
  const double dt = 1 / 60.0, v = 2, R = 0.5, r = 0.1, x0 = -2.05;
  World w({.stepper = {.fixed_dt = dt}, .gravity = {0, 0, 0}});
  const EntityId paddle = w.create_entity({.name = "paddle", .pose = {.position = {x0, 0, 0}}});
  w.add_collider(paddle, {.shape = ColliderShape::sphere(R), .material = {.restitution = 1, .friction = 0}});
  w.add_kinematic(paddle, {.path = pba::PathType::Linear, .velocity = {v, 0, 0}});
  const EntityId ball = w.create_entity({.name = "ball"});
  w.add_particle(ball, {.radius = r});
  const int expected = static_cast<int>(std::ceil((-x0 - (R + r)) / v / dt));
  ASSERT_EQ(expected, 44);
  const TouchTicks t = one_touch(w, 60, ball, [&](const pba::TouchBeginEvent& ev) {
    EXPECT_EQ(ev.a, paddle);
    EXPECT_EQ(ev.b, ball);
    EXPECT_NEAR(ev.normal.x, 1, 1e-6);
    EXPECT_NEAR(ev.approach_speed, v, 1e-5 * v);
  });
  EXPECT_EQ(t.begin, expected);
  EXPECT_EQ(t.end, expected + 1);
  // and the ball flies off at 2 v (float state: 1e-5 relative)
  EXPECT_NEAR(w.velocity(ball).x, 2 * v, 1e-5 * v);
}

// A particle that meets more than kMaxParticleContacts colliders in one step records the
// first ones tested, in collider order (the World's touch events come from these records,
// so a seventh wall would not be reported either); the response still meets every wall.
TEST(ParticleTouch, AParticleMeetingSixWallsRecordsTheFirstFour) {
  pba::ParticleSystem ps({.forces = {.gravity = {0, 0, 0}}});
  ps.set_record_contacts(true);
  const pba::ParticleId id = ps.create({.position = {0, 0, 0}, .radius = 0.1});
  pba::CollisionWorld cw;
  // a 0.19 m box of walls around a 0.2 m ball: each wall 5 mm into it
  for (int axis = 0; axis < 3; ++axis)
    for (double s : {1.0, -1.0}) {
      Vec3 n(0.0);
      n[axis] = s;
      cw.add(pba::Collider::plane(n, -0.095));
    }
  ps.step(0, 1 / 60.0, cw, {});
  const auto got = ps.contacts(id);
  ASSERT_EQ(got.size(), pba::kMaxParticleContacts);
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].collider, i);
  EXPECT_GE(ps.contacts(), 4u);
}

// A particle entity on a path touches where the path puts it, not where the particle stage
// would have taken it. A particle of radius r = 0.05 m at 10 m/s (dt = 0.01 s: 0.1 m a
// tick) toward a slab whose faces are at x = 1 and 1.2 m is within r of it from tick 10 (x =
// 1.0) to tick 12 (x = 1.2, its far face), so the touch begins at tick 10, at the slab's near
// face with the path's speed, and ends at tick 13 (x = 1.3, 0.1 m past it). Before the fix
// the particle stage had integrated it a tick on (and met the slab there): the touch began
// at tick 9, with the particle 5 cm short of the slab.
TEST(ParticleTouch, AParticleOnAPathTouchesWhereThePathPutsIt) {
  const double r = 0.05;
  World w({.stepper = {.fixed_dt = 0.01}});
  const EntityId slab = w.create_entity({.name = "slab", .pose = {.position = {1.1, 0, 0}}});
  w.add_collider(slab, {.shape = ColliderShape::box({0.1, 1, 1})});
  const EntityId p = w.create_entity({.name = "runner"});
  w.add_particle(p, {.radius = r});
  w.add_kinematic(p, {.path = pba::PathType::Linear, .velocity = {10, 0, 0}});
  const TouchTicks t = one_touch(w, 20, p, [&](const pba::TouchBeginEvent& ev) {
    EXPECT_EQ(ev.a, slab);
    EXPECT_EQ(ev.b, p);
    EXPECT_LE(1 - w.pose(p).position.x, r) << "began touching short of the slab";
    EXPECT_NEAR(ev.normal.x, -1, 1e-6);  // out of the near face, toward the particle
    EXPECT_NEAR(ev.point.x, 1, 1e-6);
    EXPECT_NEAR(ev.approach_speed, 10, 1e-5);
  });
  EXPECT_EQ(t.begin, 10);
  EXPECT_EQ(t.end, 13);
}

// A particle held still by a motor path 1 mm above the ground (radius 0.05 m, centre at
// 0.051 m) never touches it, though gravity pulls the particle stage's copy into it each
// tick (before the fix it touched from tick 1 for good); 1 mm into the ground (0.049 m) it
// touches from tick 1 and never stops, at approach speed 0 (it is not moving).
TEST(ParticleTouch, AParticleHeldByAMotorTouchesOnlyWithinItsRadius) {
  for (const double y : {0.051, 0.049}) {
    SCOPED_TRACE(y);
    World w({.stepper = {.fixed_dt = 1 / 60.0}});
    const EntityId ground = w.create_entity({.name = "ground"});
    w.add_collider(ground, {.shape = ColliderShape::plane({0, 1, 0}, 0)});
    const EntityId p = w.create_entity({.name = "hover", .pose = {.position = {0, y, 0}}});
    w.add_particle(p, {.radius = 0.05});
    w.add_kinematic(p, {.path = pba::PathType::Motor});
    int begins = 0, ends = 0;
    for (int n = 1; n <= 30; ++n) {
      w.step();
      for (const pba::TouchBeginEvent& ev : w.touch_begin_events()) {
        ++begins;
        EXPECT_EQ(n, 1);
        EXPECT_EQ(ev.a, ground);
        EXPECT_NEAR(ev.normal.y, 1, 1e-12);
        EXPECT_EQ(ev.approach_speed, 0);
      }
      ends += static_cast<int>(w.touch_end_events().size());
    }
    EXPECT_NEAR(w.pose(p).position.y, y, 1e-7);
    EXPECT_EQ(begins, y > 0.05 ? 0 : 1);
    EXPECT_EQ(ends, 0);
  }
}

}  // namespace
