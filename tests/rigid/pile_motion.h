// How far a pile's bodies moved from where they were built and how fast they move (tests of
// piles that must stand: test_rigid_contact.cpp, soak_rigid.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "pba/rigid.h"

namespace pba::test {

/// The most any of `bodies` moved from `start` (its centre of mass there, m) and the fastest
/// of their centres' speeds now (m/s).
struct PileMotion {
  double moved = 0, fastest = 0;
};

inline PileMotion pile_motion(const RigidBodySystem& s, const std::vector<RigidBodyId>& bodies,
                              const std::vector<Vec3>& start) {
  PileMotion m;
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    m.moved = std::max(m.moved, glm::length(s.center_of_mass(bodies[k]) - start[k]));
    m.fastest = std::max(m.fastest, glm::length(s.linear_velocity(bodies[k])));
  }
  return m;
}

/// Whether any of `bodies` moves at or over the sleep tolerances (ContactSettings::sleep_linear,
/// sleep_angular): what keeps the soft step's halving from counting its calm (columns.cpp's
/// still(), over every awake dynamic body). Read here through the public API over the pile's
/// bodies on purpose: the tests' own statement of the rule, which the library's is checked by.
inline bool any_unsettled(const RigidBodySystem& s, const std::vector<RigidBodyId>& bodies) {
  const double v = s.settings().sleep_linear, w = s.settings().sleep_angular;
  for (const RigidBodyId b : bodies) {
    const Vec3 lv = s.linear_velocity(b), av = s.angular_velocity(b);
    if (glm::dot(lv, lv) >= v * v || glm::dot(av, av) >= w * w) return true;
  }
  return false;
}

/// The step at which the soft step's halving comes to a pile built at step 0 whose bodies
/// last moved at or over the sleep tolerances in step `last_unsettled` (-1: never), its pairs
/// the same from then on: its calm (columns.cpp, kCalmTime: 1 s) counts from the second step
/// after (the first starts on that motion) and not in the first step (its pairs are new), and
/// it halves in the step that completes 1 s, the 60th at 60 Hz: the calm is a sum of the
/// steps' dt, so the step is counted as the sum is made (120 steps of 1/120 s sum to just under
/// 1 s and the 121st completes it).
inline int halving_step(int last_unsettled, double dt = 1.0 / 60) {
  int more = 0;
  for (double calm = dt; calm < 1; calm += dt) ++more;
  return std::max(1, last_unsettled + 2) + more;
}

/// The step at which the soft step takes the next rung down (4 -> 3 at the defaults) after
/// taking a rung in step `taken`, the pile's bodies having last moved at or over the sleep
/// tolerances in step `last_unsettled` (-1 or before `taken`: not since), its pairs the same:
/// the calm starts again in the step a rung is taken and counts from the step after it, or
/// from the second step after the last motion, whichever is later (halving_step's rule).
inline int next_rung_step(int taken, int last_unsettled, double dt = 1.0 / 60) {
  return halving_step(std::max(last_unsettled, taken - 1), dt);
}

/// The soft step's lowering over a run from a pile's building (8 -> 4 -> 3 at the defaults):
/// the step each rung was first taken and the last step before it in which a body moved at or
/// over the sleep tolerances, for halving_step and next_rung_step.
struct Lowering {
  int halved = -1, third = -1;              // the first step at 4 and at 3 substeps after it (-1: none)
  int unsettled = -1, unsettled_at_4 = -1;  // the last step with a body moving before each (-1: none)
  void record(int step, int substeps, bool moving) {
    if (halved < 0 && substeps == 4) halved = step;
    if (halved >= 0 && third < 0 && substeps == 3) third = step;
    if (halved < 0 && moving) unsettled = step;
    if (halved >= 0 && third < 0 && moving) unsettled_at_4 = step;
  }
};

}  // namespace pba::test
