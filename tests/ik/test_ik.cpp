// Tests for pba/ik.h: skeleton validation and forward kinematics, every solver on
// random reachable targets (made from random joint angles with fixed seeds), joint
// limits on every returned pose, unreachable targets, analytic exactness, the
// two-bone pole, several effectors on a tree, determinism and zero allocations.
#include <gtest/gtest.h>

#include "error_of.h"

#include <atomic>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <random>

#include "cpu_time.h"
#include "ik/ik_access.h"
#include "pba/ik.h"
#include "pba/ik_scenes.h"
#include "alloc_count.h"

// count heap allocations (alloc_count.cpp replaces the global operator new)
namespace {
using pba::test_support::g_allocations;
}

namespace {

using namespace pba;
using namespace pba::ik;
constexpr double kPi = 3.141592653589793;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

using pba::test_support::error_of;

SkeletonDef two_bones() {
  SkeletonDef def;
  def.bones.resize(2);
  def.bones[0].length = 1;
  def.bones[1].parent = 0;
  def.bones[1].length = 0.5;
  return def;
}

// ---------------------------------------------------------------------------
// model and bad input

TEST(IkSkeleton, BadDefinitionsNameTheBoneAndValue) {
  auto with = [](auto edit) {
    SkeletonDef d = two_bones();
    edit(d);
    return error_of([&] { Skeleton s(d); });
  };
  EXPECT_EQ(with([](SkeletonDef& d) { d.bones[1].length = 0; }),
            "SkeletonDef.bones[1].length: must be finite and > 0, got 0");
  EXPECT_EQ(with([](SkeletonDef& d) { d.bones[1].length = -2; }),
            "SkeletonDef.bones[1].length: must be finite and > 0, got -2");
  EXPECT_EQ(with([](SkeletonDef& d) { d.bones[0].length = kNaN; }),
            "SkeletonDef.bones[0].length: must be finite and > 0, got nan");
  EXPECT_EQ(with([](SkeletonDef& d) {
              d.bones[1].joint = JointType::Hinge;
              d.bones[1].min_angle = 0.5;
              d.bones[1].max_angle = 0.2;
            }),
            "SkeletonDef.bones[1].min_angle: must be <= max_angle (0.2), got 0.5");
  EXPECT_EQ(with([](SkeletonDef& d) {
              d.bones[1].min_twist = 1;
              d.bones[1].max_twist = -1;
            }),
            "SkeletonDef.bones[1].min_twist: must be <= max_twist (-1), got 1");
  EXPECT_EQ(with([](SkeletonDef& d) { d.bones[1].parent = 7; }),
            "SkeletonDef.bones[1].parent: must be -1 or a bone index in [0, 1], got 7");
  EXPECT_EQ(with([](SkeletonDef& d) { d.bones[1].parent = 1; }),
            "SkeletonDef.bones[1].parent: a bone cannot be its own parent (cycle)");
  EXPECT_EQ(with([](SkeletonDef& d) { d.bones[1].parent = -1; }),
            "SkeletonDef.bones: bones 0 and 1 are both roots (parent -1); a skeleton has exactly one root");
  EXPECT_EQ(with([](SkeletonDef& d) {
              d.bones[1].joint = JointType::Hinge;
              d.bones[1].axis = Vec3(0, 0, 0);
            }),
            "SkeletonDef.bones[1].axis: must be a unit vector, got length 0");
  EXPECT_EQ(with([](SkeletonDef& d) {
              d.bones[1].joint = JointType::Hinge;
              d.bones[1].axis = Vec3(0, 0, 2);
            }),
            "SkeletonDef.bones[1].axis: must be a unit vector, got length 2");
  // a cycle: 0 is the root, 1 -> 2 -> 3 -> 1
  EXPECT_EQ(with([](SkeletonDef& d) {
              d.bones.resize(4);
              d.bones[1].parent = 3;
              d.bones[2].parent = 1;
              d.bones[3].parent = 2;
              d.bones[3].name = "loop";
            }),
            "SkeletonDef.bones[1].parent: the hierarchy has a cycle through this bone (parent 3)");
  EXPECT_EQ(error_of([] { Skeleton s(SkeletonDef{}); }),
            "SkeletonDef.bones: must hold at least one bone, got 0");
}

TEST(IkSkeleton, BadTargetsAndSettingsAreRejected) {
  Skeleton s(two_bones());
  EffectorDef ef;
  ef.bone = 1;
  ef.target = Vec3(0.5, 0.5, 0);
  const int k = s.add_effector(ef);
  EXPECT_EQ(error_of([&] { s.set_target(k, Vec3(kNaN, 0, 1)); }),
            "effector 0 target: must be finite, got (nan, 0, 1)");
  EXPECT_EQ(s.effector(k).target, Vec3(0.5, 0.5, 0));  // unchanged after the error
  EXPECT_EQ(error_of([&] { s.set_orientation_target(k, Quat(0, 0, 0, 0)); }),
            "effector 0 orientation: must be a non-zero quaternion, got norm 0");
  ef.bone = 5;
  EXPECT_EQ(error_of([&] { s.add_effector(ef); }), "EffectorDef[1].bone: must be a bone index in [0, 1], got 5");
  ef.bone = 0;
  ef.weight = 0;
  EXPECT_EQ(error_of([&] { s.add_effector(ef); }), "EffectorDef[1].weight: must be in [1e-06, 1e+06], got 0");
  EXPECT_EQ(s.effector_count(), 1);
  SolverSettings st;
  st.tolerance = -1;
  EXPECT_EQ(error_of([&] { Solver solver(s, st); }), "SolverSettings.tolerance: must be finite and > 0, got -1");
  EXPECT_EQ(error_of([] { parse_method("newton", "--ik"); }),
            "--ik: unknown IK solver 'newton' (expected one of analytic_1dof, analytic_3dof, two_bone, "
            "ccd, jacobian_transpose, pseudo_inverse, dls, sdls, fabrik)");
  for (Method m : kAllMethods) EXPECT_EQ(parse_method(name(m)), m);
  EXPECT_EQ(parse_method("FABRIK"), Method::Fabrik);
  EXPECT_EQ(parse_method("two-bone"), Method::TwoBone);
  // an analytic solver on a skeleton it cannot solve says why
  Skeleton chain = Skeleton::chain(5, 0.2);
  chain.add_effector(4, Vec3(0.5, 0.5, 0));
  Solver solver(chain, Method::Analytic1Dof);
  EXPECT_EQ(error_of([&] { solver.solve(); }),
            "ik::Solver: analytic_1dof: needs exactly one moving joint, a hinge, between the root and "
            "the effector; found 5 moving joints");
}

// Every index-taking accessor of a Skeleton refuses an index out of range by name, with the
// count. Until the fix bone_def(i), effector(k) and effector_error(k) read past their arrays
// (undefined behaviour: garbage or a crash); the setters and reach already checked.
TEST(IkSkeleton, IndicesOutOfRangeAreRefusedNamingTheCallAndTheCount) {
  Skeleton s(two_bones());
  EXPECT_EQ(error_of([&] { (void)s.bone_def(2); }), "Skeleton::bone_def: bone index 2 out of range (the skeleton has 2 bones)");
  EXPECT_EQ(error_of([&] { (void)s.bone_def(-1); }),
            "Skeleton::bone_def: bone index -1 out of range (the skeleton has 2 bones)");
  EXPECT_EQ(error_of([&] { (void)s.effector(0); }),
            "Skeleton::effector: effector index 0 out of range (the skeleton has 0 effectors)");
  s.add_effector(1, Vec3(0.5, 0.5, 0));
  EXPECT_EQ(s.effector(0).bone, 1);
  EXPECT_EQ(s.bone_def(1).parent, 0);
  EXPECT_EQ(error_of([&] { (void)s.effector(1); }),
            "Skeleton::effector: effector index 1 out of range (the skeleton has 1 effector)");
  EXPECT_EQ(error_of([&] { (void)s.effector_error(3); }),
            "Skeleton::effector_error: effector index 3 out of range (the skeleton has 1 effector)");
  EXPECT_EQ(error_of([&] { s.set_target(1, Vec3(0)); }),
            "Skeleton::set_target effector: must be an integer in [0, 0], got 1");
  EXPECT_EQ(error_of([&] { s.set_hinge_angle(2, 0); }), "Skeleton::set_hinge_angle bone: must be an integer in [0, 1], got 2");
  EXPECT_EQ(error_of([&] { (void)s.reach(-1); }), "Skeleton::reach bone: must be an integer in [0, 1], got -1");
}

// The ranges the solvers hold (2026-12-06): weights in [1e-6, 1e6], lengths and positions
// within a float's. Until then a weight of 1e-300 left every Jacobian method where it
// started (the weighted squared error underflowed to 0), one of 1e150 made
// jacobian_transpose return a non-finite pose with residual 0 and the other Jacobian methods
// stop unmoved; a target at 1e155 m gave an infinite residual with the chain pointing
// elsewhere, and a bone of 1e100 m a non-finite pose. At the ranges' edges each iterative
// method converges on a reachable target; beyond them the value is refused by name.
TEST(IkSkeleton, WeightsLengthsAndPositionsHoldTheirRangesAndAreRefusedBeyond) {
  for (Method m : {Method::Ccd, Method::JacobianTranspose, Method::PseudoInverse, Method::Dls, Method::Sdls,
                   Method::Fabrik}) {
    for (double w : {kMinEffectorWeight, kMaxEffectorWeight}) {
      Skeleton s = Skeleton::chain(3, 1.0);
      s.add_effector(2, Vec3(0.3, 1.2, 0.1), w);
      const SolveResult r = Solver(s, m).solve();
      for (const Vec3& t : s.tips()) EXPECT_TRUE(is_finite(t)) << name(m) << " weight " << w;
      EXPECT_TRUE(r.converged) << name(m) << " weight " << w << " residual " << r.residual;
    }
    // bones and targets at the edge of a float's range, in units of the bone
    const double big = 1e38;
    SkeletonDef def;
    for (int i = 0; i < 3; ++i) def.bones.push_back(BoneDef{.name = "", .parent = i - 1, .length = big});
    def.root_position = Vec3(3e38, 0, 0);
    Skeleton s(def);
    s.add_effector(2, def.root_position + big * Vec3(0.3, 1.2, 0.1));
    SolverSettings st;
    st.method = m;
    st.tolerance = 1e-6 * big;
    const SolveResult r = Solver(s, st).solve();
    EXPECT_TRUE(r.converged) << name(m) << " at 1e38 m: residual " << r.residual;
    for (const Vec3& t : s.tips()) EXPECT_TRUE(is_finite(t)) << name(m);
  }
  Skeleton s = Skeleton::chain(3, 1.0);
  EXPECT_EQ(error_of([&] { s.add_effector(2, Vec3(1, 1, 0), 1e-300); }),
            "EffectorDef[0].weight: must be in [1e-06, 1e+06], got 1e-300");
  EXPECT_EQ(error_of([&] { s.add_effector(2, Vec3(1, 1, 0), 1e150); }),
            "EffectorDef[0].weight: must be in [1e-06, 1e+06], got 1e+150");
  EXPECT_EQ(error_of([&] { s.add_effector(2, Vec3(0, 1e155, 0)); }),
            "effector 0 target: must fit a float (|component| <= 3.4028234663852886e+38), got (0, 1e+155, 0)");
  EXPECT_EQ(s.effector_count(), 0);
  const int k = s.add_effector(2, Vec3(1, 1, 0));
  EXPECT_EQ(error_of([&] { s.set_target(k, Vec3(-1e39, 0, 0)); }),
            "effector 0 target: must fit a float (|component| <= 3.4028234663852886e+38), got (-1e+39, 0, 0)");
  EXPECT_EQ(s.effector(k).target, Vec3(1, 1, 0));
  EXPECT_EQ(error_of([&] { s.set_pole(k, Vec3(0, 0, 1e200)); }),
            "effector 0 pole: must fit a float (|component| <= 3.4028234663852886e+38), got (0, 0, 1e+200)");
  EXPECT_EQ(error_of([&] { s.set_root_position(Vec3(1e39, 0, 0)); }),
            "Skeleton::set_root_position: must fit a float (|component| <= 3.4028234663852886e+38), got (1e+39, 0, 0)");
  SkeletonDef def;
  def.bones.push_back(BoneDef{.name = "femur", .length = 1e100});
  EXPECT_EQ(error_of([&] { Skeleton bad(def); }),
            "SkeletonDef.bones[0] ('femur').length: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+100");
  def.bones[0].length = 1;
  def.root_position = Vec3(0, 1e39, 0);
  EXPECT_EQ(error_of([&] { Skeleton bad(def); }),
            "SkeletonDef.root_position: must fit a float (|component| <= 3.4028234663852886e+38), got (0, 1e+39, 0)");
  EXPECT_EQ(error_of([] { Skeleton::chain(2, 1e39); }),
            "Skeleton::chain length: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+39");
}

TEST(IkSkeleton, ForwardKinematicsOfAHingeChain) {
  // two hinges about Z, lengths 1 and 0.5: angles 90 deg and -90 deg
  SkeletonDef def = two_bones();
  for (auto& b : def.bones) b.joint = JointType::Hinge;
  def.root_position = Vec3(1, 2, 3);
  Skeleton s(def);
  s.set_hinge_angle(0, kPi / 2);
  s.set_hinge_angle(1, -kPi / 2);
  s.forward_kinematics();
  EXPECT_NEAR(glm::length(s.tips()[0] - Vec3(1, 3, 3)), 0, 1e-12);
  EXPECT_NEAR(glm::length(s.tips()[1] - Vec3(1.5, 3, 3)), 0, 1e-12);
  EXPECT_EQ(s.starts()[1], s.tips()[0]);
  // limits clamp: a hinge limited to [-0.5, 0.5] cannot be set to 2
  def.bones[1].min_angle = -0.5;
  def.bones[1].max_angle = 0.5;
  Skeleton t(def);
  t.set_hinge_angle(1, 2.0);
  EXPECT_DOUBLE_EQ(t.hinge_angles()[1], 0.5);
}

TEST(IkSkeleton, BonesAreStoredParentsFirst) {
  // definition order: child first; stored order puts the root first
  SkeletonDef def;
  def.bones.resize(3);
  def.bones[0] = {.name = "tip", .parent = 2, .length = 0.25};
  def.bones[1] = {.name = "root", .parent = -1, .length = 1};
  def.bones[2] = {.name = "mid", .parent = 1, .length = 0.5};
  Skeleton s(def);
  EXPECT_EQ(s.index_of(1), 0);
  EXPECT_EQ(s.index_of(2), 1);
  EXPECT_EQ(s.index_of(0), 2);
  EXPECT_EQ(s.find("tip"), 2);
  for (int i = 0; i < 3; ++i) EXPECT_LT(s.parents()[i], i);
  EXPECT_NEAR(s.tips()[2].x, 1.75, 1e-15);
  EXPECT_DOUBLE_EQ(s.total_length(), 1.75);
}

// ---------------------------------------------------------------------------
// random reachable targets

struct Case {
  Method method;
  int bones;
  JointType joint;
  bool limited;
  int targets;
  double min_success;  // fraction
};

std::string case_name(const testing::TestParamInfo<Case>& info) {
  const Case& c = info.param;
  return std::string(name(c.method)) + "_" + std::to_string(c.bones) +
         (c.joint == JointType::Ball ? "_ball" : "_hinge") + (c.limited ? "_limited" : "_free");
}

class RandomTargets : public testing::TestWithParam<Case> {};

TEST_P(RandomTargets, ReachWithinToleranceAndNeverViolateLimits) {
  const Case c = GetParam();
  Skeleton s = scenes::make_chain(c.bones, c.joint, c.limited);
  const auto targets = scenes::random_targets(s, c.bones - 1, c.targets, 1234 + c.bones);
  s.add_effector(c.bones - 1, Vec3(0));
  SolverSettings st;
  st.method = c.method;
  st.tolerance = 1e-4 * s.total_length();
  Solver solver(s, st);
  int ok = 0;
  for (const auto& t : targets) {
    scenes::bent_pose(s);
    s.set_target(0, t.position);
    const SolveResult r = solver.solve();
    int bad = -1;
    ASSERT_TRUE(s.within_limits(1e-9, &bad)) << "joint " << bad << " violates its limits";
    ASSERT_TRUE(std::isfinite(r.residual));
    // the reported residual is the true distance
    ASSERT_NEAR(r.residual, glm::length(s.tips()[c.bones - 1] - t.position), 1e-12);
    ASSERT_LE(r.iterations, default_max_iterations(c.method));
    ok += r.converged;
  }
  EXPECT_GE(ok, c.min_success * c.targets) << ok << " of " << c.targets << " converged";
}

// success goals: >= 99.9% without limits (0 failures in a few hundred), >= 98% with limits
INSTANTIATE_TEST_SUITE_P(
    Ik, RandomTargets,
    testing::Values(
        Case{Method::Fabrik, 10, JointType::Ball, false, 300, 0.999},
        Case{Method::Fabrik, 100, JointType::Ball, false, 100, 0.999},
        Case{Method::Fabrik, 10, JointType::Ball, true, 300, 0.98},
        Case{Method::Fabrik, 100, JointType::Ball, true, 100, 0.98},
        // FABRIK alone converges slowly on chains of 1-DOF hinges with alternating axes (its
        // position passes ignore the hinge planes except through projection: 293 of 300 at
        // 10 bones, some at the 1000-iteration cap); with the hand-over to DLS after 8
        // iterations that do not halve the error, 300 of 300 within 58 iterations
        Case{Method::Fabrik, 10, JointType::Hinge, false, 300, 0.999},
        Case{Method::Fabrik, 100, JointType::Hinge, true, 100, 0.98},
        Case{Method::Ccd, 10, JointType::Ball, false, 300, 0.999},
        Case{Method::Ccd, 100, JointType::Ball, false, 100, 0.999},
        Case{Method::Ccd, 10, JointType::Ball, true, 300, 0.98},
        Case{Method::Ccd, 100, JointType::Ball, true, 100, 0.98},
        Case{Method::Ccd, 10, JointType::Hinge, false, 300, 0.98},
        Case{Method::Ccd, 10, JointType::Hinge, true, 300, 0.98},
        Case{Method::Dls, 10, JointType::Ball, false, 300, 0.999},
        Case{Method::Dls, 100, JointType::Ball, false, 100, 0.999},
        Case{Method::Dls, 10, JointType::Ball, true, 300, 0.98},
        Case{Method::Dls, 100, JointType::Ball, true, 100, 0.98},
        Case{Method::Dls, 10, JointType::Hinge, true, 300, 0.98},
        Case{Method::Sdls, 10, JointType::Ball, false, 300, 0.999},
        Case{Method::Sdls, 100, JointType::Ball, true, 100, 0.98},
        Case{Method::PseudoInverse, 10, JointType::Ball, false, 300, 0.999},
        Case{Method::PseudoInverse, 100, JointType::Ball, true, 100, 0.98},
        Case{Method::JacobianTranspose, 10, JointType::Ball, false, 300, 0.999},
        Case{Method::JacobianTranspose, 100, JointType::Ball, true, 100, 0.98}),
    case_name);

// ---------------------------------------------------------------------------
// unreachable targets: the closest reachable point of an unlimited chain toward a far
// target is at distance total_length from the root, so the residual is |t| - L

class Unreachable : public testing::TestWithParam<Method> {};

TEST_P(Unreachable, EndsAtTheClosestReachableDistance) {
  const Method m = GetParam();
  for (int n : {10, 100, 1000}) {
    Skeleton s = scenes::make_chain(n, JointType::Ball, false);
    s.add_effector(n - 1, Vec3(0));
    Solver solver(s, {m});
    std::mt19937_64 rng(3);
    std::normal_distribution<double> g;
    for (int k = 0; k < (n == 1000 ? 5 : 20); ++k) {
      const Vec3 d = glm::normalize(Vec3(g(rng), g(rng), g(rng)));
      const double dist = 1.2 + 0.1 * k;
      scenes::bent_pose(s);
      s.set_target(0, dist * d);
      const SolveResult r = solver.solve();
      EXPECT_FALSE(r.converged);
      EXPECT_NEAR(r.residual, dist - s.total_length(), 1e-3 * s.total_length())
          << n << " bones, target " << k;
      // pointing at the target
      EXPECT_GT(glm::dot(glm::normalize(s.tips()[n - 1]), d), 0.999);
      // solving again from there never moves away (no oscillation) and stays in tolerance
      const SolveResult again = solver.solve();
      EXPECT_LE(again.residual, r.residual + 1e-9);
      EXPECT_NEAR(again.residual, dist - s.total_length(), 1e-3 * s.total_length());
    }
  }
}

// every iterative method, at every length: the straight chain toward the target is found
// directly (it is the closest reachable point of a free chain), not approached within a cap
INSTANTIATE_TEST_SUITE_P(Ik, Unreachable,
                         testing::Values(Method::Fabrik, Method::Dls, Method::Sdls, Method::Ccd,
                                         Method::PseudoInverse, Method::JacobianTranspose),
                         [](const auto& info) { return std::string(name(info.param)); });

// A limited chain cannot straighten toward every far target: its closest reachable point is
// not known in closed form, but no method may violate the limits, end non-finite, or spend
// its whole iteration cap creeping (one limited ball chain, targets far outside its cone).
TEST(IkUnreachable, LimitedChainsStopWellBeforeTheCap) {
  for (Method m : {Method::Fabrik, Method::Dls, Method::Sdls}) {
    Skeleton s = scenes::make_chain(6, JointType::Ball, true);
    s.add_effector(5, Vec3(0));
    Solver solver(s, {m});
    std::mt19937_64 rng(8);
    std::normal_distribution<double> g;
    int worst = 0;
    for (int k = 0; k < 50; ++k) {
      s.set_target(0, 1.3 * glm::normalize(Vec3(g(rng), g(rng), g(rng))));
      const SolveResult r = solver.solve();
      ASSERT_TRUE(s.within_limits(1e-9));
      ASSERT_TRUE(std::isfinite(r.residual));
      EXPECT_FALSE(r.converged);
      worst = std::max(worst, r.iterations);
    }
    // the cap is 1000; the solves run to their stationary poses (the limits are in the
    // Jacobian model, docs/ik.md): measured at most 122 iterations (DLS; FABRIK 91, SDLS 119)
    EXPECT_LT(worst, default_max_iterations(m) / 2) << name(m);
  }
}

// ---------------------------------------------------------------------------
// FABRIK with joint limits: the passes fight the limits and creep; after 8 iterations that
// do not halve the error, damped least squares finishes

TEST(IkFabrikLimits, HingeChainsTrackAReachableTargetWithoutCreeping) {
  for (int n : {6, 12, 24}) {
    // the target is the tip of a driver chain with the same limited hinges whose angles swing
    // inside the limits (0.9 of them), so every frame's target is reachable by construction
    Skeleton s = scenes::make_chain(n, JointType::Hinge, true);
    Skeleton driver = scenes::make_chain(n, JointType::Hinge, true);
    scenes::bent_pose(s);
    s.add_effector(n - 1, Vec3(0));
    SolverSettings st;
    st.method = Method::Fabrik;
    st.tolerance = 1e-4 * s.total_length();
    Solver solver(s, st);
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> u(0, 2 * kPi);
    std::vector<double> phase(n);
    for (double& p : phase) p = u(rng);
    int converged = 0, worst = 0;
    for (int f = 0; f < 600; ++f) {
      for (int i = 0; i < n; ++i) driver.set_hinge_angle(i, 0.9 * scenes::kHingeLimit * std::sin(0.7 * f / 60.0 + phase[i]));
      driver.forward_kinematics();
      s.set_target(0, driver.tips()[n - 1]);
      const SolveResult r = solver.solve();
      ASSERT_TRUE(s.within_limits(1e-9)) << n << " bones, frame " << f;
      converged += r.converged;
      worst = std::max(worst, r.iterations);
    }
    // FABRIK alone converged on 497, 414 and 599 of the 600 frames, some only at the
    // 1000-iteration cap with up to 6 mm left; with the hand-over, all within 48 iterations
    EXPECT_EQ(converged, 600) << n << " bones";
    EXPECT_LE(worst, 100) << n << " bones";
  }
}

TEST(IkFabrikLimits, TheJointLimitsSampleNeverSpendsTheCap) {
  // the "Joint limits" sample: 6 hinges limited to +-1 rad, the root turned up, a target
  // on a Lissajous path that often leaves the limited chain's reach
  SkeletonDef def;
  const Skeleton c = scenes::make_chain(6, JointType::Hinge, true);
  for (int i = 0; i < c.bone_count(); ++i) def.bones.push_back(c.bone_def(i));
  def.root_position = Vec3(0, 0.1, 0);
  def.root_rotation = glm::angleAxis(0.5 * kPi, Vec3(0, 0, 1));
  Skeleton s(def);
  scenes::bent_pose(s);
  s.add_effector(5, Vec3(0.3, 0.7, 0.2));
  Solver solver(s, Method::Fabrik);
  int worst = 0, within_100 = 0;
  for (int f = 0; f < 1200; ++f) {
    const double w = 0.44 * f / 60.0;
    s.set_target(0, Vec3(0.5 * std::sin(w), 0.52 + 0.28 * std::sin(1.7 * w + 0.6), 0.3 * std::sin(0.8 * w + 1.3)));
    const SolveResult r = solver.solve();
    ASSERT_TRUE(s.within_limits(1e-9)) << "frame " << f;
    ASSERT_TRUE(std::isfinite(r.residual)) << "frame " << f;
    // every frame ends converged or on a stationary pose, never at the budget
    EXPECT_NE(r.stop, StopReason::IterationCap) << "frame " << f;
    worst = std::max(worst, r.iterations);
    within_100 += r.iterations <= 100;
  }
  // before the hand-over, 588 of these 1200 frames ran the full 1000 iterations. The bound
  // was a quarter of the cap while a solve pressed on limits stopped on slow progress (1% in
  // 16 iterations); it now runs to the stationary pose, which at a singular pose on the edge
  // of the reach (frame 207: 0.6 mm short, three hinges on their limits, the other three
  // unable to move the tip toward the target) damped least squares approaches linearly:
  // 495 iterations (0.1 ms) on that frame, the rest within 250, 1190 of 1200 within 100
  EXPECT_LT(worst, default_max_iterations(Method::Fabrik) / 2);
  EXPECT_GE(within_100, 1188);
}

// ---------------------------------------------------------------------------
// the FABRIK reaching pass against the textbook one

TEST(IkFabrikPass, MatchesTheTextbookPassAndKeepsBoneLengths) {
  // reach_pass updates each step's squared distance algebraically; the textbook pass
  // recomputes it from the vector. Both must agree to rounding (relative 1e-12 of the
  // chain's size over 50 steps: each step's error is ~1e-16, bounded by the cancellation
  // guard to ~64 times that), on random goals that fold the chain back and forth
  std::mt19937_64 rng(29);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.05, 0.2);
  for (int trial = 0; trial < 200; ++trial) {
    const int count = 50;
    std::vector<Vec3> q(count + 1);
    std::vector<double> len(count);
    for (auto& p : q) p = Vec3(g(rng), g(rng), g(rng)) * (trial % 2 ? 0.05 : 1.0);
    for (double& l : len) l = u(rng);
    // a goal that coincides with the running point: the step keeps the goals' direction
    if (trial % 10 == 0) q[count - 5] = q[count - 4];
    const Vec3 from(g(rng), g(rng), g(rng));
    std::vector<Vec3> out(count + 1);
    // goals are read backwards: Q_i = q[count - 1 - i], and q[count] gives the fallback
    detail::reach_pass(from, &q[count - 1], len.data(), out.data(), count);
    Vec3 p = from;
    for (int i = 0; i < count; ++i) {
      const Vec3 goal = q[count - 1 - i];
      Vec3 d = goal - p;
      if (glm::dot(d, d) <= 1e-300) d = goal - q[count - i];
      p += d * (len[i] / glm::length(d));
      ASSERT_NEAR(glm::length(out[i + 1] - p), 0, 1e-12) << "trial " << trial << " step " << i;
      ASSERT_NEAR(glm::length(out[i + 1] - out[i]), len[i], 1e-13) << "trial " << trial << " step " << i;
    }
  }
}

// ---------------------------------------------------------------------------
// the Jacobian methods' one-effector path (J never stored: each ball joint's block is
// v -> v x D, its share of J J^T is |D|^2 I - D D^T) against the general path (J stored)

TEST(IkJacobian, OneEffectorPathTakesTheGeneralPathsSteps) {
  // One effector of weight 1, or the same effector twice with weight 1/sqrt(2): the stacked
  // J' = [J; J] / sqrt(2), e' = [e; e] / sqrt(2) give J'^T J' = J^T J and J'^T e' = J^T e, so
  // DLS's step J^T (J J^T + l^2 I)^-1 e = (J^T J + l^2 I)^-1 J^T e, the transpose's
  // alpha J^T e, and the cost are the same; only rounding differs (the second runs the 6-row
  // general path). Ball chains and limited hinge chains (saturated columns dropped).
  for (Method m : {Method::Dls, Method::JacobianTranspose}) {
    for (JointType jt : {JointType::Ball, JointType::Hinge}) {
      Skeleton one = scenes::make_chain(12, jt, jt == JointType::Hinge);
      Skeleton two = scenes::make_chain(12, jt, jt == JointType::Hinge);
      const auto targets = scenes::random_targets(one, 11, 20, 61);  // leaves `one` bent
      scenes::bent_pose(two);
      one.add_effector(11, Vec3(0), 1.0);
      two.add_effector(11, Vec3(0), std::sqrt(0.5));
      two.add_effector(11, Vec3(0), std::sqrt(0.5));
      Solver s1(one, {m}), s2(two, {m});
      for (const auto& t : targets) {
        one.set_target(0, t.position);
        two.set_target(0, t.position);
        two.set_target(1, t.position);
        const SolveResult r1 = s1.solve(), r2 = s2.solve();
        EXPECT_EQ(r1.iterations, r2.iterations) << name(m);
        // rounding of ~1e-16 per operation over tens of iterations: 1e-9 m on a 1 m chain
        for (int i = 0; i < 12; ++i) ASSERT_NEAR(glm::length(one.tips()[i] - two.tips()[i]), 0, 1e-9) << name(m);
      }
    }
  }
}

// Weights are relative: a lone effector's weight w scales J and e alike, and DLS's damping
// scales with it (lambda = 0.02 reach sqrt(sum w^2)), so its step (J^T J + lambda^2 I)^-1 J^T e
// is the weight-1 step for every accepted w: the same iterations, the same pose to rounding
// (1e-9 m on a 1 m chain, as above). Until 2026-12-06 the damping ignored the weights and a
// lone effector of weight 1e-3 ended at the iteration cap. Also for two effectors of weight w
// each.
TEST(IkJacobian, DlsTakesTheSameStepsWhateverTheWeightsScale) {
  for (const int effectors : {1, 2}) {
    auto solve = [&](double w, std::vector<Vec3>& tips) {
      Skeleton s = scenes::make_chain(12, JointType::Ball, false);
      scenes::bent_pose(s);
      s.add_effector(11, Vec3(0.5, 0.6, 0.1), w);
      if (effectors == 2) s.add_effector(5, Vec3(0.2, 0.3, -0.1), w);
      const SolveResult r = Solver(s, {Method::Dls}).solve();
      tips.assign(s.tips().begin(), s.tips().end());
      return r;
    };
    std::vector<Vec3> tips1, tips;
    const SolveResult r1 = solve(1, tips1);
    ASSERT_TRUE(r1.converged || effectors == 2);
    for (const double w : {1e-6, 1e-3, 0.1, 10.0, 1e3, 1e6}) {
      const SolveResult r = solve(w, tips);
      EXPECT_EQ(r.converged, r1.converged) << "weight " << w;
      EXPECT_EQ(r.iterations, r1.iterations) << "weight " << w;
      for (std::size_t i = 0; i < tips.size(); ++i) ASSERT_NEAR(glm::length(tips[i] - tips1[i]), 0, 1e-9) << w;
    }
  }
}

// The rest pose, a straight chain, toward a target on its line short of the tip, behind the
// root or at the root: every column of J (r_j x (e - p_j), the tip moving across the chain)
// is square to the error (along the chain), so J^T e = 0 and the pose is stationary for the
// whole Jacobian family, although it is a saddle or a maximum of the error and the target
// is reachable (a free chain folds onto any point within its length). The methods used to
// stop there untouched, Stalled, 0.5 m, 1.5 m and 1 m from these targets of a 1 m chain;
// CCD and FABRIK reached them. Unlimited chains of 2 ball joints and of 10 ball joints or
// hinges: all must converge. (Two hinges on crossed axes cannot reach the line short of
// the tip, so the hinge chain is the longer one.)
TEST(IkJacobian, StraightChainLeavesTheSaddleOfATargetOnItsLine) {
  for (Method m : {Method::JacobianTranspose, Method::PseudoInverse, Method::Dls, Method::Sdls}) {
    for (const auto& [n, jt] : {std::pair{2, JointType::Ball}, std::pair{10, JointType::Ball},
                                std::pair{10, JointType::Hinge}}) {
      for (const double x : {0.5, -0.5, 0.0}) {
        Skeleton s = scenes::make_chain(n, jt, false);
        s.add_effector(n - 1, Vec3(x, 0, 0));
        const SolveResult r = Solver(s, {m}).solve();
        EXPECT_TRUE(r.converged) << name(m) << " n " << n << " x " << x << ": residual " << r.residual << " after "
                                 << r.iterations << " iterations, " << name(r.stop);
        EXPECT_LE(s.max_effector_error(), 1e-4) << name(m) << " n " << n << " x " << x;
      }
    }
  }
}

// A budget of one or two iterations a frame (SolverSettings::max_iterations) spreads a solve
// over frames with warm starts. From the rest pose of a 100-bone chain the full step of DLS
// and of the pseudo-inverse raises the error and is rejected; each solve used to start from
// the full step again, so the chain never moved (0.77 m away after 200 frames). A solve that
// runs out of iterations now hands its shortening to the next: every Jacobian method
// converges within 12 frames of 1 iteration (measured: at most 7), as a single solve does in
// at most 8 iterations.
TEST(IkJacobian, AnIterationAFrameProgressesFromAStraightChain) {
  for (Method m : {Method::JacobianTranspose, Method::PseudoInverse, Method::Dls, Method::Sdls}) {
    for (const int cap : {1, 2}) {
      Skeleton s = scenes::make_chain(100, JointType::Ball, false);
      s.add_effector(99, Vec3(0.3, 0.5, 0.2));
      SolverSettings st{m};
      st.max_iterations = cap;
      Solver solver(s, st);
      const int frames = m == Method::JacobianTranspose ? 40 : 12;
      SolveResult r;
      for (int f = 0; f < frames && !r.converged; ++f) r = solver.solve();
      EXPECT_TRUE(r.converged) << name(m) << " cap " << cap << ": residual " << r.residual << " after " << frames
                               << " frames";
    }
  }
}

// What a capped solve hands to the next (its shortened step, Impl::carry_valid) belongs to
// the pose it ended at, its settings and its effectors. A solve after the user changed any
// of them must be the solve of a fresh solver on the same skeleton, bit for bit (state hash
// and iterations): after reset_pose or set_joint_rotation (the dirty pose; before the fix
// the carry survived it: in the review's animation overwriting the pose every frame, the
// worst residual went from 1.094 to 1.574 m), after set_settings, after add_effector.
// From the rest pose of a 100-bone chain the full DLS, pseudo-inverse or SDLS step is
// rejected for several frames of one iteration, each ending with a shorter step to hand on
// (AnIterationAFrameProgressesFromAStraightChain); after three such frames and the change,
// six more frames of the two solvers must agree.
TEST(IkJacobian, TheCarriedShorteningDoesNotOutliveItsPose) {
  enum Change { kReset, kRotation, kSettings, kEffector };
  for (Method m : {Method::PseudoInverse, Method::Dls, Method::Sdls}) {
    for (const Change c : {kReset, kRotation, kSettings, kEffector}) {
      Skeleton s = scenes::make_chain(100, JointType::Ball, false);
      s.add_effector(99, Vec3(0.3, 0.5, 0.2));
      SolverSettings st{m};
      st.max_iterations = 1;
      Solver solver(s, st);
      for (int f = 0; f < 3; ++f) ASSERT_EQ(solver.solve().stop, StopReason::IterationCap) << name(m);
      switch (c) {
        case kReset: s.reset_pose(); break;
        case kRotation: s.set_joint_rotation(50, Quat(std::cos(0.1), 0, 0, std::sin(0.1))); break;
        case kSettings: solver.set_settings(st); break;
        case kEffector: s.add_effector(49, Vec3(0.1, 0.3, 0)); break;
      }
      Skeleton fresh_s = s;
      Solver fresh(fresh_s, st);
      for (int f = 0; f < 6; ++f) {
        const SolveResult r = solver.solve();
        const SolveResult rf = fresh.solve();
        EXPECT_EQ(s.state_hash(), fresh_s.state_hash()) << name(m) << " change " << c << " frame " << f;
        EXPECT_EQ(r.residual, rf.residual) << name(m) << " change " << c << " frame " << f;
      }
    }
  }
}

// One joint, a ball or a hinge, its 1 m bone along +X toward a target on the bone 0.5 m
// from the joint: the tip moves on the unit sphere (circle) about the joint, whose nearest
// point to the target is the tip at rest, so the rest pose is the minimum (0.5 m), and a
// pose on the line that the bend tries (the target short of the tip, J^T e = 0 exactly:
// the first run leaves the pose untouched and stalls). With a cap of 3 iterations the bent
// pose's run ends short of the rest pose, worse: the solve must return the rest pose bit
// for bit (state hash), and Stalled: the solve stalled there, whatever the thrown-away
// run hit (it said IterationCap before). A bend kept whatever it ends at fails this
// (checked), through the stop reason only: the pose given is the stationary one here, so
// the driver's never-worse check (given_cost) puts it back; with the whole default budget
// the bent run even comes back to the identity rotation exactly. The hinge chain of the
// test before passed with the bend always kept.
TEST(IkJacobian, TheBendKeepsATrueMinimum) {
  for (Method m : {Method::JacobianTranspose, Method::PseudoInverse, Method::Dls, Method::Sdls}) {
    for (const JointType jt : {JointType::Ball, JointType::Hinge}) {
      SkeletonDef def;
      def.bones.resize(1);
      def.bones[0].length = 1;
      def.bones[0].joint = jt;
      Skeleton rest(def);
      rest.forward_kinematics();
      Skeleton s(def);
      s.add_effector(0, Vec3(0.5, 0, 0));
      SolverSettings st{m};
      st.max_iterations = 3;
      const SolveResult r = Solver(s, st).solve();
      EXPECT_EQ(s.state_hash(), rest.state_hash()) << name(m) << " " << (jt == JointType::Ball ? "ball" : "hinge");
      EXPECT_EQ(r.residual, 0.5) << name(m);
      EXPECT_EQ(r.stop, StopReason::Stalled) << name(m);
    }
  }
}

// The bend runs only on the line it is for (Impl::on_line_saddle). Off the line a stall is
// a true minimum, where the bend and its second solve were paid on every solve and thrown
// away (review of d53039a: 100 warm frames of a limited ten-ball chain toward an
// unreachable target took 4306 DLS iterations instead of 691). Two true minima with closed
// forms: three hinges in [-0.5, 0.5] toward a target far behind (all at -0.5), and a planar
// chain of four free hinges about Z toward a target 0.5 m above its plane (the tip under the
// target, 0.5 m away). A warm solve from the pose the last one returned starts stationary:
// its first accepted step stalls, DLS's at once and the others' after one hand-over to DLS,
// so it must take at most 2 iterations (before the fix: 5 to 8, the bend's second solve).
TEST(IkJacobian, AStallOffTheLineIsNotBent) {
  SkeletonDef curl, planar;
  curl.bones.resize(3);
  for (int i = 0; i < 3; ++i) {
    curl.bones[i].parent = i - 1;
    curl.bones[i].length = 1.0 / 3;
    curl.bones[i].joint = JointType::Hinge;
    curl.bones[i].min_angle = -0.5;
    curl.bones[i].max_angle = 0.5;
  }
  planar.bones.resize(4);
  for (int i = 0; i < 4; ++i) {
    planar.bones[i].parent = i - 1;
    planar.bones[i].length = 0.25;
    planar.bones[i].joint = JointType::Hinge;
  }
  Vec3 curled_tip(0);
  for (int i = 1; i <= 3; ++i) curled_tip += Vec3(std::cos(-0.5 * i), std::sin(-0.5 * i), 0) / 3.0;
  const struct {
    const SkeletonDef* def;
    Vec3 target;
    double closest;
  } cases[] = {{&curl, Vec3(-3, -3, 0), glm::length(Vec3(-3, -3, 0) - curled_tip)},
               {&planar, Vec3(0.3, 0.4, 0.5), 0.5}};
  for (Method m : {Method::JacobianTranspose, Method::PseudoInverse, Method::Dls, Method::Sdls}) {
    for (const auto& c : cases) {
      Skeleton s(*c.def);
      s.add_effector(s.bone_count() - 1, c.target);
      Solver solver(s, {m});
      const SolveResult r1 = solver.solve();
      ASSERT_TRUE(s.within_limits());
      EXPECT_FALSE(r1.converged);
      EXPECT_NEAR(r1.residual, c.closest, 1e-6) << name(m) << " bones " << s.bone_count();
      const SolveResult r2 = solver.solve();
      EXPECT_LE(r2.iterations, 2) << name(m) << " bones " << s.bone_count();
      EXPECT_EQ(r2.stop, StopReason::Stalled) << name(m) << " bones " << s.bone_count();
    }
  }
}

// ---------------------------------------------------------------------------
// analytic solvers

TEST(IkAnalytic, OneHingeAimsExactly) {
  SkeletonDef def;
  def.bones.resize(1);
  def.bones[0].length = 2;
  def.bones[0].joint = JointType::Hinge;
  Skeleton s(def);
  s.add_effector(0, Vec3(0));
  Solver solver(s, Method::Analytic1Dof);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  for (int k = 0; k < 100; ++k) {
    // a target on the reachable circle is hit exactly
    const double a = u(rng);
    s.set_target(0, Vec3(2 * std::cos(a), 2 * std::sin(a), 0));
    const SolveResult r = solver.solve();
    EXPECT_LT(r.residual, 1e-12);
    EXPECT_TRUE(r.converged);
    EXPECT_EQ(r.iterations, 1);
    // an off-circle target: the tip points at the target's projection on the hinge plane
    const Vec3 t(3 * std::cos(a + 1), 3 * std::sin(a + 1), 0.7);
    s.set_target(0, t);
    solver.solve();
    EXPECT_NEAR(glm::length(glm::normalize(s.tips()[0]) - glm::normalize(Vec3(t.x, t.y, 0))), 0, 1e-12);
  }
}

TEST(IkAnalytic, OneBallJointAimsExactly) {
  SkeletonDef def;
  def.bones.resize(2);
  def.bones[0].length = 0.5;
  def.bones[0].joint = JointType::Fixed;  // a fixed upper arm, then one ball joint
  def.bones[1].parent = 0;
  def.bones[1].length = 1;
  Skeleton s(def);
  s.add_effector(1, Vec3(0));
  Solver solver(s, Method::Analytic3Dof);
  std::mt19937_64 rng(12);
  std::normal_distribution<double> g;
  for (int k = 0; k < 100; ++k) {
    const Vec3 d = glm::normalize(Vec3(g(rng), g(rng), g(rng)));
    s.set_target(0, Vec3(0.5, 0, 0) + d);
    const SolveResult r = solver.solve();
    EXPECT_LT(r.residual, 1e-12);
    EXPECT_TRUE(s.within_limits());
  }
}

TEST(IkAnalytic, TwoBoneReachesWithTheElbowOnThePoleSide) {
  SkeletonDef def;
  def.bones.resize(2);
  def.bones[0].length = 0.3;
  def.bones[1].parent = 0;
  def.bones[1].length = 0.25;
  def.bones[1].joint = JointType::Hinge;
  Skeleton s(def);
  s.add_effector(1, Vec3(0));
  Solver solver(s, Method::TwoBone);
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  int tested = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec3 t(u(rng), u(rng), u(rng)), pole(u(rng), u(rng), u(rng));
    const double dist = glm::length(t);
    if (dist < 0.06 || dist > 0.55) continue;
    // the pole must be off the shoulder-target line for a half-plane to exist
    const Vec3 axis = t / dist;
    const Vec3 pole_off = pole - glm::dot(pole, axis) * axis;
    if (glm::length(pole_off) < 0.05) continue;
    s.set_target(0, t);
    s.set_pole(0, pole);
    const SolveResult r = solver.solve();
    EXPECT_LT(r.residual, 1e-9) << k;
    const Vec3 elbow = s.starts()[1];
    const Vec3 elbow_off = elbow - glm::dot(elbow, axis) * axis;
    EXPECT_GT(glm::dot(elbow_off, pole_off), 0) << "elbow not on the pole's side, target " << k;
    EXPECT_TRUE(s.within_limits());
    ++tested;
  }
  EXPECT_GT(tested, 100);
}

TEST(IkAnalytic, TwoBoneHingeAngleAndRotationStayTogether) {
  // Method::TwoBone turns the elbow's quaternion by the bend (no sine or cosine) and adds
  // the bend's arc tangent to its angle: over many warm-started solves the two must keep
  // describing the same rotation (each solve adds ~1e-16 of disagreement; 1e-12 after
  // 20000), and the limits (elbow in [0, 2.8] rad) must hold
  Skeleton s = scenes::make_limb();
  EffectorDef ef;
  ef.bone = 1;
  ef.pole = Vec3(0, 1, 0);
  s.add_effector(ef);
  Solver solver(s, Method::TwoBone);
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  const Vec3 axis = s.bone_def(1).axis;
  for (int k = 0; k < 20000; ++k) {
    s.set_target(0, Vec3(u(rng), u(rng), u(rng)));
    solver.solve();
    ASSERT_TRUE(s.within_limits(1e-12)) << k;
    const double a = s.hinge_angles()[1];
    const Quat expect = glm::angleAxis(a, axis);
    ASSERT_NEAR(std::abs(glm::dot(expect, s.joint_rotations()[1])), 1, 1e-12) << k;
  }
}

TEST(IkAnalytic, TwoBoneJobValidatesAndReportsReach) {
  TwoBoneJob job;
  job.start = Vec3(0);
  job.mid = Vec3(1, 0, 0);
  job.end = Vec3(2, 0, 0);
  job.target = Vec3(1, 1, 0);
  job.pole = Vec3(0, 1, 0);
  ASSERT_TRUE(job.validate());
  ASSERT_TRUE(job.run());
  EXPECT_TRUE(job.reached);
  // apply the corrections: end' = start + Cs((mid - start) + Cm(end - mid))
  auto end_after = [](const TwoBoneJob& j) {
    const Vec3 mid = j.start + j.start_correction * (j.mid - j.start);
    return mid + j.start_correction * (j.mid_correction * (j.end - j.mid));
  };
  EXPECT_LT(glm::length(end_after(job) - job.target), 1e-12);
  job.target = Vec3(5, 0, 0);
  ASSERT_TRUE(job.run());
  EXPECT_FALSE(job.reached);
  EXPECT_NEAR(glm::length(end_after(job)), 2, 1e-12);  // stretched toward the target
  job.target = Vec3(kNaN, 0, 0);
  EXPECT_FALSE(job.validate());
  EXPECT_FALSE(job.run());
}

// ---------------------------------------------------------------------------
// several effectors on a tree; orientation targets; a free root

Skeleton make_y(bool limited) { return scenes::make_y_tree(limited); }

TEST(IkTree, SeveralEffectorsReachTheirTargets) {
  for (Method m : {Method::Fabrik, Method::Dls, Method::Ccd, Method::Sdls}) {
    for (bool limited : {false, true}) {
      Skeleton s = make_y(limited);
      const int n = s.bone_count();
      const int leaf_a = n - 2, leaf_b = n - 1;
      s.add_effector(leaf_a, Vec3(0));
      s.add_effector(leaf_b, Vec3(0));
      SolverSettings st;
      st.method = m;
      st.tolerance = 1e-4 * s.total_length();
      st.max_iterations = 1000;
      Solver solver(s, st);
      std::mt19937_64 rng(21);
      int ok = 0, total = 50;
      for (int k = 0; k < total; ++k) {
        scenes::random_pose(s, rng);
        const Vec3 ta = s.tips()[leaf_a], tb = s.tips()[leaf_b];
        s.reset_pose();
        s.set_target(0, ta);
        s.set_target(1, tb);
        const SolveResult r = solver.solve();
        ASSERT_TRUE(s.within_limits());
        ok += r.converged && s.effector_error(0) <= st.tolerance && s.effector_error(1) <= st.tolerance;
      }
      // measured 50 of 50 for each method, limited or not
      EXPECT_GE(ok, 0.98 * total) << name(m) << (limited ? " limited" : "");
    }
  }
}

TEST(IkTree, AHumanoidReachesWithBothHandsAndFeet) {
  Skeleton s = scenes::make_humanoid();
  const int ends[4] = {s.find("hand_l"), s.find("hand_r"), s.find("shin_l"), s.find("shin_r")};
  for (int b : ends) ASSERT_GE(b, 0);
  // standing: the ankles about a foot's height above the ground, the hands at the sides
  EXPECT_NEAR(s.tips()[ends[2]].y, 0.1, 0.05);
  EXPECT_NEAR(s.tips()[ends[3]].y, 0.1, 0.05);
  EXPECT_LT(s.tips()[ends[0]].x, -0.1);
  EXPECT_GT(s.tips()[ends[1]].x, 0.1);
  for (int b : ends) s.add_effector(b, s.tips()[b]);
  for (Method m : {Method::Fabrik, Method::Dls, Method::Ccd}) {
    SolverSettings st;
    st.method = m;
    st.tolerance = 1e-4 * s.total_length();
    Solver solver(s, st);
    std::mt19937_64 rng(41);
    int ok = 0, total = 30;
    for (int k = 0; k < total; ++k) {
      scenes::random_pose(s, rng);
      for (int e = 0; e < 4; ++e) s.set_target(e, s.tips()[ends[e]]);
      s.reset_pose();
      const SolveResult r = solver.solve();
      ASSERT_TRUE(s.within_limits());
      ok += r.converged;
    }
    // measured: DLS 30 of 30, FABRIK 30 of 30 (29 before its hand-over to DLS), CCD 30 of 30
    // (19 before a stuck CCD handed over to DLS; SDLS 27: not tested here)
    EXPECT_GE(ok, 0.9 * total) << name(m);
  }
}

TEST(IkTree, OrientationTargetsAreMet) {
  for (Method m : {Method::Fabrik, Method::Dls, Method::Sdls}) {
    Skeleton s = scenes::make_chain(8, JointType::Ball, false);
    const auto targets = scenes::random_targets(s, 7, 50, 31);
    s.add_effector(7, Vec3(0));
    SolverSettings st;
    st.method = m;
    st.max_iterations = 500;
    Solver solver(s, st);
    int ok = 0;
    for (const auto& t : targets) {
      scenes::bent_pose(s);
      s.set_target(0, t.position);
      s.set_orientation_target(0, t.rotation);
      const SolveResult r = solver.solve();
      ok += r.converged;
    }
    EXPECT_GE(ok, 49) << name(m);
  }
}

TEST(IkTree, AFreeRootFollowsAFarTarget) {
  for (Method m : {Method::Fabrik, Method::Dls, Method::Ccd}) {
    SkeletonDef def;
    def.root_free = true;
    def.bones.resize(4);
    for (int i = 0; i < 4; ++i) def.bones[i].parent = i - 1, def.bones[i].length = 0.25;
    Skeleton s(def);
    EXPECT_EQ(s.dof_count(), 15);
    s.add_effector(3, Vec3(5, 3, 1));
    const SolveResult r = Solver(s, {m}).solve();
    EXPECT_TRUE(r.converged) << name(m) << " residual " << r.residual;
  }
}

// ---------------------------------------------------------------------------
// determinism, allocations, blending

std::uint64_t run_sequence(Method m) {
  Skeleton s = scenes::make_chain(20, JointType::Ball, true);
  const auto targets = scenes::random_targets(s, 19, 20, 77);
  s.add_effector(19, Vec3(0));
  Solver solver(s, {m});
  std::uint64_t h = 0;
  for (const auto& t : targets) {
    s.set_target(0, t.position);  // warm start from the previous solution
    solver.solve();
    h ^= s.state_hash() + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
  }
  return h;
}

TEST(IkDeterminism, SameInputsSameState) {
  for (Method m : {Method::Fabrik, Method::Ccd, Method::Dls, Method::Sdls, Method::PseudoInverse,
                   Method::JacobianTranspose})
    EXPECT_EQ(run_sequence(m), run_sequence(m)) << name(m);
}

TEST(IkAllocations, SolvingAllocatesNothing) {
  // the counter counts (so a zero below means something)
  {
    const long long before = g_allocations.load();
    void* volatile probe = ::operator new(64);  // a direct call: never elided
    ::operator delete(probe);
    EXPECT_EQ(g_allocations.load() - before, 1);
  }
  for (Method m : {Method::Fabrik, Method::Ccd, Method::Dls, Method::Sdls, Method::PseudoInverse,
                   Method::JacobianTranspose}) {
    Skeleton s = make_y(true);
    s.add_effector(s.bone_count() - 1, Vec3(0.2, 0.3, 0.1));
    const int k = s.add_effector(s.bone_count() - 2, Vec3(-0.2, 0.3, 0.0));
    s.set_orientation_target(k, glm::angleAxis(1.0, Vec3(0, 0, 1)));
    Solver solver(s, {m});
    solver.solve();  // the first solve may size nothing more, but count from the second
    const long long before = g_allocations.load();
    for (int k = 0; k < 10; ++k) {
      s.set_target(0, Vec3(0.2 - 0.01 * k, 0.3, 0.1));
      s.set_orientation_target(1, k % 2 ? std::optional<Quat>() : glm::angleAxis(0.5, Vec3(1, 0, 0)));
      solver.solve();
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << name(m);
  }
  // one effector on a chain: FABRIK's chain loop and hand-over to DLS, the Jacobian
  // methods' one-effector path, and the straightening toward an unreachable target
  for (Method m : {Method::Fabrik, Method::Ccd, Method::Dls, Method::Sdls, Method::PseudoInverse,
                   Method::JacobianTranspose}) {
    for (JointType jt : {JointType::Ball, JointType::Hinge}) {
      Skeleton c = scenes::make_chain(30, jt, jt == JointType::Hinge);
      c.add_effector(29, Vec3(0.3, 0.4, 0.1));
      Solver solver(c, {m});
      solver.solve();
      const long long before = g_allocations.load();
      for (int k = 0; k < 6; ++k) {
        c.set_target(0, k % 3 == 2 ? Vec3(2, 1, 0) : Vec3(0.3 - 0.02 * k, 0.4, 0.1));
        solver.solve();
      }
      EXPECT_EQ(g_allocations.load() - before, 0) << name(m) << " on a chain";
    }
  }
  // the analytic solvers too
  Skeleton s(two_bones());
  SkeletonDef d = two_bones();
  d.bones[1].joint = JointType::Hinge;
  Skeleton limb(d);
  limb.add_effector(1, Vec3(0.7, 0.7, 0));
  limb.set_pole(0, Vec3(0, 1, 0));
  Solver two(limb, Method::TwoBone);
  const long long before = g_allocations.load();
  for (int k = 0; k < 10; ++k) {
    limb.set_target(0, Vec3(0.7, 0.7 - 0.05 * k, 0));
    two.solve();
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
}

TEST(IkBlend, MovesOnlyOnceSolvedThenBlendsThere) {
  Skeleton s = scenes::make_chain(10, JointType::Ball, true);
  const auto targets = scenes::random_targets(s, 9, 1, 5);
  s.add_effector(9, targets[0].position);
  SolverSettings st;
  st.method = Method::Fabrik;
  SolveThenBlend blend(s, st, Blend::Slerp, 10.0, 3);
  const std::uint64_t h0 = s.state_hash();
  const SolveResult r = blend.update(0.0);  // dt = 0: solved, goal set, nothing moved yet
  ASSERT_TRUE(r.converged);
  EXPECT_EQ(s.state_hash(), h0);
  EXPECT_TRUE(blend.blending());
  double last = s.max_effector_error();
  for (int f = 0; f < 240 && blend.blending(); ++f) {
    blend.update(1.0 / 60);
    ASSERT_TRUE(s.within_limits());
    EXPECT_LE(s.max_effector_error(), last + 1e-3);  // approaches, no wild swings
    last = s.max_effector_error();
  }
  EXPECT_FALSE(blend.blending());
  EXPECT_LT(s.max_effector_error(), 2e-4);
  // an unreachable target: no solution, so the visible pose does not move
  s.set_target(0, Vec3(5, 0, 0));
  const std::uint64_t h1 = s.state_hash();
  EXPECT_FALSE(blend.update(1.0 / 60).converged);
  EXPECT_EQ(s.state_hash(), h1);
}

TEST(IkSettings, ATimeBudgetStopsALongSolve) {
  // CCD on 1000 limited ball joints from a cold start: one sweep takes about 0.2 ms here and
  // the solve 26 sweeps (measured); with a budget of 1 us, the clock (read before every
  // sweep at this length) must stop it after the first sweep on any machine, and say so
  Skeleton s = scenes::make_chain(1000, JointType::Ball, true);
  const auto targets = scenes::random_targets(s, 999, 1, 3);
  s.add_effector(999, targets[0].position);
  SolverSettings st;
  st.method = Method::Ccd;
  st.max_seconds = 1e-6;
  Solver solver(s, st);
  const double cpu_before = test::thread_cpu_seconds();
  const SolveResult r = solver.solve();
  const double cpu = test::thread_cpu_seconds() - cpu_before;
  EXPECT_TRUE(r.out_of_time);
  EXPECT_FALSE(r.converged);
  EXPECT_LE(r.iterations, 1);
  // one sweep's work (0.2 ms) with a margin for a slower machine; the solve's CPU time,
  // since a loaded machine stretches its wall time
  EXPECT_LT(cpu, 0.02);
  EXPECT_TRUE(s.within_limits(1e-9));
  // without a budget nothing reports running out of time
  st.max_seconds = 0;
  solver.set_settings(st);
  s.set_target(0, targets[0].position + Vec3(0, 0, 1e-3));
  st.max_iterations = 3;
  solver.set_settings(st);
  EXPECT_FALSE(solver.solve().out_of_time);
  st.max_seconds = -1;
  EXPECT_EQ(error_of([&] { solver.set_settings(st); }), "SolverSettings.max_seconds: must be finite and >= 0, got -1");
}

// a DebugDraw that counts what it is asked to draw and keeps the capsules' radii
struct DrawRecorder final : DebugDraw {
  int capsules = 0, spheres = 0, lines = 0;
  std::vector<double> radii;
  void capsule(const Vec3&, const Vec3&, double radius, Color) override { ++capsules, radii.push_back(radius); }
  void sphere(const Vec3&, double, Color) override { ++spheres; }
  void line(const Vec3&, const Vec3&, Color) override { ++lines; }
  void point(const Vec3&, float, Color) override {}
  void box(const Vec3&, const Vec3&, const Quat&, Color) override {}
  void plane(const Vec3&, double, double, Color) override {}
  void arrow(const Vec3&, const Vec3&, double, Color) override {}
  void text(const Vec3&, std::string_view, Color) override {}
};

TEST(IkDraw, BoneRadiusOptions) {
  Skeleton s = scenes::make_chain(1000, JointType::Ball, false);  // 1 mm bones
  SkeletonDrawOptions o;
  DrawRecorder a;
  s.draw(a, o);
  ASSERT_EQ(a.radii.size(), 1000u);
  EXPECT_DOUBLE_EQ(a.radii[0], 0.08e-3);  // 8% of the length by default
  o.min_radius = 0.004;
  DrawRecorder b;
  s.draw(b, o);
  EXPECT_DOUBLE_EQ(b.radii[500], 0.004);
  o.bone_radius = 0.002;  // a fixed radius, still at least min_radius
  DrawRecorder c;
  s.draw(c, o);
  EXPECT_DOUBLE_EQ(c.radii[500], 0.004);
  o.min_radius = 0;
  DrawRecorder d;
  s.draw(d, o);
  EXPECT_DOUBLE_EQ(d.radii[999], 0.002);
  o.min_radius = -1;
  EXPECT_EQ(error_of([&] { s.draw(d, o); }), "SkeletonDrawOptions.min_radius: must be finite and >= 0, got -1");
  o.min_radius = 0;
  o.bone_radius = kNaN;
  EXPECT_EQ(error_of([&] { s.draw(d, o); }), "SkeletonDrawOptions.bone_radius: must be finite and >= 0, got nan");
}

TEST(IkDraw, DrawsBonesJointsAndTargets) {
  DrawRecorder dd;
  Skeleton s = scenes::make_chain(5, JointType::Hinge, true);
  s.add_effector(4, Vec3(0.5, 0.5, 0));
  SkeletonDrawOptions o;
  o.limits = true;
  s.draw(dd, o);
  EXPECT_EQ(dd.capsules, 5);
  EXPECT_EQ(dd.spheres, 6);  // 5 joints + 1 target
  EXPECT_GT(dd.lines, 5 * 16);  // limit arcs and the error line
}

}  // namespace
