// IK scenes shared by the samples, the tests and bench/bench_ik.cpp (one set of scenes
// for all three): chains 1 m long, a Y-shaped tree, a two-bone limb and a humanoid; the
// bent start pose for cold solves; random poses and reachable targets (random joint
// angles, fixed seed).
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "pba/ik.h"

namespace pba::ik::scenes {

/// Joint limits used for "limited" chains (rad).
inline constexpr double kHingeLimit = 1.0;    // hinges in [-1, 1]
inline constexpr double kSwingLimit = 0.6;    // ball swing cone half-angle
inline constexpr double kTwistLimit = 0.5;    // ball twist in [-0.5, 0.5]

/// The definition of a chain of n bones, total length 1 m, along +X, on joints of kind
/// `joint_of(i)`; hinges alternate between local Z and Y axes so the chain reaches in 3D.
template <class JointOf>
inline SkeletonDef chain_def(int n, bool limited, JointOf joint_of) {
  SkeletonDef def;
  def.bones.resize(n);
  for (int i = 0; i < n; ++i) {
    BoneDef& b = def.bones[i];
    b.parent = i - 1;
    b.length = 1.0 / n;
    b.joint = joint_of(i);
    b.axis = (i % 2 == 0) ? Vec3(0, 0, 1) : Vec3(0, 1, 0);
    if (limited) {
      b.min_angle = -kHingeLimit;
      b.max_angle = kHingeLimit;
      b.swing_limit = kSwingLimit;
      b.min_twist = -kTwistLimit;
      b.max_twist = kTwistLimit;
    }
  }
  return def;
}

/// A chain of n bones, total length 1 m, along +X, all on `type` joints. Hinges alternate
/// between local Z and Y axes so the chain reaches in 3D.
inline Skeleton make_chain(int n, JointType type, bool limited) {
  return Skeleton(chain_def(n, limited, [type](int) { return type; }));
}

/// A chain of n bones, total length 1 m, along +X, mixing joint kinds: every third bone
/// (the root first) on a ball joint, the others on hinges about local Z and Y in turn
/// (as in make_chain). The root's ball joint can aim the straight chain anywhere.
inline Skeleton make_mixed_chain(int n, bool limited) {
  return Skeleton(chain_def(n, limited, [](int i) { return i % 3 == 0 ? JointType::Ball : JointType::Hinge; }));
}

/// The common start pose for cold solves: every joint bent a little about its first
/// axis (a curve, away from the straight-chain singularity), inside any limits.
inline void bent_pose(Skeleton& s) {
  s.reset_pose();
  const double a = std::min(0.3, 3.0 / s.bone_count());
  for (int i = 0; i < s.bone_count(); ++i) {
    if (s.joint_types()[i] == JointType::Hinge)
      s.set_hinge_angle(i, (i % 2 == 0) ? a : 0.0);
    else if (s.joint_types()[i] == JointType::Ball)
      s.set_joint_rotation(i, glm::angleAxis(a, Vec3(0, 0, 1)));
  }
  s.forward_kinematics();
}

/// Random joint angles inside the limits (hinges uniform in their range, or [-pi/2, pi/2]
/// when unlimited; ball swing uniform in [0, min(limit, pi/2)] about a random
/// perpendicular axis, twist uniform in range or [-pi/2, pi/2]).
inline void random_pose(Skeleton& s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double half_pi = 1.5707963267948966;
  for (int i = 0; i < s.bone_count(); ++i) {
    const BoneDef& b = s.bone_def(i);
    if (b.joint == JointType::Hinge) {
      const double lo = std::max(b.min_angle, -half_pi), hi = std::min(b.max_angle, half_pi);
      s.set_hinge_angle(i, lo + (hi - lo) * u01(rng));
    } else if (b.joint == JointType::Ball) {
      const double sw = std::min(b.swing_limit, half_pi) * u01(rng);
      const double phi = 2 * kPi * u01(rng);
      const double tlo = std::max(b.min_twist, -half_pi), thi = std::min(b.max_twist, half_pi);
      const double tw = tlo + (thi - tlo) * u01(rng);
      const Quat swing = glm::angleAxis(sw, Vec3(0, std::cos(phi), std::sin(phi)));
      s.set_joint_rotation(i, swing * glm::angleAxis(tw, Vec3(1, 0, 0)));
    }
  }
  s.forward_kinematics();
}

/// `count` reachable targets for the tip of `bone`: the tip positions (and world
/// rotations) of random poses. Leaves the skeleton in its bent pose.
struct Target {
  Vec3 position;
  Quat rotation;
};
inline std::vector<Target> random_targets(Skeleton& s, int bone, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Target> out;
  out.reserve(count);
  for (int k = 0; k < count; ++k) {
    random_pose(s, rng);
    out.push_back({s.tips()[bone], s.world_rotations()[bone]});
  }
  bent_pose(s);
  return out;
}

/// A Y: a trunk of 3 bones going up (+Y) from the origin, forking into two branches of
/// 4 bones turned +-0.8 rad about Z; every bone 0.1 m, ball joints (limited: 0.8 rad
/// cones, +-0.5 rad twist). The two leaves are the last two bones.
inline Skeleton make_y_tree(bool limited) {
  SkeletonDef def;
  auto add = [&](int parent, double angle) {
    BoneDef b;
    b.parent = parent;
    b.length = 0.1;
    b.rest = glm::angleAxis(angle, Vec3(0, 0, 1));
    if (limited) {
      b.swing_limit = 0.8;
      b.min_twist = -0.5;
      b.max_twist = 0.5;
    }
    def.bones.push_back(b);
    return static_cast<int>(def.bones.size()) - 1;
  };
  int p = add(-1, 1.5707963267948966);
  p = add(p, 0);
  const int fork = add(p, 0);
  int a = add(fork, 0.8), b = add(fork, -0.8);
  for (int i = 0; i < 3; ++i) a = add(a, 0), b = add(b, 0);
  return Skeleton(def);
}

/// A two-bone limb: a 0.3 m upper bone on a ball joint (the shoulder, at the origin) and a
/// 0.25 m lower bone on a hinge about local Z (the elbow, interior bend in [0, 2.8] rad),
/// the effector's bone for Method::TwoBone being bone 1.
inline Skeleton make_limb() {
  SkeletonDef def;
  def.bones.resize(2);
  def.bones[0].name = "upper";
  def.bones[0].length = 0.3;
  def.bones[1].name = "lower";
  def.bones[1].parent = 0;
  def.bones[1].length = 0.25;
  def.bones[1].joint = JointType::Hinge;
  def.bones[1].min_angle = 0;
  def.bones[1].max_angle = 2.8;
  return Skeleton(def);
}

/// A humanoid about 1.7 m tall standing on the origin's plane, facing +Z, Y up, with its
/// root (the pelvis) at `pelvis` (m): spine (3 ball joints), neck and head, clavicles
/// (fixed), arms (ball shoulder, hinge elbow, ball wrist), hips (fixed), legs (ball hip,
/// hinge knee). Named bones: "pelvis", "spine0".."spine2", "neck", "head", "clavicle_l/r",
/// "upper_arm_l/r", "forearm_l/r", "hand_l/r", "hip_l/r", "thigh_l/r", "shin_l/r".
/// Effectors for hands and feet go on "hand_l/r" and "shin_l/r" (the ankles).
inline Skeleton make_humanoid(const Vec3& pelvis = Vec3(0, 0.95, 0), bool root_free = false) {
  const double half_pi = 1.5707963267948966;
  SkeletonDef def;
  def.root_position = pelvis;
  def.root_free = root_free;
  auto add = [&](const char* name, int parent, double length, JointType joint, double rest_z,
                 double swing = kPi) {
    BoneDef b;
    b.name = name;
    b.parent = parent;
    b.length = length;
    b.joint = joint;
    b.rest = glm::angleAxis(rest_z, Vec3(0, 0, 1));
    b.swing_limit = swing;
    b.min_twist = -0.6;
    b.max_twist = 0.6;
    def.bones.push_back(b);
    return static_cast<int>(def.bones.size()) - 1;
  };
  // the root points up; every frame's +X is its bone direction
  const int root = add("pelvis", -1, 0.05, JointType::Fixed, half_pi);
  int spine = add("spine0", root, 0.15, JointType::Ball, 0, 0.35);
  spine = add("spine1", spine, 0.15, JointType::Ball, 0, 0.35);
  const int chest = add("spine2", spine, 0.15, JointType::Ball, 0, 0.35);
  const int neck = add("neck", chest, 0.1, JointType::Ball, 0, 0.5);
  add("head", neck, 0.15, JointType::Fixed, 0);
  for (int side = 0; side < 2; ++side) {
    const bool left = side == 0;
    const double s = left ? 1.0 : -1.0;  // left is world -X, right +X
    // clavicle sideways from the chest top, upper arm hanging down
    const int clav = add(left ? "clavicle_l" : "clavicle_r", chest, 0.18, JointType::Fixed, s * half_pi);
    const int upper = add(left ? "upper_arm_l" : "upper_arm_r", clav, 0.3, JointType::Ball, s * half_pi, 2.0);
    // elbows and knees rest slightly bent (0.2 rad), inside their ranges, so a solver
    // starting from the rest pose is not pinned at a limit on the straight limb
    const int fore = add(left ? "forearm_l" : "forearm_r", upper, 0.27, JointType::Hinge, -s * 0.2);
    def.bones[fore].axis = Vec3(0, 0, 1);
    def.bones[fore].min_angle = left ? -2.4 : -0.2;
    def.bones[fore].max_angle = left ? 0.2 : 2.4;
    add(left ? "hand_l" : "hand_r", fore, 0.08, JointType::Ball, 0, 0.9);
    // hip sideways-down from the pelvis, thigh and shin down
    const int hip = add(left ? "hip_l" : "hip_r", root, 0.1, JointType::Fixed, s * 2.3);
    const int thigh = add(left ? "thigh_l" : "thigh_r", hip, 0.42, JointType::Ball, s * (kPi - 2.3), 1.6);
    const int shin = add(left ? "shin_l" : "shin_r", thigh, 0.4, JointType::Hinge, s * 0.2);
    def.bones[shin].axis = Vec3(0, 0, 1);
    def.bones[shin].min_angle = left ? -0.2 : -2.2;
    def.bones[shin].max_angle = left ? 2.2 : 0.2;
  }
  return Skeleton(def);
}

}  // namespace pba::ik::scenes
