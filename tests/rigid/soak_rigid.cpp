// Rigid-body soaks (release build only: label soak): the full-size scenes.
#include <gtest/gtest.h>

#include <cmath>

#include "pba/rigid.h"
#include "pba/rigid_scenes.h"

using pba::RigidBodySystem;
using pba::RigidSolverType;
using pba::Vec3;

namespace {

// 5000 boxes and spheres of 0.5 m at 250 m/s in a closed box of 20 m with 0.2 m walls:
// none escapes (its centre never crosses a wall's middle plane), under either solver.
TEST(RigidSoak, FiveThousandBodiesAt250MetresPerSecondStayInAClosedBox) {
  const double inner = 10, wall = 0.2;
  for (const RigidSolverType solver : {RigidSolverType::SoftStep, RigidSolverType::SequentialImpulse}) {
    RigidBodySystem s({.capacity = 5006, .contacts = {.solver = solver}});
    const auto bodies = pba::rigid_scenes::closed_box(s, 5000, 250.0, inner, wall);
    int escaped = 0;
    double worst = 0;
    for (int step = 0; step < 60; ++step) {
      s.step(1.0 / 60, Vec3(0, -9.81, 0));
      for (const auto b : bodies) {
        const Vec3 c = s.center_of_mass(b);
        const double m = std::max(std::abs(c.x), std::max(std::abs(c.y), std::abs(c.z)));
        worst = std::max(worst, m);
        escaped += m >= inner + 0.5 * wall;
      }
    }
    EXPECT_EQ(escaped, 0) << to_string(solver) << ": farthest centre " << worst;
  }
}

}  // namespace
