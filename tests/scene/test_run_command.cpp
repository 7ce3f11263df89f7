// `pba run`: bad flags exit 2 with a message, bad scenes exit 1, a run writes the CSV it
// promises and prints the same hash as the World it ran.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <cstdlib>
#include <sstream>

#include "commands_run.h"
#include "pba/scene.h"
#include "pba/soft.h"

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

// a scene file in the temporary directory
std::string write_scene(const std::string& name, const std::string& json) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path) << json;
  return path.string();
}

std::string hash_of(const pba::World& w) {
  char hash[32];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(w.hash()));
  return hash;
}

// the hash `pba run ... --quiet` prints (without the newline)
std::string quiet_hash(std::vector<std::string> words) {
  words.push_back("--quiet");
  testing::internal::CaptureStdout();
  const int rc = run(words);
  std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(rc, 0);
  if (!out.empty() && out.back() == '\n') out.pop_back();
  return out;
}

TEST(RunCommand, FlagEqualsValueIsTheSameAsFlagValue) {
  EXPECT_EQ(quiet_hash({kScene, "--steps=37"}), quiet_hash({kScene, "--steps", "37"}));
  EXPECT_NE(quiet_hash({kScene, "--steps=37"}), quiet_hash({kScene, "--steps=38"}));
}

// every soft-body particle is written, numbered within its body and named by it; the
// values are the body's own state after that many steps (the same World stepped here)
TEST(RunCommand, CsvHasSoftBodyParticlesWithTheirBody) {
  const std::string flag = std::string(PBA_SCENES_DIR) + "/soft_flag.json";
  const auto csv = std::filesystem::temp_directory_path() / "pba_run_soft.csv";
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({flag, "--steps", "30", "--every", "10", "--csv", csv.string()}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  pba::Scene s = pba::load_scene(flag);
  const auto* soft = dynamic_cast<const pba::SoftSystem*>(s.world.find_system(pba::SoftSystem::kName));
  ASSERT_NE(soft, nullptr);
  ASSERT_EQ(soft->size(), 1u);
  const std::size_t n = soft->at(0).size();
  ASSERT_GT(n, 0u);
  EXPECT_EQ(s.world.particles().size(), 0u) << "the flag is all soft body";
  EXPECT_NE(out.find("soft-body particles " + std::to_string(n)), std::string::npos) << out;
  for (int i = 0; i < 30; ++i) s.world.step();
  // header, then 4 snapshots (steps 0, 10, 20, 30) of n particles, all of body "flag"
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "step,time,particle,x,y,z,vx,vy,vz,body");
  std::size_t rows = 0;
  std::string last;
  while (std::getline(in, line)) {
    ++rows, last = line;
    EXPECT_EQ(line.substr(line.rfind(',') + 1), "flag") << line;
  }
  EXPECT_EQ(rows, 4 * n);
  // the last row is particle n - 1 at step 30, as the World here has it (%.9g of floats
  // round-trips them exactly)
  const pba::SoftBody& b = soft->at(0);
  const pba::Vec3 v = b.velocity(n - 1);
  char want[256];
  std::snprintf(want, sizeof want, "30,%.17g,%zu,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,flag", s.world.time(), n - 1,
                b.xs()[n - 1], b.ys()[n - 1], b.zs()[n - 1], static_cast<float>(v.x), static_cast<float>(v.y),
                static_cast<float>(v.z));
  EXPECT_EQ(last, want);
}

// what the World simulates at a step: the particle system's particles, every soft body's
// particles and every entity's rigid body (the colliders' stand-ins are not simulated)
std::size_t simulated_points(const pba::World& w) {
  std::size_t n = w.particles().size();
  if (const auto* soft = dynamic_cast<const pba::SoftSystem*>(w.find_system(pba::SoftSystem::kName)))
    for (std::size_t b = 0; b < soft->size(); ++b) n += soft->at(b).size();
  for (std::size_t i = 0; i < w.rigid().size(); ++i) n += w.valid(w.rigid().id_at(i));
  return n;
}

// every shipped scene: the CSV has a row for every simulated point at every snapshot, as
// many as the same World stepped here holds then (emitters change the count); before, the
// soft bodies wrote none (soft_flag's CSV was its header line)
TEST(RunCommand, CsvHasEverySimulatedPointOfEveryShippedScene) {
  const auto csv = std::filesystem::temp_directory_path() / "pba_run_every_point.csv";
  int scenes = 0;
  for (const auto& e : std::filesystem::directory_iterator(PBA_SCENES_DIR)) {
    if (e.path().extension() != ".json") continue;
    ++scenes;
    const std::string file = e.path().string();
    testing::internal::CaptureStdout();
    const int rc = run({file, "--steps", "20", "--every", "10", "--csv", csv.string()});
    testing::internal::GetCapturedStdout();
    ASSERT_EQ(rc, 0) << file;
    // rows per step (the first column)
    std::map<long long, std::size_t> rows;
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) ++rows[std::stoll(line.substr(0, line.find(',')))];
    pba::Scene s = pba::load_scene(file);
    for (int step = 0; step <= 20; ++step) {
      if (step % 10 == 0) {
        EXPECT_EQ(rows[step], simulated_points(s.world)) << file << " at step " << step;
      }
      if (step < 20) s.world.step();
    }
    EXPECT_GT(rows[20], 0u) << file << ": simulates nothing";
  }
  EXPECT_GE(scenes, 15);
}

// the profile says where the collisions' time goes: semi-implicit Euler's fused kernel
// times them with the integration, so its line says so instead of "collide 0" beside
// contacts (the balls bounce: contacts every step); the other integrators time them apart
TEST(RunCommand, ProfileSaysWhenCollisionsAreFusedWithIntegration) {
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({kScene, "--steps", "300"}), 0);
  std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(out.find("contacts 0 per step"), std::string::npos) << out;
  EXPECT_NE(out.find(", integrate + collide "), std::string::npos) << out;
  EXPECT_NE(out.find(" (fused), recycle "), std::string::npos) << out;
  EXPECT_EQ(out.find("collide 0,"), std::string::npos) << out;
  testing::internal::CaptureStdout();
  ASSERT_EQ(run({kScene, "--steps", "300", "--method", "rk4"}), 0);
  out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find(", collide "), std::string::npos) << out;
  EXPECT_EQ(out.find("(fused)"), std::string::npos) << out;
}

// --method is applied to what an integrator steps (the particles, mass-spring bodies)
// and refused, naming the reason, where the scene cannot honour it: never reported as
// applied while the state is the same
TEST(RunCommand, MethodRefusedWhereTheSceneCannotHonourIt) {
  const std::string springs = std::string(PBA_SCENES_DIR) + "/soft_spring.json";
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({springs, "--method", "euler", "--steps", "10"}), 2);
  const std::string empty = write_scene("pba_run_empty.json", R"({"version": 1})");
  EXPECT_EQ(run({empty, "--method", "rk4", "--steps", "10"}), 2);
  EXPECT_EQ(run({kScene, "--every", "5"}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("--method euler: scene " + springs + " has the soft body 'XPBD' solved by XPBD"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("--method rk4: scene " + empty + " has no particles, emitters or soft bodies"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("--every 5: sets the CSV interval, so it needs --csv FILE"), std::string::npos) << err;
}

TEST(RunCommand, MethodAppliesToMassSpringBodies) {
  // two mass-spring springs; --method replaces both integrators: the hash is that of the
  // same World with the bodies' methods set here, and differs between methods
  const std::string file = write_scene("pba_run_springs.json", R"({"version": 1,
    "settings": {"dt": 0.01},
    "soft_bodies": [
      {"type": "spring", "name": "one", "solver": "mass-spring", "integrator": "semi-implicit-euler",
       "a": [0, 2, 0], "b": [0, 1, 0], "rest_length": 0.8, "mass": 0.5, "stiffness": 40},
      {"type": "spring", "name": "two", "solver": "mass-spring", "integrator": "velocity-verlet",
       "a": [1, 2, 0], "b": [1, 1, 0], "rest_length": 0.8, "mass": 0.5, "stiffness": 40}]})");
  for (pba::Method m : {pba::Method::ExplicitEuler, pba::Method::Rk4}) {
    pba::Scene s = pba::load_scene(file);
    auto* soft = dynamic_cast<pba::SoftSystem*>(s.world.find_system(pba::SoftSystem::kName));
    ASSERT_NE(soft, nullptr);
    for (std::size_t b = 0; b < soft->size(); ++b) soft->at(b).settings().method = m;
    for (int i = 0; i < 50; ++i) s.world.step();
    EXPECT_EQ(quiet_hash({file, "--steps", "50", "--method", std::string(pba::name(m))}), hash_of(s.world))
        << pba::name(m);
  }
  EXPECT_NE(quiet_hash({file, "--steps", "50", "--method", "euler"}),
            quiet_hash({file, "--steps", "50", "--method", "rk4"}));
  EXPECT_NE(quiet_hash({file, "--steps", "50", "--method", "euler"}), quiet_hash({file, "--steps", "50"}));
  // the summary says what integrated what
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({file, "--steps", "5", "--method", "rk4"}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("integrators  'one' mass-spring rk4, 'two' mass-spring rk4 (from --method)"), std::string::npos)
      << out;
}

// the summary says when the soft step may change the substeps it was given (auto_substeps)
// and not when the scene fixed them
TEST(RunCommand, SummarySaysWhenTheSoftStepPicksItsSubsteps) {
  const char* body = R"("rigid_bodies": [{"type": "static", "shapes": [{"type": "plane"}]},
      {"shapes": [{"type": "box"}], "position": [0, 0.5, 0]}]})";
  auto summary = [&](const std::string& name, const std::string& settings) {
    const std::string file = write_scene(name, R"({"version": 1, "settings": {"rigid": )" + settings + "}, " + body);
    testing::internal::CaptureStdout();
    EXPECT_EQ(run({file, "--steps", "2"}), 0);
    return testing::internal::GetCapturedStdout();
  };
  const std::string fixed = summary("pba_run_fixed.json", R"({"substeps": 8})");
  EXPECT_NE(fixed.find("integrators  rigid bodies soft-step x8 substeps\n"), std::string::npos) << fixed;
  const std::string grows = summary("pba_run_auto.json", R"({"auto_substeps_sag_fraction": 0})");
  EXPECT_NE(grows.find("soft-step x8 substeps (more for tall columns)\n"), std::string::npos) << grows;
  const std::string defaults = summary("pba_run_default.json", "{}");
  EXPECT_NE(defaults.find("soft-step x8 substeps (more for tall columns, fewer at rest (at least 3) under a sag of 2% "
                          "of each body's size)\n"),
            std::string::npos)
      << defaults;
  const std::string halves = summary("pba_run_halve.json", R"({"auto_substeps_sag": 0.01, "auto_substeps_least": 4})");
  EXPECT_NE(halves.find("soft-step x8 substeps (more for tall columns, fewer at rest (at least 4) under a sag of 2% of "
                        "each body's size and 10 mm)\n"),
            std::string::npos)
      << halves;
}

// progress goes to stderr as lines when it is not a terminal (here a file), at the
// PBA_PROGRESS_INTERVAL period; --quiet prints none
TEST(RunCommand, ProgressLinesUnlessQuiet) {
  ::setenv("PBA_PROGRESS_INTERVAL", "1e-9", 1);
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({kScene, "--steps", "200"}), 0);
  const std::string err = testing::internal::GetCapturedStderr();
  testing::internal::GetCapturedStdout();
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({kScene, "--steps", "200", "--quiet"}), 0);
  const std::string quiet_err = testing::internal::GetCapturedStderr();
  testing::internal::GetCapturedStdout();
  ::unsetenv("PBA_PROGRESS_INTERVAL");
  EXPECT_NE(err.find("pba run: 200/200 steps (100%), "), std::string::npos) << err;
  EXPECT_NE(err.find(" steps/s, 0.0 s left\n"), std::string::npos) << err;
  EXPECT_EQ(err.find('\r'), std::string::npos) << "no live line in a file";
  EXPECT_EQ(quiet_err, "");
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

// A CSV that cannot be written (a full disk, here /dev/full, where every write fails with
// ENOSPC) is a failed run: exit 1 naming the file, whatever the CSV's length. stdio keeps a
// failed buffered write in the stream's error flag, and fclose returns 0 when its own last
// flush has nothing left to write: the two steps of the rigid stack, whose rows end on a
// buffer's boundary, lost their CSV and exited 0 with the hash.
TEST(RunCommand, ACsvThatCannotBeWrittenExitsOneNamingTheFile) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  const std::string stack = std::string(PBA_SCENES_DIR) + "/rigid_stack.json";
  for (int steps = 1; steps <= 12; ++steps) {
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    const int code = run({stack, "--steps", std::to_string(steps), "--csv", "/dev/full", "--quiet"});
    const std::string out = testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(code, 1) << steps << " steps: " << out << err;
    EXPECT_NE(err.find("pba run: --csv: error writing '/dev/full'"), std::string::npos) << steps << " steps: " << err;
  }
}

// `--csv -` is standard output, as for most Unix tools (it wrote a file named "-"), and the
// summary then goes to standard error: what stdout holds is one CSV (the header, then rows of
// its column count), and the hash, on stderr, is the run's (--quiet's too).
TEST(RunCommand, CsvDashIsStandardOutputWithTheSummaryOnStandardError) {
  const std::string stack = std::string(PBA_SCENES_DIR) + "/rigid_stack.json";
  const std::string hash = quiet_hash({stack, "--steps", "12"});
  std::filesystem::remove("-");
  for (const bool quiet : {false, true}) {
    std::vector<std::string> words{stack, "--steps", "12", "--every", "4", "--csv", "-"};
    if (quiet) words.push_back("--quiet");
    testing::internal::CaptureStdout();
    testing::internal::CaptureStderr();
    const int rc = run(words);
    const std::string out = testing::internal::GetCapturedStdout();
    const std::string err = testing::internal::GetCapturedStderr();
    ASSERT_EQ(rc, 0) << err;
    EXPECT_FALSE(std::filesystem::exists("-")) << "a file named '-' was written";
    std::istringstream in(out);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "step,time,particle,x,y,z,vx,vy,vz,body,qw,qx,qy,qz") << quiet;
    int rows = 0;
    while (std::getline(in, line)) {
      EXPECT_EQ(std::count(line.begin(), line.end(), ','), 13) << line;
      ++rows;
    }
    EXPECT_GT(rows, 0) << quiet;
    EXPECT_EQ(out.find(hash), std::string::npos) << quiet;
    EXPECT_NE(err.find(quiet ? hash + "\n" : "final hash   " + hash), std::string::npos) << quiet << ": " << err;
    if (!quiet) {
      EXPECT_NE(err.find("csv          standard output (every 4 steps)"), std::string::npos) << err;
    }
  }
  std::filesystem::remove("-");
}

// The CSV ends with the final state whatever the interval: 25 steps every 10 write steps 0,
// 10, 20 and 25 (before, the last snapshot was step 20, 5 steps short of the state whose hash
// the command printed), each step once (100 steps every 10, or 7 every 1, add no repeat).
TEST(RunCommand, CsvEndsWithTheFinalStep) {
  const auto csv = std::filesystem::temp_directory_path() / "pba_run_final_step.csv";
  auto snapshots = [&](const char* steps, const char* every) {
    testing::internal::CaptureStdout();
    EXPECT_EQ(run({kScene, "--steps", steps, "--every", every, "--csv", csv.string()}), 0);
    testing::internal::GetCapturedStdout();
    std::vector<long long> out;
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      const long long s = std::stoll(line.substr(0, line.find(',')));
      if (out.empty() || out.back() != s) out.push_back(s);
    }
    return out;
  };
  EXPECT_EQ(snapshots("25", "10"), (std::vector<long long>{0, 10, 20, 25}));
  EXPECT_EQ(snapshots("100", "10"), (std::vector<long long>{0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100}));
  EXPECT_EQ(snapshots("7", "1"), (std::vector<long long>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(snapshots("3", "1000"), (std::vector<long long>{0, 3}));
  // the last rows are the state of the World stepped 25 times here (8 particles at t = 25 dt)
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({kScene, "--steps", "25", "--every", "10", "--csv", csv.string()}), 0);
  testing::internal::GetCapturedStdout();
  pba::Scene s = pba::load_scene(kScene);
  for (int i = 0; i < 25; ++i) s.world.step();
  std::ifstream in(csv);
  std::string line, last;
  while (std::getline(in, line)) last = line;
  const std::size_t i = s.world.particles().size() - 1;
  const pba::Vec3 x = s.world.particles().position(i);
  char want[160];
  std::snprintf(want, sizeof want, "25,%.17g,%zu,%.9g,%.9g,%.9g,", s.world.time(), i, static_cast<float>(x.x),
                static_cast<float>(x.y), static_cast<float>(x.z));
  EXPECT_EQ(last.rfind(want, 0), 0u) << last << "\nwant " << want;
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
  EXPECT_EQ(line, "step,time,particle,x,y,z,vx,vy,vz,body");
  int rows = 0;
  std::string last;
  while (std::getline(in, line)) ++rows, last = line;
  EXPECT_EQ(rows, 13 * 8);
  EXPECT_EQ(last.rfind("120,1,7,", 0), 0u) << last;
  EXPECT_EQ(last.substr(last.rfind(',') + 1), "particles") << last;
  // --quiet prints only the hash; builders run too
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({kScene, "--steps", "120", "--quiet"}), 0);
  EXPECT_EQ(testing::internal::GetCapturedStdout(), std::string(hash) + "\n");
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({"--builder", "forcer-stream", "--steps", "50"}), 0);
  testing::internal::GetCapturedStdout();
}

}  // namespace
