// Memory limits and emission cost: inputs that cannot fit a particle system's memory
// budget are refused before anything is allocated, naming the field and the memory; an
// emitter's cost is that of the particles it emits, not of those due.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>

#include "error_of.h"
#include "pba/particles.h"

namespace {

using pba::ParticleSystem;
using pba::test_support::error_of;

constexpr std::size_t kMiB = std::size_t{1} << 20;

TEST(MemoryLimits, CapacityBeyondTheBudgetIsRefusedBeforeAllocating) {
  // 2^28 particles at 256 B are 64 GiB, 16 times the default budget (before: bad_alloc)
  EXPECT_EQ(error_of([] { ParticleSystem ps({.capacity = std::size_t{1} << 28}); }),
            "ParticleSystemDef.capacity: 268435456 particles would take 64 GiB (256 B each), over the particle "
            "system's memory budget of 4 GiB (ParticleSystemDef.memory_budget)");
  // the default budget holds 2^24 particles; one more is refused (nothing is allocated)
  EXPECT_EQ(pba::kParticleMemoryBudget / pba::kParticleBytes, std::size_t{1} << 24);
  EXPECT_NE(error_of([] { ParticleSystem ps({.capacity = (std::size_t{1} << 24) + 1}); }), "");
  // a smaller budget: exactly budget / 256 particles fit
  EXPECT_EQ(error_of([] { ParticleSystem ps({.capacity = 4096, .memory_budget = kMiB}); }), "");
  EXPECT_NE(error_of([] { ParticleSystem ps({.capacity = 4097, .memory_budget = kMiB}); })
                .find("4097 particles would take 1 MiB (256 B each), over the particle system's memory budget of 1 MiB"),
            std::string::npos);
  EXPECT_NE(error_of([] { ParticleSystem ps({.memory_budget = 100}); }).find("ParticleSystemDef.memory_budget"),
            std::string::npos);
}

TEST(MemoryLimits, GrowthStopsAtTheBudget) {
  ParticleSystem ps({.capacity = 16, .memory_budget = kMiB});
  EXPECT_EQ(ps.max_particles(), 4096u);
  for (int i = 0; i < 4096; ++i) ps.spawn({});
  EXPECT_EQ(ps.size(), 4096u);
  EXPECT_EQ(ps.capacity(), 4096u);  // grown by doubling, clamped at the budget
  EXPECT_NE(error_of([&] { ps.spawn({}); }).find("ParticleSystem: adding a particle: 4097 particles would take"),
            std::string::npos);
  EXPECT_EQ(ps.size(), 4096u);
}

TEST(MemoryLimits, AnUncappedEmitterThatCannotFitIsRefusedAtCreation) {
  ParticleSystem ps;
  // before: accepted, and the first step ended in std::bad_alloc
  const std::string m = error_of([&] { ps.add_emitter({.rate = 1e12, .lifetime = 2}, "sparks"); });
  EXPECT_EQ(m,
            "sparks.rate: 2000000000000 particles would take 466 TiB (256 B each), over the particle system's memory "
            "budget of 4 GiB (ParticleSystemDef.memory_budget); it emits 1e+12 particles/s that live up to 2 s: "
            "lower the rate or the lifetime, or set max_alive");
  EXPECT_EQ(ps.emitter_count(), 0u);
  // a cap that cannot fit names max_alive
  EXPECT_NE(error_of([&] { ps.add_emitter({.rate = 1e12, .max_alive = std::size_t{1} << 28}, "sparks"); })
                .find("sparks.max_alive: 268435456 particles would take 64 GiB"),
            std::string::npos);
  // a rate raised between steps is refused at the step
  const pba::EmitterId id = ps.add_emitter({.rate = 100});
  ps.step(0, 0.01, {}, {});
  ps.emitter(id).rate = 1e12;
  EXPECT_NE(error_of([&] { ps.step(0.01, 0.01, {}, {}); }).find("emitter.rate: 2000000000000 particles would take"),
            std::string::npos);
}

TEST(MemoryLimits, AStepLongerThanTheLifetimesCannotOverfillTheBudget) {
  // 1000 live at most in steady state, but a 100 s step brings 10^8 due at once
  ParticleSystem ps({.memory_budget = kMiB});
  ps.add_emitter({.rate = 1e6, .lifetime = 1e-3});
  EXPECT_NE(error_of([&] { ps.step(0, 100, {}, {}); }).find("emitter.rate: 100000000 particles would take"),
            std::string::npos);
}

// max_alive with a rate of 1e12: before, emission looped over every due particle (1.7e10
// per step of 1/60 s, skipping them one by one: minutes per step); now the particles due
// while the emitter is full are skipped as a count, and a step costs the particles emitted
TEST(EmitterCost, ACappedEmitterCostsWhatItEmits) {
  ParticleSystem ps;
  const pba::EmitterId id = ps.add_emitter({.rate = 1e12, .lifetime = 0.05, .max_alive = 1000});
  const auto start = std::chrono::steady_clock::now();
  const double h = 1.0 / 60;
  for (int i = 0; i < 120; ++i) {
    ps.step(i * h, h, {}, {});
    ASSERT_EQ(ps.size(), 1000u) << i;  // the cap refills every step: the 0.05 s lives end within 3 steps
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // 120 steps of at most 1000 emissions each take milliseconds; the old loop needed at
  // least 120 * 1.7e10 iterations (over half an hour at one per nanosecond). 10 s is a
  // bound no loaded machine reaches with the new code and none passes with the old.
  EXPECT_LT(seconds, 10.0);
  // every 0.05 s life ends by the 4th step after its birth, so the cap refilled 1000 per
  // lifetime: at least 120 / 4 refills
  EXPECT_GE(ps.emitted(id), 30 * 1000);
}

// the particles a capped emitter emits are the first ones due, with the same draws from
// its stream as an uncapped emitter's: capped, the first step's particles are bit for bit
// the first ones of the uncapped emitter
TEST(EmitterCost, CappedEmissionIsTheUncappedStreamCutShort) {
  const pba::EmitterDef def{.spread = 0.8, .speed_jitter = 0.3, .rate = 6000, .lifetime = 5, .lifetime_jitter = 0.4};
  ParticleSystem capped, uncapped;
  pba::EmitterDef cut = def;
  cut.max_alive = 37;
  capped.add_emitter(cut);
  uncapped.add_emitter(def);
  const double h = 1.0 / 60;
  capped.step(0, h, {}, {});
  uncapped.step(0, h, {}, {});
  ASSERT_EQ(capped.size(), 37u);
  ASSERT_EQ(uncapped.size(), 100u);
  for (std::size_t i = 0; i < 37; ++i) {
    EXPECT_EQ(capped.position(i), uncapped.position(i)) << i;
    EXPECT_EQ(capped.velocity(i), uncapped.velocity(i)) << i;
    EXPECT_EQ(capped.lifetime(i), uncapped.lifetime(i)) << i;
  }
  // full, it stays full: nothing dies within the 3 to 7 s lifetimes
  for (int i = 1; i < 60; ++i) capped.step(i * h, h, {}, {});
  EXPECT_EQ(capped.size(), 37u);
}

}  // namespace
