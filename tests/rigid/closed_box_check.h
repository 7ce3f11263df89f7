// The tunnelling check shared by the unit and soak suites (test_rigid_continuous.cpp,
// soak_rigid.cpp).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "pba/rigid.h"
#include "pba/rigid_scenes.h"

namespace pba::test {

// The tunnelling scene: boxes and spheres of 0.5 m at 250 m/s (4.2 m per 60 Hz step, twenty
// times a wall's 0.2 m thickness) in a closed box. A body escapes when its centre crosses a
// wall's middle plane: from there the wall's contact pushes it out the other side. Without
// the continuous pass hundreds get out in the first steps. `n` bodies in a box of half size
// `inner` (m), 60 steps of 60 Hz, under every solver, at `speed` (m/s).
inline void expect_none_escapes(int n, double inner, double speed = 250.0) {
  const double wall = 0.2;
  for (const pba::RigidSolverType solver : pba::kRigidSolvers) {
    pba::RigidBodySystem s({.capacity = static_cast<std::size_t>(n) + 6, .contacts = {.solver = solver}});
    const auto bodies = pba::rigid_scenes::closed_box(s, n, speed, inner, wall);
    int escaped = 0;
    double worst = 0;
    for (int step = 0; step < 60; ++step) {
      s.step(1.0 / 60, pba::Vec3(0, -9.81, 0));
      for (const auto b : bodies) {
        const pba::Vec3 c = s.center_of_mass(b);
        const double m = std::max(std::abs(c.x), std::max(std::abs(c.y), std::abs(c.z)));
        worst = std::max(worst, m);
        escaped += m >= inner + 0.5 * wall;
      }
    }
    EXPECT_EQ(escaped, 0) << to_string(solver) << " at " << speed << " m/s: farthest centre " << worst;
  }
}

}  // namespace pba::test
