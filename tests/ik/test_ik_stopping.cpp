// Tests for how the IK solvers end a solve (issue 12, physics faults 2-4): no solver
// returns a pose worse than the one it was given; on chains mixing hinges and ball joints
// every iterative solver reaches the closest reachable pose of an unreachable target; CCD
// reaches the reachable targets of a long limited chain; SolveResult says why it stopped.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "pba/ik.h"
#include "pba/ik_scenes.h"

namespace {

using namespace pba;
using namespace pba::ik;

constexpr double kEps = std::numeric_limits<double>::epsilon();

// the iterative methods (the analytic ones need one or two joints)
constexpr Method kIterative[] = {Method::Ccd, Method::JacobianTranspose, Method::PseudoInverse,
                                 Method::Dls, Method::Sdls, Method::Fabrik};

// weighted squared position error over every effector (what "worse" means for the methods
// that ignore orientation targets, and for position-only effectors everywhere)
double squared_error(const Skeleton& s) {
  double c = 0;
  for (int k = 0; k < s.effector_count(); ++k) {
    const EffectorDef& ef = s.effector(k);
    const Vec3 d = s.tips()[ef.bone] - ef.target;
    c += ef.weight * ef.weight * glm::dot(d, d);
  }
  return c;
}

// random unit direction
Vec3 direction(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return glm::normalize(Vec3(g(rng), g(rng), g(rng)));
}

// ---------------------------------------------------------------------------
// fault 2: never worse than given

// The case: a 333-bone chain mixing hinges and ball joints, a target 1.7 m from
// the root of the 1 m chain. The pseudo-inverse went from 1.354 m to 1.523 m, the chain
// coiled. From the bent pose and from random poses (limited and free chains, targets near
// and far), no method may end with a larger error than it started with.
TEST(IkNeverWorse, NoMethodEndsFartherThanItStarted) {
  for (bool limited : {false, true}) {
    for (int n : {333, 30}) {
      Skeleton s = scenes::make_mixed_chain(n, limited);
      s.add_effector(n - 1, Vec3(0));
      std::mt19937_64 rng(41 + n);
      for (int k = 0; k < 6; ++k) {
        const Vec3 target = (k < 3 ? 1.7 : 0.9) * direction(rng);
        // a start pose: the bent pose, or a random one
        const bool bent = k % 2 == 0;
        std::vector<Quat> start;
        std::mt19937_64 pose_rng(7 * k + n);
        if (bent) scenes::bent_pose(s);
        else scenes::random_pose(s, pose_rng);
        start.assign(s.joint_rotations().begin(), s.joint_rotations().end());
        for (Method m : kIterative) {
          for (int i = 0; i < n; ++i) s.set_joint_rotation(i, start[i]);
          s.forward_kinematics();
          s.set_target(0, target);
          const double before = squared_error(s);
          Solver solver(s, m);
          const SolveResult r = solver.solve();
          // the pose after is the pose reported, and within the limits
          ASSERT_NEAR(r.residual * r.residual, squared_error(s), 1e-12);
          ASSERT_TRUE(s.within_limits(1e-9));
          EXPECT_LE(squared_error(s), before)
              << name(m) << ", " << n << (limited ? " limited" : " free") << " bones, case " << k
              << ": " << std::sqrt(before) << " m before, " << r.residual << " m after";
        }
      }
    }
  }
}

// Several effectors on a tree pulled apart (the two leaves of the Y toward opposite far
// points): the methods trade one effector against the other, but none may raise the
// weighted squared error it was given.
TEST(IkNeverWorse, TreesWithSeveralEffectors) {
  for (bool limited : {false, true}) {
    Skeleton s = scenes::make_y_tree(limited);
    const int a = s.bone_count() - 2, b = s.bone_count() - 1;
    s.add_effector(a, Vec3(0));
    s.add_effector(b, Vec3(0), 2.0);
    std::mt19937_64 rng(5);
    for (int k = 0; k < 20; ++k) {
      const Vec3 ta = 1.2 * direction(rng), tb = 0.2 * direction(rng) + Vec3(0, 0.4, 0);
      for (Method m : kIterative) {
        scenes::bent_pose(s);
        s.set_target(0, ta);
        s.set_target(1, tb);
        const double before = squared_error(s);
        Solver solver(s, m);
        solver.solve();
        ASSERT_TRUE(s.within_limits(1e-9));
        EXPECT_LE(squared_error(s), before) << name(m) << (limited ? " limited" : " free") << ", case " << k;
      }
    }
  }
}

// ---------------------------------------------------------------------------
// fault 3: the closest reachable pose on mixed chains

// On make_mixed_chain the root is a ball joint and every later joint can hold zero (hinge
// ranges and twist ranges contain 0, rest rotations are the identity), so the tip lies
// within L of the root and, for a target at |t| > L, the closest reachable pose is the
// straight chain toward it, at |t| - L, exactly: a lower bound that the straight chain
// attains. Limited chains can aim the straight chain wherever the root's cone allows.
// Tolerance: forward kinematics sums n rotated bone vectors, each within a few ulp of its
// length, so the tip is within ~4 n eps L of the exact one; 16 n eps L leaves a margin.
// Before: the methods stopped 3e-4 to 0.8 m from it (the 1%-progress rule, a coiled chain).
TEST(IkClosestPose, MixedChainsStraightenTowardUnreachableTargets) {
  for (bool limited : {false, true}) {
    for (int n : {333, 30, 7}) {
      Skeleton s = scenes::make_mixed_chain(n, limited);
      s.add_effector(n - 1, Vec3(0));
      const double L = s.total_length();
      const double tol = 16 * n * kEps * L;
      std::mt19937_64 rng(3 + n);
      int cases = 0;
      while (cases < 6) {
        Vec3 u = direction(rng);
        // inside the root's cone for limited chains (swing from +X below the limit)
        if (limited && u.x < std::cos(scenes::kSwingLimit)) continue;
        ++cases;
        const Vec3 target = (1.2 + 0.1 * cases) * L * u;
        for (Method m : kIterative) {
          scenes::bent_pose(s);
          s.set_target(0, target);
          Solver solver(s, m);
          const SolveResult r = solver.solve();
          EXPECT_NEAR(r.residual, glm::length(target) - L, tol)
              << name(m) << ", " << n << (limited ? " limited" : " free") << " bones";
          EXPECT_EQ(r.stop, StopReason::Stalled) << name(m);
          EXPECT_FALSE(r.converged);
          ASSERT_TRUE(s.within_limits(1e-9));
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------
// fault 4: CCD on long limited chains

// CCD on 333 limited hinges (alternating axes, +-1 rad) reached 82% of 100 reachable
// targets (random joint angles inside the limits, so each target has an exact solution)
// within its 1000-sweep cap, spending up to 100 ms; its sweeps bend the chain's end
// against its limits and stop getting closer. Now a stuck CCD hands over to damped least
// squares from the given pose: every target is reached and the result says how.
TEST(IkCcd, LongLimitedChainsReachEveryReachableTarget) {
  for (JointType jt : {JointType::Hinge, JointType::Ball}) {
    const int n = 333;
    Skeleton s = scenes::make_chain(n, jt, true);
    const auto targets = scenes::random_targets(s, n - 1, jt == JointType::Hinge ? 100 : 30, 1);
    s.add_effector(n - 1, Vec3(0));
    SolverSettings st;
    st.method = Method::Ccd;
    st.tolerance = 1e-4;
    Solver solver(s, st);
    int converged = 0, handed = 0;
    for (const auto& t : targets) {
      scenes::bent_pose(s);
      s.set_target(0, t.position);
      const SolveResult r = solver.solve();
      ASSERT_TRUE(s.within_limits(1e-9));
      converged += r.converged;
      handed += r.handed_over;
      EXPECT_EQ(r.stop, r.converged ? StopReason::Converged : StopReason::IterationCap);
    }
    EXPECT_EQ(converged, static_cast<int>(targets.size())) << (jt == JointType::Hinge ? "hinges" : "balls");
    // the hand-over is what reaches the hard ones (18 of the 100 hinge targets before)
    if (jt == JointType::Hinge) {
      EXPECT_GT(handed, 0);
    }
  }
}

// The result says why a solve stopped: converged, the iteration budget, the time budget, or
// stalled (a stationary pose: the closest reachable pose of an unreachable target).
TEST(IkStop, TheResultSaysWhyTheSolveStopped) {
  Skeleton s = scenes::make_chain(100, JointType::Ball, true);
  const auto targets = scenes::random_targets(s, 99, 1, 9);
  s.add_effector(99, targets[0].position);
  for (Method m : kIterative) {
    SolverSettings st;
    st.method = m;
    Solver solver(s, st);
    scenes::bent_pose(s);
    SolveResult r = solver.solve();
    EXPECT_TRUE(r.converged) << name(m);
    EXPECT_EQ(r.stop, StopReason::Converged) << name(m);
    // one iteration is not enough from the bent pose: the budget is reported
    st.max_iterations = 1;
    solver.set_settings(st);
    scenes::bent_pose(s);
    r = solver.solve();
    EXPECT_FALSE(r.converged) << name(m);
    EXPECT_EQ(r.stop, StopReason::IterationCap) << name(m);
    EXPECT_EQ(r.iterations, 1) << name(m);
  }
  // a free chain toward a far target ends stationary, on the straight chain
  Skeleton f = scenes::make_chain(20, JointType::Ball, false);
  f.add_effector(19, Vec3(0, 3, 0));
  Solver solver(f, Method::Dls);
  const SolveResult r = solver.solve();
  EXPECT_EQ(r.stop, StopReason::Stalled);
  EXPECT_NEAR(r.residual, 2.0, 16 * 20 * kEps);
  EXPECT_EQ(name(StopReason::IterationCap), "iteration_cap");
}

}  // namespace
