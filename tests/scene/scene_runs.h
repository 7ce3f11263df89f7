// The shipped scene files and a run of one, for the scene tests and the scene soak.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "pba/scene.h"

// the shipped scenes (scenes/*.json), sorted by name
inline std::vector<std::filesystem::path> example_scenes() {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(PBA_SCENES_DIR))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

// run a scene for n ticks and return its hash (World::step throws on a non-finite state)
inline std::uint64_t run(const std::filesystem::path& file, long long n) {
  pba::Scene s = pba::load_scene(file);
  for (long long i = 0; i < n; ++i) s.world.step();
  EXPECT_EQ(s.world.ticks(), n);
  return s.world.hash();
}
