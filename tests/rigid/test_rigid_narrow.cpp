// The rigid contacts' narrow phase without collide()'s input checks (collide_unchecked_into,
// src/collide/narrow_internal.h): for valid input, every closed-form and polygon pair the
// rigid bodies make gives collide()'s manifold and cache to the bit.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "collide/narrow_internal.h"
#include "pba/collide/narrow_phase.h"
#include "pba/core.h"
#include "pba/rigid.h"

using namespace pba;

namespace {

Quat random_turn(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0, 1);
  return glm::normalize(Quat(g(rng), g(rng), g(rng), g(rng)));
}

ColliderShape random_shape(std::mt19937_64& rng, int type) {
  std::uniform_real_distribution<double> size(0.1, 0.6);
  switch (type) {
    case 0: return ColliderShape::sphere(size(rng));
    case 1: return ColliderShape::box(Vec3(size(rng), size(rng), size(rng)));
    case 2: return ColliderShape::capsule(size(rng), size(rng));
    default: return ColliderShape::plane(glm::normalize(Vec3(0.2, 1, -0.1)), 0.05);
  }
}

}  // namespace

TEST(RigidNarrow, UncheckedIntoGivesCollidesManifoldAndCache) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> at(-0.8, 0.8), margin(0, 0.05);
  int touching = 0;
  for (int i = 0; i < 6000; ++i) {
    const int ta = static_cast<int>(rng() % 4), tb = static_cast<int>(rng() % 3);  // (no plane-plane)
    const bool swap = rng() % 2 == 1;
    const ColliderShape a = random_shape(rng, swap ? tb : ta), b = random_shape(rng, swap ? ta : tb);
    const Pose pa{Vec3(at(rng), at(rng), at(rng)), random_turn(rng)};
    const Pose pb{Vec3(at(rng), at(rng), at(rng)), random_turn(rng)};
    const NarrowPhaseSettings settings{.speculative_margin = margin(rng)};
    NarrowPhaseCache cache_ref{}, cache{};
    const Manifold ref = collide(a, pa, b, pb, settings, &cache_ref);
    Manifold m;
    std::memset(static_cast<void*>(&m), 0x5a, sizeof m);  // (what the scratch held before)
    narrow::collide_unchecked_into(a, pa, b, pb, settings, &cache, m);
    ASSERT_EQ(m.count, ref.count) << i;
    ASSERT_EQ(m.sub_shape_b, ref.sub_shape_b) << i;
    // (field by field: SatCache's padding bytes are whatever each copy left there)
    ASSERT_EQ(cache.sat.kind, cache_ref.sat.kind) << i;
    ASSERT_EQ(cache.sat.index_a, cache_ref.sat.index_a) << i;
    ASSERT_EQ(cache.sat.index_b, cache_ref.sat.index_b) << i;
    if (ref.count == 0) continue;
    ++touching;
    ASSERT_EQ(std::memcmp(&m.normal, &ref.normal, sizeof m.normal), 0) << i;
    for (int k = 0; k < ref.count; ++k) {
      const ContactPoint &p = m.points[static_cast<std::size_t>(k)], &q = ref.points[static_cast<std::size_t>(k)];
      ASSERT_EQ(std::memcmp(&p.point_a, &q.point_a, sizeof(Vec3)), 0) << i;
      ASSERT_EQ(std::memcmp(&p.point_b, &q.point_b, sizeof(Vec3)), 0) << i;
      ASSERT_EQ(std::memcmp(&p.depth, &q.depth, sizeof(double)), 0) << i;
      ASSERT_EQ(p.id, q.id) << i;
    }
  }
  EXPECT_GT(touching, 1000);
}

TEST(RigidNarrow, UncheckedIntoStillThrowsForAPairWithoutANarrowPhase) {
  const ColliderShape plane = ColliderShape::plane(Vec3(0, 1, 0), 0);
  Manifold m;
  EXPECT_THROW(narrow::collide_unchecked_into(plane, Pose{}, plane, Pose{}, NarrowPhaseSettings{}, nullptr, m), Error);
}

// The contacts take a body's plane as it is, so a plane whose normal is not unit (the shape's
// fields set by hand: ColliderShape::plane() normalises) is refused when the body is made,
// naming the body and the normal, not used with its depths scaled by |n|.
TEST(RigidNarrow, ABodysPlaneWithANonUnitNormalIsRefusedWhenMade) {
  RigidBodySystem s;
  ColliderShape plane = ColliderShape::plane(Vec3(0, 1, 0), 0);
  plane.normal = Vec3(0, 2, 0);
  try {
    s.create({.name = "floor", .type = BodyType::Static, .shapes = {{.shape = plane}}});
    FAIL() << "a plane of normal (0, 2, 0) was taken";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("floor"), std::string::npos) << what;
    EXPECT_NE(what.find("normal must be unit"), std::string::npos) << what;
    EXPECT_NE(what.find("length 2"), std::string::npos) << what;
  }
  EXPECT_EQ(s.size(), 0u);
  plane.normal = Vec3(0, 1, 0);
  EXPECT_NO_THROW(s.create({.name = "floor", .type = BodyType::Static, .shapes = {{.shape = plane}}}));
}
