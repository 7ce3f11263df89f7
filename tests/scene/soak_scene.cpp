// The shipped scenes over 10^5 ticks (28 minutes of simulated time at 60 Hz): no non-finite
// state (World::step throws, naming the object and the time) and the same hash twice.
// Release only: the sanitizer presets exclude the soak label.
#include <gtest/gtest.h>

#include "scene_runs.h"

namespace {

TEST(ExampleScenesSoak, HundredThousandStepsNoNaNSameHashTwice) {
  for (const auto& file : example_scenes()) {
    SCOPED_TRACE(file.string());
    const std::uint64_t a = run(file, 100000);
    EXPECT_EQ(a, run(file, 100000));
  }
}

}  // namespace
