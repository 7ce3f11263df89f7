// Skeleton: validation, topological ordering, pose, forward kinematics,
// end-effectors and debug drawing.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "ik/ik_math.h"
#include "pba/ik.h"

namespace pba::ik {


namespace {

std::string bone_where(int i, const BoneDef& b, const char* field) {
  std::string s = "SkeletonDef.bones[" + std::to_string(i) + "]";
  if (!b.name.empty()) s += " ('" + b.name + "')";
  return s + "." + field;
}

void require_unit_quat(const Quat& q, const std::string& where) {
  for (int c = 0; c < 4; ++c) require_finite(q[c], where);
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (std::abs(n - 1) > 1e-6)
    throw Error(where + ": must be a unit quaternion, got norm " + format_value(n));
}

}  // namespace

Skeleton::Skeleton(const SkeletonDef& def) {
  const int n = static_cast<int>(def.bones.size());
  if (n < 1) throw Error("SkeletonDef.bones: must hold at least one bone, got 0");
  // lengths and positions beyond a float's range overflow the solvers' squared errors (their
  // costs, the transpose's step length): the pose came back non-finite or not at the target
  require_float(def.root_position, "SkeletonDef.root_position");
  require_unit_quat(def.root_rotation, "SkeletonDef.root_rotation");

  // validate each bone on its own
  int root = -1;
  for (int i = 0; i < n; ++i) {
    const BoneDef& b = def.bones[i];
    if (b.parent < -1 || b.parent >= n)
      throw Error(bone_where(i, b, "parent") + ": must be -1 or a bone index in [0, " +
                  std::to_string(n - 1) + "], got " + std::to_string(b.parent));
    if (b.parent == i)
      throw Error(bone_where(i, b, "parent") + ": a bone cannot be its own parent (cycle)");
    if (b.parent == -1) {
      if (root >= 0)
        throw Error("SkeletonDef.bones: bones " + std::to_string(root) + " and " +
                    std::to_string(i) + " are both roots (parent -1); a skeleton has exactly one root");
      root = i;
    }
    require_positive(b.length, bone_where(i, b, "length"));
    if (!fits_float(b.length)) require_float(b.length, bone_where(i, b, "length"));
    require_unit_quat(b.rest, bone_where(i, b, "rest"));
    require_non_negative(b.radius, bone_where(i, b, "radius"));
    if (b.joint == JointType::Hinge) {
      const std::string w = bone_where(i, b, "axis");
      for (int c = 0; c < 3; ++c) require_finite(b.axis[c], w);
      const double len = glm::length(b.axis);
      if (std::abs(len - 1) > 1e-6)
        throw Error(w + ": must be a unit vector, got length " + format_value(len));
      require_in_range(b.min_angle, -kPi, kPi, bone_where(i, b, "min_angle"));
      require_in_range(b.max_angle, -kPi, kPi, bone_where(i, b, "max_angle"));
      if (b.min_angle > b.max_angle)
        throw Error(bone_where(i, b, "min_angle") + ": must be <= max_angle (" +
                    format_value(b.max_angle) + "), got " + format_value(b.min_angle));
    } else if (b.joint == JointType::Ball) {
      require_in_range(b.swing_limit, 0, kPi, bone_where(i, b, "swing_limit"));
      require_in_range(b.min_twist, -kPi, kPi, bone_where(i, b, "min_twist"));
      require_in_range(b.max_twist, -kPi, kPi, bone_where(i, b, "max_twist"));
      if (b.min_twist > b.max_twist)
        throw Error(bone_where(i, b, "min_twist") + ": must be <= max_twist (" +
                    format_value(b.max_twist) + "), got " + format_value(b.min_twist));
    }
  }
  if (root < 0)
    throw Error("SkeletonDef.bones: no root (every bone has a parent), so the hierarchy has a cycle");

  // order bones parents-first (breadth-first from the root); unreached bones sit on a cycle
  std::vector<std::vector<int>> children(n);
  for (int i = 0; i < n; ++i)
    if (def.bones[i].parent >= 0) children[def.bones[i].parent].push_back(i);
  std::vector<int> order;
  order.reserve(n);
  order.push_back(root);
  for (std::size_t k = 0; k < order.size(); ++k)
    for (int c : children[order[k]]) order.push_back(c);
  if (static_cast<int>(order.size()) != n) {
    std::vector<char> seen(n, 0);
    for (int i : order) seen[i] = 1;
    int bad = 0;
    while (seen[bad]) ++bad;
    throw Error(bone_where(bad, def.bones[bad], "parent") +
                ": the hierarchy has a cycle through this bone (parent " +
                std::to_string(def.bones[bad].parent) + ")");
  }
  def_to_stored_.assign(n, -1);
  for (int k = 0; k < n; ++k) def_to_stored_[order[k]] = k;

  // copy the model into stored order (structure of arrays)
  defs_.resize(n);
  parent_.resize(n);
  length_.resize(n);
  type_.resize(n);
  rest_.resize(n);
  rest_identity_.resize(n);
  axis_.resize(n);
  lo_.resize(n);
  hi_.resize(n);
  swing_.resize(n);
  limited_.resize(n);
  dof_offset_.resize(n);
  reach_.resize(n);
  root_free_ = def.root_free;
  int dof = root_free_ ? 3 : 0;
  for (int k = 0; k < n; ++k) {
    const BoneDef& b = def.bones[order[k]];
    defs_[k] = b;
    parent_[k] = b.parent < 0 ? -1 : def_to_stored_[b.parent];
    defs_[k].parent = parent_[k];
    length_[k] = b.length;
    type_[k] = b.joint;
    rest_[k] = glm::normalize(b.rest);
    rest_identity_[k] = rest_[k] == Quat(1, 0, 0, 0);
    axis_[k] = glm::normalize(b.axis);
    dof_offset_[k] = dof;
    total_length_ += b.length;
    reach_[k] = b.length + (parent_[k] >= 0 ? reach_[parent_[k]] : 0.0);
    if (b.joint == JointType::Hinge) {
      lo_[k] = b.min_angle;
      hi_[k] = b.max_angle;
      swing_[k] = 0;
      limited_[k] = (b.max_angle - b.min_angle) < 2 * kPi - 1e-9;
      dof += 1;
    } else if (b.joint == JointType::Ball) {
      lo_[k] = b.min_twist;
      hi_[k] = b.max_twist;
      swing_[k] = b.swing_limit;
      limited_[k] = b.swing_limit < kPi - 1e-9 || (b.max_twist - b.min_twist) < 2 * kPi - 1e-9;
      dof += 3;
    } else {
      lo_[k] = hi_[k] = swing_[k] = 0;
      limited_[k] = 0;
    }
  }
  dof_count_ = dof;
  root_position0_ = root_position_ = def.root_position;
  root_rotation_ = glm::normalize(def.root_rotation);

  // rest pose
  q_.assign(n, Quat(1, 0, 0, 0));
  angle_.assign(n, 0.0);
  world_.assign(n, Quat(1, 0, 0, 0));
  start_.assign(n, Vec3(0));
  tip_.assign(n, Vec3(0));
  for (int k = 0; k < n; ++k) clamp_joint(k);  // rest may lie outside asymmetric limits
  forward_kinematics();
}

Skeleton Skeleton::chain(int n, double length, JointType joint, const BoneDef& joint_template) {
  require_count(n, 1, 1 << 24, "Skeleton::chain n");
  require_positive(length, "Skeleton::chain length");
  require_float(length, "Skeleton::chain length");
  SkeletonDef def;
  def.bones.resize(n, joint_template);
  for (int i = 0; i < n; ++i) {
    def.bones[i].parent = i - 1;
    def.bones[i].length = length;
    def.bones[i].joint = joint;
  }
  return Skeleton(def);
}

int Skeleton::index_of(int def_index) const {
  require_count(def_index, 0, bone_count() - 1, "Skeleton::index_of");
  return def_to_stored_[def_index];
}

int Skeleton::find(std::string_view name) const {
  for (int i = 0; i < bone_count(); ++i)
    if (defs_[i].name == name) return i;
  return -1;
}

// an index into the skeleton's bones or effectors, checked before it is read (an index out of
// range was undefined behaviour in bone_def and effector)
void Skeleton::index_out_of_range(int i, int count, const char* what, const char* call) {
  throw Error(std::string(call) + ": " + what + " index " + std::to_string(i) + " out of range (the skeleton has " +
              std::to_string(count) + " " + what + (count == 1 ? "" : "s") + ")");
}

double Skeleton::reach(int bone) const {
  require_count(bone, 0, bone_count() - 1, "Skeleton::reach bone");
  return reach_[bone];
}

void Skeleton::clamp_joint(int i) {
  // project the joint rotation into its limits; hinges also wrap to (-pi, pi]
  switch (type_[i]) {
    case JointType::Fixed:
      q_[i] = Quat(1, 0, 0, 0);
      angle_[i] = 0;
      break;
    case JointType::Hinge: {
      double a = detail::wrap_angle(angle_[i]);
      if (limited_[i]) a = std::clamp(a, lo_[i], hi_[i]);
      angle_[i] = a;
      const double s = std::sin(0.5 * a);
      detail::put(q_[i], Quat(std::cos(0.5 * a), axis_[i].x * s, axis_[i].y * s, axis_[i].z * s));
      break;
    }
    case JointType::Ball:
      if (limited_[i])
        detail::put(q_[i], detail::clamp_ball(q_[i], swing_[i], lo_[i], hi_[i]));
      else
        detail::put(q_[i], glm::normalize(q_[i]));
      break;
  }
}

void Skeleton::set_joint_rotation(int i, const Quat& q) {
  fk_dirty_ = true;
  require_count(i, 0, bone_count() - 1, "Skeleton::set_joint_rotation bone");
  for (int c = 0; c < 4; ++c) require_finite(q[c], "Skeleton::set_joint_rotation q");
  const double n = glm::length(q);
  if (n < 1e-12) throw Error("Skeleton::set_joint_rotation q: must be non-zero, got norm 0");
  const Quat u = q / n;
  if (type_[i] == JointType::Hinge) {
    // the angle of the rotation's component about the hinge axis
    const double s = u.x * axis_[i].x + u.y * axis_[i].y + u.z * axis_[i].z;
    angle_[i] = 2 * std::atan2(s, u.w);
  } else {
    q_[i] = u;
  }
  clamp_joint(i);
}

void Skeleton::set_hinge_angle(int i, double angle) {
  fk_dirty_ = true;
  require_count(i, 0, bone_count() - 1, "Skeleton::set_hinge_angle bone");
  require_finite(angle, "Skeleton::set_hinge_angle angle");
  if (type_[i] != JointType::Hinge)
    throw Error("Skeleton::set_hinge_angle: bone " + std::to_string(i) + " is not a hinge");
  angle_[i] = angle;
  clamp_joint(i);
}

void Skeleton::reset_pose() {
  fk_dirty_ = true;
  std::fill(q_.begin(), q_.end(), Quat(1, 0, 0, 0));
  std::fill(angle_.begin(), angle_.end(), 0.0);
  root_position_ = root_position0_;
  for (int k = 0; k < bone_count(); ++k) clamp_joint(k);
}

void Skeleton::set_root_position(const Vec3& p) {
  fk_dirty_ = true;
  require_float(p, "Skeleton::set_root_position");
  root_position_ = p;
}

bool Skeleton::within_limits(double tol, int* bad) const {
  for (int i = 0; i < bone_count(); ++i) {
    bool ok = true;
    if (!is_finite(q_[i].w) || !is_finite(q_[i].x) || !is_finite(q_[i].y) || !is_finite(q_[i].z))
      ok = false;
    else if (type_[i] == JointType::Hinge) {
      if (limited_[i]) ok = angle_[i] >= lo_[i] - tol && angle_[i] <= hi_[i] + tol;
      // the quaternion must agree with the angle
      const double s = std::sin(0.5 * angle_[i]);
      const Quat e(std::cos(0.5 * angle_[i]), axis_[i].x * s, axis_[i].y * s, axis_[i].z * s);
      ok = ok && std::abs(std::abs(glm::dot(e, q_[i])) - 1) < 1e-9;
    } else if (type_[i] == JointType::Ball) {
      if (limited_[i]) {
        double swing, twist;
        detail::swing_twist_angles(q_[i], swing, twist);
        ok = swing <= swing_[i] + tol &&
             (swing > kPi - 1e-6 || (twist >= lo_[i] - tol && twist <= hi_[i] + tol));
      }
    } else {
      ok = q_[i].w == 1 && q_[i].x == 0 && q_[i].y == 0 && q_[i].z == 0;
    }
    if (!ok) {
      if (bad) *bad = i;
      return false;
    }
  }
  return true;
}

namespace {

// forward kinematics over a skeleton's arrays, parents before children (compiled for AVX2
// and the baseline, same bits: see PBA_CLONES)
PBA_CLONES void forward_pass(int n, const int* parent, const std::uint8_t* rest_identity, const Quat* rest,
                                const Quat* q, const double* length, const Quat& root_rotation,
                                const Vec3& root_position, Quat* world, Vec3* start, Vec3* tip) {
  for (int i = 0; i < n; ++i) {
    const int p = parent[i];
    const Quat base = p >= 0 ? world[p] : root_rotation;
    const Quat w = rest_identity[i] ? detail::qmul(base, q[i]) : detail::qmul(detail::qmul(base, rest[i]), q[i]);
    detail::put(world[i], w);
    const Vec3 st = p >= 0 ? tip[p] : root_position;
    start[i] = st;
    tip[i] = st + detail::rotate_x(w, length[i]);
  }
}

}  // namespace

void Skeleton::forward_kinematics() {
  // one pass, parents before children
  fk_dirty_ = false;
  forward_pass(bone_count(), parent_.data(), rest_identity_.data(), rest_.data(), q_.data(), length_.data(),
               root_rotation_, root_position_, world_.data(), start_.data(), tip_.data());
}

int Skeleton::add_effector(const EffectorDef& e) {
  const std::string where = "EffectorDef[" + std::to_string(effectors_.size()) + "]";
  if (e.bone < 0 || e.bone >= bone_count())
    throw Error(where + ".bone: must be a bone index in [0, " + std::to_string(bone_count() - 1) +
                "], got " + std::to_string(e.bone));
  require_in_range(e.weight, kMinEffectorWeight, kMaxEffectorWeight, where + ".weight");
  effectors_.push_back({e.bone, Vec3(0), std::nullopt, e.weight, std::nullopt});
  const int k = static_cast<int>(effectors_.size()) - 1;
  try {
    set_target(k, e.target);
    set_orientation_target(k, e.orientation);
    set_pole(k, e.pole);
  } catch (...) {
    effectors_.pop_back();
    throw;
  }
  ++effector_version_;
  return k;
}

int Skeleton::add_effector(int bone, const Vec3& target, double weight) {
  EffectorDef e;
  e.bone = bone;
  e.target = target;
  e.weight = weight;
  return add_effector(e);
}

void Skeleton::clear_effectors() {
  effectors_.clear();
  ++effector_version_;
}

void Skeleton::set_target(int k, const Vec3& target) {
  require_count(k, 0, effector_count() - 1, "Skeleton::set_target effector");
  if (!fits_float(target)) require_float(target, "effector " + std::to_string(k) + " target");
  effectors_[k].target = target;
}

void Skeleton::set_orientation_target(int k, std::optional<Quat> q) {
  require_count(k, 0, effector_count() - 1, "Skeleton::set_orientation_target effector");
  if (q) {
    // build the message only on failure: setting a target never allocates
    auto where = [k] { return "effector " + std::to_string(k) + " orientation"; };
    for (int c = 0; c < 4; ++c)
      if (!std::isfinite((*q)[c])) require_finite((*q)[c], where());
    const double n = glm::length(*q);
    if (n < 1e-12) throw Error(where() + ": must be a non-zero quaternion, got norm 0");
    q = *q / n;
  }
  effectors_[k].orientation = q;
}

void Skeleton::set_pole(int k, std::optional<Vec3> pole) {
  require_count(k, 0, effector_count() - 1, "Skeleton::set_pole effector");
  if (pole && !fits_float(*pole)) require_float(*pole, "effector " + std::to_string(k) + " pole");
  effectors_[k].pole = pole;
}

double Skeleton::effector_error(int k) const {
  if (k < 0 || k >= effector_count()) index_out_of_range(k, effector_count(), "effector", "Skeleton::effector_error");
  return glm::length(tip_[effectors_[k].bone] - effectors_[k].target);
}

double Skeleton::max_effector_error() const {
  double e = 0;
  for (int k = 0; k < effector_count(); ++k) e = std::max(e, effector_error(k));
  return e;
}

std::uint64_t Skeleton::state_hash() const {
  std::uint64_t h = hash_span(std::span<const Quat>(q_));
  h = hash_span(std::span<const double>(angle_), h);
  h = hash_span(std::span<const Vec3>(tip_), h);
  return hash_bytes(&root_position_, sizeof root_position_, h);
}

void Skeleton::draw(DebugDraw& dd, const SkeletonDrawOptions& o) const {
  require_non_negative(o.bone_radius, "SkeletonDrawOptions.bone_radius");
  require_non_negative(o.min_radius, "SkeletonDrawOptions.min_radius");
  for (int i = 0; i < bone_count(); ++i) {
    const double r = std::max(o.min_radius, o.bone_radius > 0   ? o.bone_radius
                                            : defs_[i].radius > 0 ? defs_[i].radius
                                                                  : 0.08 * length_[i]);
    // the bone as a capsule from its joint to its tip
    if (o.bones) dd.capsule(start_[i], tip_[i], r, o.bone_color);
    // the joint, coloured by type
    if (o.joints) {
      const Color c = type_[i] == JointType::Hinge  ? colors::orange
                      : type_[i] == JointType::Ball ? colors::cyan
                                                    : colors::white;
      dd.sphere(start_[i], 1.3 * r, c);
    }
    if (o.frames) {
      dd.line(start_[i], start_[i] + detail::rotate(world_[i], Vec3(2 * r, 0, 0)), colors::red);
      dd.line(start_[i], start_[i] + detail::rotate(world_[i], Vec3(0, 2 * r, 0)), colors::green);
      dd.line(start_[i], start_[i] + detail::rotate(world_[i], Vec3(0, 0, 2 * r)), colors::blue);
    }
    // joint limits: a hinge's allowed arc, a ball's swing cone
    if (o.limits && limited_[i]) {
      const int p = parent_[i];
      const Quat frame = (p >= 0 ? world_[p] : root_rotation_) * rest_[i];
      const double len = 0.5 * length_[i];
      constexpr int kSeg = 16;
      if (type_[i] == JointType::Hinge) {
        Vec3 prev{};
        for (int s = 0; s <= kSeg; ++s) {
          const double a = lo_[i] + (hi_[i] - lo_[i]) * s / kSeg;
          const Vec3 pt = start_[i] + detail::rotate(frame * glm::angleAxis(a, axis_[i]), Vec3(len, 0, 0));
          if (s == 0 || s == kSeg) dd.line(start_[i], pt, colors::yellow);
          if (s > 0) dd.line(prev, pt, colors::yellow);
          prev = pt;
        }
      } else if (type_[i] == JointType::Ball && swing_[i] < kPi - 1e-9) {
        const double c = std::cos(swing_[i]) * len, s = std::sin(swing_[i]) * len;
        Vec3 prev{};
        for (int k = 0; k <= kSeg; ++k) {
          const double phi = 2 * kPi * k / kSeg;
          const Vec3 pt = start_[i] + detail::rotate(frame, Vec3(c, s * std::cos(phi), s * std::sin(phi)));
          if (k % 4 == 0) dd.line(start_[i], pt, colors::yellow);
          if (k > 0) dd.line(prev, pt, colors::yellow);
          prev = pt;
        }
      }
    }
  }
  // targets, with a line from each effector to its target
  if (o.targets) {
    for (const EffectorDef& e : effectors_) {
      const double r = 0.12 * length_[e.bone];
      dd.sphere(e.target, r, colors::red);
      dd.line(tip_[e.bone], e.target, colors::pink);
      if (e.orientation)
        dd.line(e.target, e.target + detail::rotate(*e.orientation, Vec3(3 * r, 0, 0)), colors::red);
      if (e.pole) dd.sphere(*e.pole, 0.6 * r, colors::purple);
    }
  }
}

}  // namespace pba::ik
