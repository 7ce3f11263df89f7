// Rigid-body soaks (release build only: label soak): the full-size scenes.
#include <gtest/gtest.h>

#include "closed_box_check.h"

namespace {

// 5000 boxes and spheres of 0.5 m at 250 m/s in a closed box of 20 m with 0.2 m walls:
// none escapes (its centre never crosses a wall's middle plane), under every solver.
TEST(RigidSoak, FiveThousandBodiesAt250MetresPerSecondStayInAClosedBox) { pba::test::expect_none_escapes(5000, 10); }

}  // namespace
