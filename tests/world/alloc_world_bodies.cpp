// The World's memory over rounds of bodies made and destroyed, counted in the bytes a
// replaced operator new hands out and takes back: the C heap's own statistics (mallinfo2)
// read 0 under the sanitizers' allocators, where a test of them could not fail.
#include <gtest/gtest.h>

#include "pba/world.h"

#include "alloc_count.h"

using pba::test_support::g_live_bytes;

// A body destroyed in rigid() directly was never subtracted from the World's count of entity
// bodies, and a new body on the same entity added to it: the count grew with every such round
// and sized the touch sets' room (8 touch records a body, in six sets), so 1e5 rounds on one
// entity held hundreds of MB. Both ways of destroying keep the count, and the memory, bounded.
TEST(WorldBodiesMemory, BodiesDestroyedEitherWayKeepTheWorldsMemoryBounded) {
  pba::World w;
  const pba::EntityId g = w.create_entity({.name = "ground"});
  w.add_collider(g, {.shape = pba::ColliderShape::plane({0, 1, 0}, 0)});
  const pba::EntityId e = w.create_entity({.name = "crate"});
  pba::RigidBodyDef d;
  d.shapes = {{.shape = pba::ColliderShape::box({0.5, 0.5, 0.5})}};
  auto rounds = [&](int n) {
    for (int i = 0; i < n; ++i) {
      // through rigid() directly, then through the World
      w.rigid().destroy(w.add_rigid_body(e, d));
      const pba::EntityId f = w.create_entity({});
      w.add_rigid_body(f, d);
      w.destroy_entity(f);
    }
    w.step();
  };
  rounds(100);  // warm: the sets' room for the bodies that exist at once
  const long long before = g_live_bytes.load();
  EXPECT_GT(before, 0);  // the World's own blocks are counted
  rounds(100000);
  const long long after = g_live_bytes.load();
  EXPECT_LT(after, before + (1 << 20)) << "the World's blocks grew from " << before << " to " << after << " bytes";
  EXPECT_EQ(w.entity_count(), 2u);
  EXPECT_TRUE(w.rigid_body_id(e).is_null());
}
