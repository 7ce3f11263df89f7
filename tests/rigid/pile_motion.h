// How far a pile's bodies moved from where they were built and how fast they move (tests of
// piles that must stand: test_rigid_contact.cpp, soak_rigid.cpp).
#pragma once

#include <algorithm>
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

}  // namespace pba::test
