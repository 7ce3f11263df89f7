// `pba run`: bad flags exit 2 with a message, bad scenes exit 1, a run writes the CSV it
// promises and prints the same hash as the World it ran.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "commands_run.h"
#include "pba/scene.h"

namespace {

int run(std::vector<std::string> words) {
  // argv[0] is the subcommand name
  words.insert(words.begin(), "run");
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  return pba_run_command(static_cast<int>(argv.size()), argv.data());
}

const std::string kScene = std::string(PBA_SCENES_DIR) + "/bouncing_balls.json";

TEST(RunCommand, BadFlagsExitTwo) {
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({kScene, "--steps", "-3"}), 2);
  EXPECT_EQ(run({kScene, "--steps", "ten"}), 2);
  EXPECT_EQ(run({kScene, "--steps"}), 2);
  EXPECT_EQ(run({kScene, "--every", "0"}), 2);
  EXPECT_EQ(run({kScene, "--frobnicate"}), 2);
  EXPECT_EQ(run({kScene, "--method", "leapfrog"}), 2);
  EXPECT_EQ(run({}), 2);
  EXPECT_EQ(run({kScene, kScene}), 2);
  EXPECT_EQ(run({"--builder", "nope"}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("--steps: must be in [1, 1000000000], got -3"), std::string::npos) << err;
  EXPECT_NE(err.find("--steps: expected an integer, got 'ten'"), std::string::npos) << err;
  EXPECT_NE(err.find("unknown flag '--frobnicate'"), std::string::npos) << err;
  EXPECT_NE(err.find("unknown integrator 'leapfrog'"), std::string::npos) << err;
  EXPECT_NE(err.find("missing scene file"), std::string::npos) << err;
}

TEST(RunCommand, BadSceneExitsOneNamingTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / "pba_run_test";
  std::filesystem::create_directories(dir);
  const auto bad = dir / "bad.json";
  std::ofstream(bad) << R"({"version": 1, "emitters": [{"rate": -5}]})";
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({bad.string(), "--steps", "10"}), 1);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find(bad.string() + ": /emitters/0/rate: must be >= 0, got -5"), std::string::npos) << err;
}

TEST(RunCommand, WritesCsvAndPrintsTheWorldsHash) {
  const auto csv = std::filesystem::temp_directory_path() / "pba_run_test.csv";
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({kScene, "--steps", "120", "--every", "10", "--csv", csv.string()}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  // the same scene stepped here gives the hash the command printed
  pba::Scene s = pba::load_scene(kScene);
  for (int i = 0; i < 120; ++i) s.world.step();
  char hash[32];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(s.world.hash()));
  EXPECT_NE(out.find(std::string("final hash   ") + hash), std::string::npos) << out;
  EXPECT_NE(out.find("ms per step"), std::string::npos) << out;
  // header + (step 0 and 12 snapshots) x 8 particles
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "step,time,particle,x,y,z,vx,vy,vz");
  int rows = 0;
  std::string last;
  while (std::getline(in, line)) ++rows, last = line;
  EXPECT_EQ(rows, 13 * 8);
  EXPECT_EQ(last.rfind("120,1,7,", 0), 0u) << last;
  // --quiet prints only the hash; builders run too
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({kScene, "--steps", "120", "--quiet"}), 0);
  EXPECT_EQ(testing::internal::GetCapturedStdout(), std::string(hash) + "\n");
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({"--builder", "forcer-stream", "--steps", "50"}), 0);
  testing::internal::GetCapturedStdout();
}

}  // namespace
