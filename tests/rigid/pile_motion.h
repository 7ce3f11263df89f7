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
/// sleep_angular): what keeps the soft step's halving from counting its calm (columns.cpp).
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

}  // namespace pba::test
