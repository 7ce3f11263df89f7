// Tests for pba/handle.h: which handles a pool names stale and which never issued, at both
// ends of a slot's generations.
#include <gtest/gtest.h>

#include <string>

#include "error_of.h"
#include "pba/handle.h"

namespace {

using pba::test_support::error_of;

struct TestTag {};
using Pool = pba::HandlePool<TestTag>;
using Id = Pool::Id;

// A freed slot's generation is bumped at destroy, and that generation is issued only when the
// slot is reused: until then a handle holding it was never issued here (another pool's), not
// stale. The generations the slot did issue (1) read stale; 0 and those beyond read never issued.
TEST(HandlePool, AFreeSlotsOwnGenerationWasNeverIssued) {
  Pool p;
  const Id a = p.create();
  p.destroy(a, "destroy");
  ASSERT_EQ(p.generation(a.index), 2u);
  EXPECT_EQ(error_of([&] { p.require(Id{0, 2}, "use"); }),
            "use: invalid handle (index 0 at generation 2 was never issued here, the slot is at generation 2 and "
            "free: a handle of another World or system)");
  EXPECT_EQ(error_of([&] { p.require(a, "use"); }),
            "use: stale handle (index 0, generation 1; the slot is now at generation 2 and free): destroyed since, "
            "or a handle of another World or system");
  EXPECT_EQ(error_of([&] { p.require(Id{0, 0}, "use"); }),
            "use: invalid handle (index 0 at generation 0 was never issued here, the slot is at generation 2 and "
            "free: a handle of another World or system)");
  EXPECT_EQ(error_of([&] { p.require(Id{0, 3}, "use"); }),
            "use: invalid handle (index 0 at generation 3 was never issued here, the slot is at generation 2 and "
            "free: a handle of another World or system)");
  // reused, the slot issues generation 2: valid now, and generation 1 is stale
  const Id b = p.create();
  EXPECT_EQ(b, (Id{0, 2}));
  EXPECT_TRUE(p.valid(b));
  EXPECT_EQ(error_of([&] { p.require(a, "use"); }),
            "use: stale handle (index 0, generation 1; the slot is now at generation 2): destroyed since, or a "
            "handle of another World or system");
  EXPECT_EQ(error_of([&] { p.require(Id{0, 3}, "use"); }),
            "use: invalid handle (index 0 at generation 3 was never issued here, the slot is at generation 2: a "
            "handle of another World or system)");
}

// A slot that issued its last generation retires instead of wrapping around to a generation a
// kept handle may hold: every handle it issued stays stale for good, and the pool grows a slot.
// (Before, generation 2^32 - 1 wrapped to 1: after 2^32 - 1 reuses the first handle of the slot
// named its newest object, and the ones in between read "never issued here".)
TEST(HandlePool, ASlotRetiresAfterItsLastGenerationAndNeverWrapsAround) {
  pba::HandlePool<TestTag, 3> p;
  Id ids[3];
  for (std::uint32_t g = 1; g <= 3; ++g) {
    ids[g - 1] = p.create();
    EXPECT_EQ(ids[g - 1], (Id{0, g}));
    p.destroy(ids[g - 1], "destroy");
  }
  EXPECT_EQ(p.size(), 0u);
  // the slot is not reused: the next handle takes a new one
  const Id next = p.create();
  EXPECT_EQ(next, (Id{1, 1}));
  EXPECT_EQ(p.slots(), 2u);
  for (const Id& old : ids) {
    EXPECT_FALSE(p.valid(old));
    EXPECT_EQ(error_of([&] { p.require(old, "use"); }),
              "use: stale handle (index 0, generation " + std::to_string(old.generation) +
                  "; the slot is retired, its generations used up): destroyed since, or a handle of another World "
                  "or system");
  }
  EXPECT_EQ(error_of([&] { p.require(Id{0, 4}, "use"); }),
            "use: invalid handle (index 0 at generation 4 was never issued here, the slot is at generation 3: a "
            "handle of another World or system)");
  EXPECT_NE(error_of([&] { p.destroy(ids[2], "destroy"); }).find("destroy: stale handle"), std::string::npos);
  // a retired slot is never handed out again, however many handles come and go (each new
  // slot retires in its turn after three)
  for (int k = 0; k < 10; ++k) {
    const Id h = p.create();
    EXPECT_NE(h.index, 0u);
    p.destroy(h, "destroy");
  }
  EXPECT_EQ(p.slots(), 6u);  // slot 1 live, 2, 3 and 4 retired, 5 free at generation 2
  EXPECT_FALSE(p.valid(ids[0]));
}

// The slot table ends before the null handle's index: with every slot live or retired,
// create() throws instead of appending a slot at index kMaxSlots. At the default, 0xFFFFFFFF
// slots, the next index was the null handle's 0xFFFFFFFF, handed out as a live handle that
// read as null (is_null) and as "never issued" to require. The pool's third parameter
// reaches the end in three slots; a freed slot is still reused, and the pool is unchanged by
// the refusal.
TEST(HandlePool, APoolWhoseSlotsAreUsedUpRefusesInsteadOfIssuingTheNullIndex) {
  pba::HandlePool<TestTag, 2, 3> p;
  const Id a = p.create(), b = p.create(), c = p.create();
  EXPECT_EQ(c, (Id{2, 1}));
  const std::string full =
      "HandlePool::create: every one of the 3 slots is live or retired (3 live): index 3 is past the last, 2";
  EXPECT_EQ(error_of([&] { p.create(); }), full);
  EXPECT_EQ(p.size(), 3u);
  EXPECT_EQ(p.slots(), 3u);
  // a freed slot is reused, at its next generation; once it retires the pool is full again
  p.destroy(b, "destroy");
  const Id b2 = p.create();
  EXPECT_EQ(b2, (Id{1, 2}));
  p.destroy(b2, "destroy");  // generation 2 is the last: slot 1 retires
  EXPECT_EQ(error_of([&] { p.create(); }),
            "HandlePool::create: every one of the 3 slots is live or retired (2 live): index 3 is past the last, 2");
  EXPECT_TRUE(p.valid(a));
  EXPECT_TRUE(p.valid(c));
  // the default pool's last slot index is one below the null handle's
  static_assert(Id::kNullIndex == 0xFFFFFFFFu);
}

// The full 32-bit pool: generation 1 is the first, a handle of a full slot table's last index
// is refused by index, and the null handle by name.
TEST(HandlePool, TheNullHandleAndIndicesBeyondTheTableAreNamed) {
  Pool p;
  const Id a = p.create();
  EXPECT_EQ(a, (Id{0, 1}));
  EXPECT_EQ(error_of([&] { p.require(Id{}, "use"); }), "use: null handle");
  EXPECT_EQ(error_of([&] { p.require(Id{Id::kNullIndex - 1, 1}, "use"); }),
            "use: invalid handle (index 4294967294 was never issued here: a handle of another World or system)");
}

}  // namespace
