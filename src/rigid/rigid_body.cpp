// Rigid bodies: definitions, mass properties, storage and free motion.
#include "pba/rigid.h"

#include "collide/query_internal.h"
#include "contacts.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>

#include <Eigen/Eigenvalues>

namespace pba {

namespace {

// the rotation by `angle` (rad) about the unit `axis`
Quat axis_angle(const Vec3& axis, double angle) {
  const double s = std::sin(0.5 * angle);
  return Quat(std::cos(0.5 * angle), axis.x * s, axis.y * s, axis.z * s);
}

// `d`, or for a compound its children (each at the compound's pose composed with its own,
// with the compound's density and material), recursively, appended to `out`
void flatten_compound(const RigidShapeDef& d, std::vector<RigidShapeDef>& out) {
  if (d.shape.type != ShapeType::Compound) {
    out.push_back(d);
    return;
  }
  for (const CompoundChild& c : d.shape.compound->children) {
    RigidShapeDef child = d;
    child.shape = c.shape;
    child.local = compose(d.local, c.pose);
    flatten_compound(child, out);
  }
}

// the principal moments of a symmetric inertia and the rotation whose columns are the
// principal axes (a diagonal tensor keeps the identity, so simple bodies stay exact)
void principal_axes(const Mat3& inertia, Vec3& moments, Quat& rotation) {
  const bool diagonal = inertia[0][1] == 0 && inertia[0][2] == 0 && inertia[1][2] == 0 && inertia[1][0] == 0 &&
                        inertia[2][0] == 0 && inertia[2][1] == 0;
  if (diagonal) {
    moments = {inertia[0][0], inertia[1][1], inertia[2][2]};
    rotation = Quat(1, 0, 0, 0);
    return;
  }
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = 0.5 * (inertia[c][r] + inertia[r][c]);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(m);
  Eigen::Matrix3d axes = eig.eigenvectors();
  // a proper rotation: flip the last axis of a reflection
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  Mat3 r;
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r[c][k] = axes(k, c);
  moments = {eig.eigenvalues()(0), eig.eigenvalues()(1), eig.eigenvalues()(2)};
  rotation = glm::normalize(glm::quat_cast(r));
}

// the inertia of a point mass m at offset d about the origin (parallel-axis term)
Mat3 parallel_axis(double m, const Vec3& d) {
  Mat3 out(m * glm::dot(d, d));
  out -= m * glm::outerProduct(d, d);
  return out;
}

bool finite_quat(const Quat& q) {
  return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

// require_unit_quat's test without building a message
bool unit_quat(const Quat& q) { return finite_quat(q) && std::abs(glm::length(q) - 1.0) <= 1e-6; }

}  // namespace

std::string_view to_string(RigidSolverType t) {
  switch (t) {
    case RigidSolverType::SoftStep: return "soft-step";
    case RigidSolverType::SequentialImpulse: return "sequential-impulse";
    case RigidSolverType::Tgs: return "tgs";
    case RigidSolverType::Xpbd: return "xpbd";
  }
  return "unknown";
}

RigidSolverType parse_rigid_solver(std::string_view text, std::string_view where) {
  // exact match against the names; the error lists them all
  std::string names;
  for (const RigidSolverType t : kRigidSolvers) {
    if (text == to_string(t)) return t;
    names += (names.empty() ? "" : ", ") + std::string(to_string(t));
  }
  throw Error(std::string(where) + ": unknown rigid solver \"" + std::string(text) + "\"; valid: " + names);
}

void ContactSettings::validate(std::string_view where) const {
  if (static_cast<std::size_t>(solver) >= kRigidSolvers.size())
    throw Error(field_path(where, "solver") + ": unknown solver " + std::to_string(static_cast<int>(solver)));
  // a MixRule cast from a number outside the enum mixed as "the first shape's value" unnoticed
  for (const auto& [rule, name] : {std::pair{friction_mix, "friction_mix"}, std::pair{restitution_mix, "restitution_mix"}})
    if (static_cast<int>(rule) > static_cast<int>(MixRule::Product))
      throw Error(field_path(where, name) + ": unknown mix rule " + std::to_string(static_cast<int>(rule)) +
                  " (valid: 0 geometric mean, 1 minimum, 2 maximum, 3 average, 4 product)");
  require_count(substeps, 1, 64, field_path(where, "substeps"));
  require_count(iterations, 1, 1000, field_path(where, "iterations"));
  require_count(substep_iterations, 1, 100, field_path(where, "substep_iterations"));
  require_count(relax_iterations, 0, 100, field_path(where, "relax_iterations"));
  require_count(manifold_iterations, 1, 16, field_path(where, "manifold_iterations"));
  require_positive(contact_hertz, field_path(where, "contact_hertz"));
  require_non_negative(auto_substeps_sag, field_path(where, "auto_substeps_sag"));
  require_in_range(auto_substeps_sag_fraction, 0, 1, field_path(where, "auto_substeps_sag_fraction"));
  require_count(auto_substeps_least, 1, 64, field_path(where, "auto_substeps_least"));
  require_non_negative(damping_ratio, field_path(where, "damping_ratio"));
  require_positive(push_out_speed, field_path(where, "push_out_speed"));
  require_in_range(baumgarte, 0, 1, field_path(where, "baumgarte"));
  require_non_negative(contact_compliance, field_path(where, "contact_compliance"));
  require_non_negative(linear_slop, field_path(where, "linear_slop"));
  require_non_negative(speculative_distance, field_path(where, "speculative_distance"));
  require_non_negative(reuse_distance, field_path(where, "reuse_distance"));
  require_non_negative(reuse_angle, field_path(where, "reuse_angle"));
  require_non_negative(restitution_threshold, field_path(where, "restitution_threshold"));
  require_non_negative(sleep_linear, field_path(where, "sleep_linear"));
  require_non_negative(sleep_angular, field_path(where, "sleep_angular"));
  require_non_negative(time_to_sleep, field_path(where, "time_to_sleep"));
}

std::string_view to_string(BodyType t) {
  switch (t) {
    case BodyType::Static: return "static";
    case BodyType::Kinematic: return "kinematic";
    case BodyType::Dynamic: return "dynamic";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------
// mass properties

RigidMass RigidMass::box(double mass, const Vec3& h) {
  require_positive(mass, "RigidMass::box: mass (kg)");
  require_positive(h.x, "RigidMass::box: half.x (m)");
  require_positive(h.y, "RigidMass::box: half.y (m)");
  require_positive(h.z, "RigidMass::box: half.z (m)");
  const Vec3 d = 2.0 * h;
  const double k = mass / 12;
  Mat3 i(0.0);
  i[0][0] = k * (d.y * d.y + d.z * d.z);
  i[1][1] = k * (d.x * d.x + d.z * d.z);
  i[2][2] = k * (d.x * d.x + d.y * d.y);
  return {mass, {0, 0, 0}, i};
}

RigidMass RigidMass::sphere(double mass, double r) {
  require_positive(mass, "RigidMass::sphere: mass (kg)");
  require_positive(r, "RigidMass::sphere: r (m)");
  return {mass, {0, 0, 0}, Mat3(0.4 * mass * r * r)};
}

RigidMass RigidMass::operator+(const RigidMass& o) const {
  const double m = mass + o.mass;
  const Vec3 c = (mass * center + o.mass * o.center) / m;
  return {m, c, inertia + parallel_axis(mass, center - c) + o.inertia + parallel_axis(o.mass, o.center - c)};
}

void RigidMass::validate(std::string_view where) const {
  if (!(std::isfinite(mass) && mass > 0)) require_positive(mass, field_path(where, "mass"));
  // a position in the body frame, held as a float by the contact rows like a shape's placement
  require_float(center, field_path(where, "center"));
  const std::string w = field_path(where, "inertia");
  // finite and symmetric to rounding
  double scale = 0;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) {
      if (!std::isfinite(inertia[c][r]))
        throw Error(w + ": must be finite, got " + format_value(inertia[c][r]) + " at row " + std::to_string(r) +
                    ", column " + std::to_string(c));
      scale = std::max(scale, std::abs(inertia[c][r]));
    }
  for (int c = 0; c < 3; ++c)
    for (int r = c + 1; r < 3; ++r)
      if (std::abs(inertia[c][r] - inertia[r][c]) > 1e-9 * scale)
        throw Error(w + ": must be symmetric, got " + format_value(inertia[c][r]) + " and " +
                    format_value(inertia[r][c]) + " at (" + std::to_string(r) + ", " + std::to_string(c) + ")");
  // positive principal moments that a real mass distribution can have
  Vec3 m;
  Quat q;
  principal_axes(inertia, m, q);
  if (!(m.x > 0 && m.y > 0 && m.z > 0))
    throw Error(w + ": must be positive definite, got principal moments " + format_vec3(m));
  const double slack = 1e-9 * (m.x + m.y + m.z);
  if (m.x > m.y + m.z + slack || m.y > m.x + m.z + slack || m.z > m.x + m.y + slack)
    throw Error(w + ": principal moments " + format_vec3(m) +
                " break the triangle inequality (each must be at most the sum of the other two)");
}

namespace {
// |v| <= kMaxRigidSpeed, without building a message (false for NaN; |v|^2 overflows to inf
// only far beyond the limit)
bool speed_ok(const Vec3& v) { return glm::dot(v, v) <= kMaxRigidSpeed * kMaxRigidSpeed; }

// The one test of a shape's frame against the float range, at create (RigidBodyDef::validate),
// at set_pose and after each step (in_float_range): the position of the frame in the world
// for the body frame at `body`, as shape_frame places it for the narrow phase, whose bounds
// and contact rows hold it as floats (beyond, a step made NaN, or stopped with the narrow
// phase's message, which names no body)
bool frame_fits_float(const Pose& body, const RigidShapeDef& d) {
  return fits_float(detail::shape_frame(body, d.local).position);
}

// Throws Error unless frame_fits_float for shapes[k], the shape `d`, naming `what` (the pose
// checked, as the caller knows it) and both terms of the sum: "<what>: position (3e+38, 0, 0)
// + rotation * shapes[0].local.position (1e+38, 0, 0) = (4e+38, 0, 0) does not fit a float
// (|component| <= 3.4028234663852886e+38)"
void require_frame_float(const Pose& body, const RigidShapeDef& d, std::size_t k, std::string_view what) {
  if (frame_fits_float(body, d)) return;
  require_float_sum(detail::shape_frame(body, d.local).position,
                    "position " + format_vec3(body.position) + " + rotation * shapes[" + std::to_string(k) +
                        "].local.position " + format_vec3(body.rotation * d.local.position),
                    what);
}
}  // namespace

void require_rigid_speed(const Vec3& v, std::string_view where, std::string_view unit) {
  if (!is_finite(v)) require_finite(v, where);
  // |v| scaled by its largest component, which cannot overflow (1e308 m/s has a length)
  const double big = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  const double speed = big > 0 ? big * glm::length(v / big) : 0.0;
  if (speed <= kMaxRigidSpeed) return;
  throw Error(std::string(where) + ": " + format_vec3(v) + " has a magnitude of " + format_value(speed) + " " +
              std::string(unit) + ", above the rigid bodies' limit of " + format_value(kMaxRigidSpeed) + " " +
              std::string(unit) + " (the contact rows carry speeds and impulses in float)");
}

void RigidBodyDef::validate(std::string_view where) const {
  if (type != BodyType::Static && type != BodyType::Kinematic && type != BodyType::Dynamic)
    throw Error(field_path(where, "type") + ": unknown body type " + std::to_string(static_cast<int>(type)));
  // the shapes' bounds and the contact rows hold positions as floats (beyond, a step made NaN)
  require_float(pose.position, field_path(where, "pose.position"));
  require_unit_quat(pose.rotation, field_path(where, "pose.rotation"));
  require_rigid_speed(linear_velocity, field_path(where, "linear_velocity"), "m/s");
  require_rigid_speed(angular_velocity, field_path(where, "angular_velocity"), "rad/s");
  require_non_negative(linear_damping, field_path(where, "linear_damping"));
  require_non_negative(angular_damping, field_path(where, "angular_damping"));
  require_finite(gravity_scale, field_path(where, "gravity_scale"));
  if (shapes.empty()) throw Error(field_path(where, "shapes") + ": a body needs at least one shape, got none");
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const RigidShapeDef& d = shapes[k];
    const std::string w = field_path(where, "shapes[" + std::to_string(k) + "]");
    // valid, and its sizes the colliders' (a float's) as the queries and compounds check
    // them, whatever the body's type: a static plane's offset of 1e39 m or a capsule 1e300 m
    // long was taken, and the first contact made the other body's NaN; a dynamic box that
    // long with a given mass (no mass from the shapes to overflow) was taken, and its first
    // step stopped with the narrow phase's message, which names no body (hulls, meshes and
    // compounds hold their points to it when built)
    query::check_shape(d.shape, field_path(w, "shape"));
    require_float(d.local.position, field_path(w, "local.position"));
    // and so is the shape's frame in the world: the body's pose plus its turned local offset
    // (3e38 + 1e38 m was taken, and the first contact stopped with the narrow phase's message)
    require_frame_float(pose, d, k, field_path(where, "pose"));
    require_unit_quat(d.local.rotation, field_path(w, "local.rotation"));
    require_positive(d.density, field_path(w, "density"));
    require_in_range(d.material.restitution, 0, 1, field_path(w, "material.restitution"));
    require_non_negative(d.material.friction, field_path(w, "material.friction"));
    require_non_negative(d.rolling_resistance, field_path(w, "rolling_resistance"));
    const bool solid = d.shape.type != ShapeType::Plane && d.shape.type != ShapeType::Mesh;
    if (type != BodyType::Static && !solid)
      throw Error(field_path(w, "shape") + ": a " + std::string(to_string(d.shape.type)) +
                  " has no volume, so only a static body can have one (this body is " + std::string(to_string(type)) +
                  ")");
  }
  if (type == BodyType::Dynamic && mass) mass->validate(field_path(where, "mass"));
}

// ---------------------------------------------------------------------------------------
// storage

RigidBodySystem::RigidBodySystem(const RigidSystemDef& def) : contacts_(std::make_unique<detail::RigidContacts>()) {
  require_count(static_cast<long long>(def.capacity), 0, 1LL << 26, "RigidSystemDef.capacity");
  def.contacts.validate("RigidSystemDef.contacts");
  settings_ = validated_ = def.contacts;
  const std::size_t n = def.capacity;
  try {
    ids_.reserve(n);
    for (auto* v : {&slot_, &owner_}) v->reserve(n);
    type_.reserve(n);
    for (auto* v : {&com_, &v_, &w_, &force_, &torque_, &inv_inertia_, &inertia_, &com_local_, &com0_, &rest_com_, &rest_v_, &rest_w_})
      v->reserve(n);
    for (auto* v : {&q_, &principal_, &q0_, &rest_q_}) v->reserve(n);
    for (auto* v :
         {&inv_mass_, &lin_damp_, &ang_damp_, &gravity_scale_, &sleep_time_, &island_slow_, &extent_, &min_extent_})
      v->reserve(n);
    for (auto* v : {&island_, &parent_}) v->reserve(n);
    asleep_.reserve(n);
    for (auto& list : contacts_->moving) list.reserve(n);
    for (auto& list : contacts_->coasting) list.reserve(n);
    contacts_->drifting.reserve(n);
    // the spare velocity arrays finish_velocities swaps with v_ and w_ (reserved in the first
    // step, they asked for 48 B a body of capacity there, a bare std::bad_alloc from step())
    contacts_->start_v.reserve(n), contacts_->start_w.reserve(n);
    name_.reserve(n);
    bullet_.reserve(n);
    shapes_.reserve(n);
  } catch (const std::bad_alloc&) {
    // the largest capacity, 2^26 bodies, reserves some 38 GiB of address space (the process's
    // VmSize 38920 MiB after construction and after a step, 2026-12-07: 608 B a body): where the
    // memory (or a limit on it) cannot give that, say which value asked for it
    throw Error("RigidSystemDef.capacity: cannot reserve room for " + std::to_string(n) +
                " bodies: out of memory; give a smaller capacity (the arrays grow "
                "past it as bodies are created)");
  }
}

RigidBodySystem::~RigidBodySystem() = default;
RigidBodySystem::RigidBodySystem(RigidBodySystem&&) noexcept = default;
// a self-move keeps the system (see World's: a vector moved into itself gives up its elements)
RigidBodySystem& RigidBodySystem::operator=(RigidBodySystem&& o) noexcept {
  if (this != &o) std::destroy_at(this), std::construct_at(this, std::move(o));
  return *this;
}

namespace {

// A moved-from system's arrays are empty (the move took them, as from a std::vector) but its
// contact state is null: create() and step() dereferenced it (a moved-from World crashed in
// add_rigid_body). It is an empty system instead: the state is made afresh where it is
// written, and read as an empty one where it is only read.
detail::RigidContacts& contact_state(std::unique_ptr<detail::RigidContacts>& c) {
  if (!c) c = std::make_unique<detail::RigidContacts>();
  return *c;
}
const detail::RigidContacts& contact_state(const std::unique_ptr<detail::RigidContacts>& c) {
  static const detail::RigidContacts none;
  return c ? *c : none;
}

}  // namespace

std::string_view to_string(RigidSimd s) {
  switch (s) {
    case RigidSimd::Best: return "best";
    case RigidSimd::Scalar: return "scalar";
    case RigidSimd::Avx2: return "avx2";
    case RigidSimd::Avx512: return "avx512";
  }
  return "unknown";
}

void RigidBodySystem::set_simd(RigidSimd path) {
  using detail::SimdPath;
  const SimdPath best = detail::best_simd_path();
  SimdPath want = best;
  switch (path) {
    case RigidSimd::Best: break;
    case RigidSimd::Scalar: want = SimdPath::Scalar; break;
    case RigidSimd::Avx2: want = SimdPath::Avx2; break;
    case RigidSimd::Avx512: want = SimdPath::Avx512; break;
    default: throw Error("RigidBodySystem::set_simd: unknown path " + std::to_string(static_cast<int>(path)));
  }
  if (static_cast<int>(want) > static_cast<int>(best))
    throw Error("RigidBodySystem::set_simd: this CPU and build cannot run the " + std::string(to_string(path)) +
                " path (the widest it runs is " +
                std::string(best == SimdPath::Avx2 ? "avx2" : "scalar") + ")");
  contact_state(contacts_).simd = want;
}

RigidSimd RigidBodySystem::simd() const {
  switch (contact_state(contacts_).simd) {
    case detail::SimdPath::Scalar: return RigidSimd::Scalar;
    case detail::SimdPath::Avx2: return RigidSimd::Avx2;
    case detail::SimdPath::Avx512: return RigidSimd::Avx512;
  }
  return RigidSimd::Scalar;
}

void RigidBodySystem::set_lane_reuse(bool on) { contact_state(contacts_).reuse_lanes = on; }

void RigidBodySystem::set_substeps(int n) {
  // the call named, not the settings' field (the call sets it: "ContactSettings.substeps" sent
  // the reader to a struct the caller never wrote)
  require_count(n, 1, 64, "RigidBodySystem::set_substeps(n)");
  settings_.substeps = n;
  settings_.auto_substeps = false;
}

RigidBodyId RigidBodySystem::create(const RigidBodyDef& def, std::string_view where) {
  const std::string w = def.name.empty() ? std::string(where) : std::string(where) + " '" + def.name + "'";
  def.validate(w);
  // compounds become their leaves (nested compounds too, depth first), so the narrow phase
  // sees convex shapes, planes and meshes only
  std::vector<RigidShapeDef> shapes;
  for (const RigidShapeDef& d : def.shapes) flatten_compound(d, shapes);
  // a plane's normal must be unit, as collide() asks (ColliderShape::validate takes any
  // non-zero one, for queries that normalise): the contacts' narrow phase takes it as it is,
  // unchecked (collide_unchecked_into), so it is refused here, naming the body
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const ColliderShape& s = shapes[k].shape;
    if (s.type == ShapeType::Plane && !(std::abs(glm::length(s.normal) - 1) <= 1e-6))
      throw Error(w + ": shape " + std::to_string(k) + ": a plane's normal must be unit (|n| within 1e-6 of 1), got " +
                  format_vec3(s.normal) + " of length " + format_value(glm::length(s.normal)));
  }
  // the principal frame of a dynamic body (mass given, or from the shapes); others have no inertia
  Vec3 moments(0), inv(0);
  Quat principal(1, 0, 0, 0);
  Vec3 com_local(0);
  double inv_mass = 0;
  if (def.type == BodyType::Dynamic) {
    // from the shapes, the number alone does not say what to change (a 1e-9 m ball's moment,
    // 7e-43 kg m^2, named no size; a 1e-300 m ball's mass of 0 kg no shape): say it is the
    // shapes' size or density
    const auto from_shapes = [](const Error& e) {
      return Error(
          std::string(e.what()) +
          ": the shapes' sizes and densities make the body too small or light, or too large or heavy, "
          "for the contact solver's float rows (scale the shapes or the density, or give the mass and inertia)");
    };
    RigidMass m;
    if (def.mass) {
      m = *def.mass;
      // A centre of mass outside the shapes is legal (a hollow body's lies inside their hull,
      // a ballast left out of them near it), but one 1e20 m from a 0.5 m ball passed the
      // float range above and made the first step NaN (the contact rows square the lever
      // arms): refused beyond kMaxCenterOfMassOffset sizes of the shapes' bounds from them
      Aabb box = bounds(shapes[0].shape, shapes[0].local);
      for (std::size_t k = 1; k < shapes.size(); ++k) box = box.merged(bounds(shapes[k].shape, shapes[k].local));
      const double size = glm::length(box.hi - box.lo);
      const double out = glm::length(glm::max(glm::max(box.lo - m.center, m.center - box.hi), Vec3(0)));
      if (!(out <= kMaxCenterOfMassOffset * size))
        throw Error(field_path(field_path(w, "mass"), "center") + ": " + format_vec3(m.center) + " m lies " +
                    format_value(out) + " m outside the shapes' bounds " + format_vec3(box.lo) + " to " +
                    format_vec3(box.hi) + " (body frame): at most " + format_value(kMaxCenterOfMassOffset) +
                    " times their size (the bounds' diagonal, " + format_value(size) + " m) is allowed");
    } else {
      for (std::size_t k = 0; k < shapes.size(); ++k) {
        const RigidMass part = RigidMass::of_shape(shapes[k].shape, shapes[k].density, shapes[k].local,
                                                   field_path(w, "shapes[" + std::to_string(k) + "]"));
        m = k == 0 ? part : m + part;
      }
      try {
        m.validate(field_path(w, "mass (from the shapes)"));
      } catch (const Error& e) {
        throw from_shapes(e);  // (a mass of 0 or inf, or a NaN inertia: sizes past the doubles)
      }
    }
    principal_axes(m.inertia, moments, principal);
    // the contact solver's blocks hold inverse masses and inertias, and effective masses, as
    // floats (src/rigid/solver.h): outside these ranges the first contact is NaN
    const std::string mw = def.mass ? field_path(w, "mass") : field_path(w, "mass (from the shapes)");
    try {
      require_float_inverse(m.mass, field_path(mw, "mass"));
      for (int a = 0; a < 3; ++a)
        require_float_inverse(moments[a], field_path(mw, "principal moment " + std::to_string(a) + " (kg m^2)"));
    } catch (const Error& e) {
      if (def.mass) throw;
      throw from_shapes(e);
    }
    inv = 1.0 / moments;
    inv_mass = 1.0 / m.mass;
    com_local = m.center;
  }
  const RigidBodyId id = ids_.create();
  if (slot_.size() <= id.index) slot_.resize(id.index + 1);
  slot_[id.index] = static_cast<std::uint32_t>(type_.size());
  owner_.push_back(id.index);
  type_.push_back(def.type);
  com_.push_back(apply(def.pose, com_local));
  q_.push_back(glm::normalize(def.pose.rotation * principal));
  v_.push_back(def.type == BodyType::Static ? Vec3(0) : def.linear_velocity);
  w_.push_back(def.type == BodyType::Static ? Vec3(0) : def.angular_velocity);
  force_.push_back(Vec3(0));
  torque_.push_back(Vec3(0));
  inv_mass_.push_back(inv_mass);
  inv_inertia_.push_back(inv);
  inertia_.push_back(moments);
  lin_damp_.push_back(def.linear_damping);
  ang_damp_.push_back(def.angular_damping);
  gravity_scale_.push_back(def.gravity_scale);
  com_local_.push_back(com_local);
  principal_.push_back(principal);
  name_.push_back(def.name);
  bullet_.push_back(def.bullet ? 1 : 0);
  // the reach of the shapes about the centre of mass, and their thinnest part (planes and
  // meshes have no finite reach; the contacts read both for every body: the pairs' speculative
  // and reuse distances, the broad phase's reach)
  double reach = 0, thin = INFINITY;
  for (const RigidShapeDef& d : shapes) {
    if (d.shape.type == ShapeType::Plane || d.shape.type == ShapeType::Mesh) {
      reach = INFINITY;
      continue;
    }
    const Aabb b = bounds(d.shape, compose(Pose{-com_local}, d.local));
    reach = std::max(reach, glm::length(glm::max(glm::abs(b.lo), glm::abs(b.hi))));
    const Aabb own = bounds(d.shape, Pose{});
    const Vec3 half = 0.5 * (own.hi - own.lo);
    thin = std::min(thin, std::min(half.x, std::min(half.y, half.z)));
  }
  extent_.push_back(reach);
  min_extent_.push_back(thin);
  detail::RigidContacts& state = contact_state(contacts_);
  state.thinnest = std::min(state.thinnest, thin);
  for (const RigidShapeDef& d : shapes)
    state.frame_reach = std::max(state.frame_reach, glm::length(d.local.position - com_local));
  shapes_.push_back(std::move(shapes));
  asleep_.push_back(0);
  sleep_time_.push_back(0);
  rest_com_.push_back(com_.back());
  rest_q_.push_back(q_.back());
  rest_v_.push_back(v_.back());
  rest_w_.push_back(w_.back());
  island_.push_back(static_cast<std::uint32_t>(type_.size() - 1));
  parent_.push_back(0);
  island_slow_.push_back(0);
  com0_.push_back(com_.back());
  q0_.push_back(q_.back());
  return id;
}

void RigidBodySystem::destroy(RigidBodyId id) {
  const std::size_t i = index(id, "RigidBodySystem::destroy");
  const std::size_t last = type_.size() - 1;
  // move the last body into the hole (every array, then the handle maps)
  auto fill = [&](auto& v) {
    v[i] = std::move(v[last]);
    v.pop_back();
  };
  fill(type_), fill(com_), fill(q_), fill(v_), fill(w_), fill(force_), fill(torque_), fill(inv_mass_);
  fill(inv_inertia_), fill(inertia_), fill(lin_damp_), fill(ang_damp_), fill(gravity_scale_);
  fill(com_local_), fill(principal_), fill(name_), fill(bullet_), fill(extent_), fill(min_extent_), fill(shapes_);
  fill(com0_), fill(q0_);
  fill(asleep_), fill(sleep_time_), fill(island_), fill(parent_), fill(island_slow_), fill(rest_com_), fill(rest_q_);
  fill(rest_v_), fill(rest_w_);
  const std::uint32_t moved = owner_[last];
  owner_[i] = moved;
  owner_.pop_back();
  slot_[moved] = static_cast<std::uint32_t>(i);
  // the body's shapes, pairs and contacts go; the others follow the moved body to its new index
  contacts_->remove_body(*this, id.index, i);
  contacts_->has_colors = false;  // the colours were by pair index
  ids_.destroy(id, "RigidBodySystem::destroy");
  // the islands' indices moved: wake everyone (rare; the next step finds the islands again)
  for (std::size_t k = 0; k < type_.size(); ++k) {
    asleep_[k] = 0, sleep_time_[k] = 0, island_[k] = static_cast<std::uint32_t>(k);
    rest_com_[k] = com_[k], rest_q_[k] = q_[k], rest_v_[k] = v_[k], rest_w_[k] = w_[k];
  }
}

void RigidBodySystem::id_out_of_range(std::size_t i) const {
  // (a std::out_of_range from the vector's at() before, whose message named no call)
  throw Error("RigidBodySystem::id_at: index " + std::to_string(i) + " out of range [0, " +
              std::to_string(owner_.size()) + ")");
}

std::size_t RigidBodySystem::index(RigidBodyId id, std::string_view where) const {
  ids_.require(id, where);
  return slot_[id.index];
}

std::string RigidBodySystem::describe(std::size_t i) const {
  return "rigid body " + std::to_string(owner_[i]) + (name_[i].empty() ? "" : " '" + name_[i] + "'");
}

// ---------------------------------------------------------------------------------------
// state

Pose RigidBodySystem::pose(RigidBodyId id) const {
  return body_pose(index(id, "RigidBodySystem::pose"));
}

Vec3 RigidBodySystem::center_of_mass(RigidBodyId id) const {
  return com_[index(id, "RigidBodySystem::center_of_mass")];
}
Vec3 RigidBodySystem::linear_velocity(RigidBodyId id) const {
  return v_[index(id, "RigidBodySystem::linear_velocity")];
}
Vec3 RigidBodySystem::angular_velocity(RigidBodyId id) const {
  return w_[index(id, "RigidBodySystem::angular_velocity")];
}
BodyType RigidBodySystem::type(RigidBodyId id) const { return type_[index(id, "RigidBodySystem::type")]; }
const std::string& RigidBodySystem::name(RigidBodyId id) const { return name_[index(id, "RigidBodySystem::name")]; }

Vec3 RigidBodySystem::velocity_at(RigidBodyId id, const Vec3& p) const {
  const std::size_t i = index(id, "RigidBodySystem::velocity_at");
  return v_[i] + glm::cross(w_[i], p - com_[i]);
}

double RigidBodySystem::mass(RigidBodyId id) const {
  const std::size_t i = index(id, "RigidBodySystem::mass");
  return inv_mass_[i] > 0 ? 1.0 / inv_mass_[i] : INFINITY;
}

Mat3 RigidBodySystem::world_inertia(RigidBodyId id) const {
  const std::size_t i = index(id, "RigidBodySystem::world_inertia");
  const Mat3 r = glm::mat3_cast(q_[i]);
  Mat3 d(0.0);
  d[0][0] = inertia_[i].x, d[1][1] = inertia_[i].y, d[2][2] = inertia_[i].z;
  return r * d * glm::transpose(r);
}

Vec3 RigidBodySystem::angular_momentum(RigidBodyId id) const {
  const std::size_t i = index(id, "RigidBodySystem::angular_momentum");
  // L = R diag(I) R^T w, in the principal frame
  const Vec3 wb = glm::conjugate(q_[i]) * w_[i];
  return q_[i] * (inertia_[i] * wb);
}

double RigidBodySystem::kinetic_energy(RigidBodyId id) const {
  const std::size_t i = index(id, "RigidBodySystem::kinetic_energy");
  if (inv_mass_[i] == 0) return 0;
  const Vec3 wb = glm::conjugate(q_[i]) * w_[i];
  return 0.5 * glm::dot(v_[i], v_[i]) / inv_mass_[i] + 0.5 * glm::dot(wb, inertia_[i] * wb);
}

double RigidBodySystem::touch_margin() const {
  return std::max(settings_.speculative_distance, settings_.linear_slop) + 1e-6;
}

bool RigidBodySystem::shapes_touch(std::size_t i, std::size_t shape_i, std::size_t k, std::size_t shape_k) const {
  // the narrow phase at the poses now, with touch_margin() as its margin: a point comes out
  // when the shapes are closer than it (both solid: dynamic bodies' shapes). The speculative
  // distance alone missed a body resting on it when that is 0 (XPBD rests at a gap of exactly
  // 0, the impulse solver at 1.4e-11 m)
  const RigidShapeDef& a = shapes_[i][shape_i];
  const RigidShapeDef& b = shapes_[k][shape_k];
  const Manifold m = collide(a.shape, detail::shape_frame(body_pose(i), a.local), b.shape,
                             detail::shape_frame(body_pose(k), b.local),
                             NarrowPhaseSettings{.speculative_margin = touch_margin()});
  return m.count > 0;
}

void RigidBodySystem::list_jumped(std::uint32_t slot) {
  detail::RigidContacts& c = contact_state(contacts_);
  if (c.jumped_slot.size() < slot_.size()) {
    c.jumped_slot.resize(slot_.size(), 0);
    c.jumped.reserve(slot_.size());
  }
  // once a slot until the step (a body set_pose moved a million times held a million entries)
  if (!c.jumped_slot[slot]) {
    c.jumped_slot[slot] = 1;
    c.jumped.push_back(slot);
  }
}

// A sleeper woken because a body was teleported away from under it (or into it) is still, so
// what sleeps on it in another island (a box placed on a sleeping box sleeps in its own island)
// would wait for it to move faster than sleep_linear: with a loose sleep_linear the top of a
// chain hung in the air. Listed as jumped, each woken body wakes what it touches next step.
void RigidBodySystem::wake_island_listed(std::size_t i) {
  if (asleep_[i]) {
    std::size_t k = i;
    do {
      list_jumped(owner_[k]);
      k = island_[k];
    } while (k != i);
  }
  wake_island(i);
}

// The sleepers' proxies are in the broad phase's tree, each fat box around its shape (a
// sleeper does not move: set_pose and set_velocity wake it first), so a query of a box finds
// every sleeper near it in O(log n + found): a scan of every body's bounds made each set_pose
// of a platform O(n).
void RigidBodySystem::wake_reached(const Aabb& reach) {
  const detail::RigidContacts& c = contact_state(contacts_);
  c.tree.query(reach, [&](std::uint32_t q) {
    const detail::ShapeProxy& p = c.proxies[q];
    const std::size_t k = p.body;
    if (k >= type_.size() || !asleep_[k]) return true;
    const RigidShapeDef& o = shapes_[k][p.shape];
    if (reach.overlaps(bounds(o.shape, detail::shape_frame(body_pose(k), o.local)))) wake_island_listed(k);
    return true;
  });
}

void RigidBodySystem::wake_touching(std::size_t i) {
  const detail::RigidContacts& c = contact_state(contacts_);
  const Pose body = body_pose(i);
  for (std::size_t m = 0; m < shapes_[i].size(); ++m) {
    const RigidShapeDef& d = shapes_[i][m];
    const Aabb near = bounds(d.shape, detail::shape_frame(body, d.local)).grown(touch_margin());
    c.tree.query(near, [&](std::uint32_t q) {
      const detail::ShapeProxy& p = c.proxies[q];
      const std::size_t k = p.body;
      if (k != i && k < type_.size() && asleep_[k] && shapes_touch(i, m, k, p.shape)) wake_island_listed(k);
      return true;
    });
  }
}

void RigidBodySystem::set_pose(RigidBodyId id, const Pose& pose) {
  const std::size_t i = index(id, "RigidBodySystem::set_pose");
  // as RigidBodyDef::validate
  if (!fits_float(pose.position)) require_float(pose.position, describe(i) + " set_pose position");
  if (!unit_quat(pose.rotation)) require_unit_quat(pose.rotation, describe(i) + " set_pose rotation");
  // each shape's frame in the world too (as RigidBodyDef::validate)
  for (std::size_t k = 0; k < shapes_[i].size(); ++k)
    if (!frame_fits_float(pose, shapes_[i][k])) require_frame_float(pose, shapes_[i][k], k, describe(i) + " set_pose");
  // what rested on the body wakes: nothing else would (the ground lowered under a sleeping
  // stack left it floating; a box asleep on an awake box teleported away hung in the air, as
  // each slept in its own island). A static or kinematic body wakes the sleeping bodies its
  // shapes' bounds reach, before or after the move (grown by touch_margin()): they rested on
  // it, or it jumped into them (a kinematic wall stepped by set_pose has no velocity, so it
  // went through a sleeping box as if it were not there); a dynamic one those its shapes
  // touch before the move (closer than touch_margin()). Each woken body is listed as jumped,
  // so what sleeps on it wakes next step
  const bool fixed = type_[i] != BodyType::Dynamic;
  // a fixed body's reach: its shapes' bounds before the move, then after it, each grown by
  // touch_margin() (one box spanning both poses woke every sleeper between them: 2514
  // for 6 within reach on a platform moved across a floor of boxes)
  auto wake_around = [&] {
    Aabb reach{Vec3(std::numeric_limits<double>::infinity()), Vec3(-std::numeric_limits<double>::infinity())};
    for (const RigidShapeDef& d : shapes_[i])
      reach = reach.merged(bounds(d.shape, detail::shape_frame(body_pose(i), d.local)));
    wake_reached(reach.grown(touch_margin()));
  };
  if (fixed)
    wake_around();
  else
    wake_touching(i);
  com_[i] = apply(pose, com_local_[i]);
  q_[i] = glm::normalize(pose.rotation * principal_[i]);
  wake_island(i);
  if (fixed)
    wake_around();
  else
    list_jumped(id.index);  // it wakes what it jumped into through next step's pairs (wake_touched)
}

void RigidBodySystem::set_velocity(RigidBodyId id, const Vec3& linear, const Vec3& angular) {
  const std::size_t i = index(id, "RigidBodySystem::set_velocity");
  if (!speed_ok(linear)) require_rigid_speed(linear, describe(i) + " set_velocity linear", "m/s");
  if (!speed_ok(angular)) require_rigid_speed(angular, describe(i) + " set_velocity angular", "rad/s");
  if (type_[i] == BodyType::Static) return;  // a static body never moves
  v_[i] = linear;
  w_[i] = angular;
  wake_island(i);
}

void RigidBodySystem::apply_force(RigidBodyId id, const Vec3& f, const Vec3& p) {
  const std::size_t i = index(id, "RigidBodySystem::apply_force");
  if (!is_finite(f)) require_finite(f, describe(i) + " apply_force force");
  if (!is_finite(p)) require_finite(p, describe(i) + " apply_force point");
  if (type_[i] != BodyType::Dynamic) return;
  // finite parts can sum, or turn about a far point, to an infinite force or torque: refused
  // here by name (the step would stop the system with the body 'non-finite', naming no force)
  const Vec3 force = force_[i] + f, torque = torque_[i] + glm::cross(p - com_[i], f);
  if (!is_finite(force)) require_finite(force, describe(i) + " apply_force: the force summed for the next step");
  if (!is_finite(torque)) require_finite(torque, describe(i) + " apply_force: the force's moment about the centre of mass, or the torque summed for the next step");
  force_[i] = force, torque_[i] = torque;
  wake_island(i);
}

void RigidBodySystem::apply_force(RigidBodyId id, const Vec3& f) {
  const std::size_t i = index(id, "RigidBodySystem::apply_force");
  if (!is_finite(f)) require_finite(f, describe(i) + " apply_force force");
  if (type_[i] != BodyType::Dynamic) return;
  const Vec3 force = force_[i] + f;
  if (!is_finite(force)) require_finite(force, describe(i) + " apply_force: the force summed for the next step");
  force_[i] = force;
  wake_island(i);
}

void RigidBodySystem::apply_torque(RigidBodyId id, const Vec3& t) {
  const std::size_t i = index(id, "RigidBodySystem::apply_torque");
  if (!is_finite(t)) require_finite(t, describe(i) + " apply_torque torque");
  if (type_[i] != BodyType::Dynamic) return;
  const Vec3 torque = torque_[i] + t;
  if (!is_finite(torque)) require_finite(torque, describe(i) + " apply_torque: the torque summed for the next step");
  torque_[i] = torque;
  wake_island(i);
}

void RigidBodySystem::apply_impulse(RigidBodyId id, const Vec3& j, const Vec3& p) {
  const std::size_t i = index(id, "RigidBodySystem::apply_impulse");
  if (!is_finite(j)) require_finite(j, describe(i) + " apply_impulse impulse");
  if (!is_finite(p)) require_finite(p, describe(i) + " apply_impulse point");
  if (type_[i] != BodyType::Dynamic) return;
  // dw = I^-1 (r x J) with I^-1 = R diag(1/I) R^T
  const Vec3 l = glm::conjugate(q_[i]) * glm::cross(p - com_[i], j);
  const Vec3 v = v_[i] + inv_mass_[i] * j, w = w_[i] + q_[i] * (inv_inertia_[i] * l);
  if (!speed_ok(v)) require_rigid_speed(v, describe(i) + " apply_impulse: the linear velocity it gives", "m/s");
  if (!speed_ok(w)) require_rigid_speed(w, describe(i) + " apply_impulse: the angular velocity it gives", "rad/s");
  wake_island(i);
  v_[i] = v, w_[i] = w;
}

void RigidBodySystem::apply_angular_impulse(RigidBodyId id, const Vec3& j) {
  const std::size_t i = index(id, "RigidBodySystem::apply_angular_impulse");
  if (!is_finite(j)) require_finite(j, describe(i) + " apply_angular_impulse");
  if (type_[i] != BodyType::Dynamic) return;
  const Vec3 w = w_[i] + q_[i] * (inv_inertia_[i] * (glm::conjugate(q_[i]) * j));
  if (!speed_ok(w))
    require_rigid_speed(w, describe(i) + " apply_angular_impulse: the angular velocity it gives", "rad/s");
  wake_island(i);
  w_[i] = w;
}

// ---------------------------------------------------------------------------------------
// stepping

namespace {

Vec3 get3(const double* p) { return {p[0], p[1], p[2]}; }

// Grows `storage` (never shrinks it) to hold `doubles` doubles from its first 64-byte line on;
// returns that line's offset in it (doubles): the free motion's lanes are read by aligned loads
std::size_t line_aligned(std::vector<double>& storage, std::size_t doubles) {
  constexpr std::size_t kLine = 64 / sizeof(double);
  if (storage.size() < doubles + kLine) storage.resize(doubles + kLine);
  const std::uintptr_t at = reinterpret_cast<std::uintptr_t>(storage.data()) / sizeof(double);
  return (kLine - at % kLine) % kLine;
}

}  // namespace

// The arrays of the free motion (src/rigid/integrate_wide.cpp): the velocities in the contact
// solver's rows when it runs, else in the system's arrays.
detail::FreeMotionArrays RigidBodySystem::free_motion(detail::SolverBody* rows, detail::SolverBody* warm,
                                                      double* motion) {
  detail::FreeMotionArrays f;
  if (rows) f.v = rows[0].v, f.w = rows[0].w, f.stride = 8;
  else if (!v_.empty()) f.v = &v_[0].x, f.w = &w_[0].x, f.stride = 3;  // (none: a moved-from system's step)
  f.warm = warm, f.motion = motion;
  f.com = com_.data(), f.com0 = com0_.data(), f.q = q_.data(), f.q0 = q0_.data();
  f.inertia = inertia_.data(), f.inv_inertia = inv_inertia_.data();
  f.force = force_.data(), f.torque = torque_.data();
  f.inv_mass = inv_mass_.data(), f.gravity_scale = gravity_scale_.data();
  f.lin_damp = lin_damp_.data(), f.ang_damp = ang_damp_.data(), f.damped = contacts_->moving_damped;
  f.torqued = contacts_->moving_torqued;
  return f;
}

void RigidBodySystem::integrate_velocities(double h, const Vec3& gravity, detail::SolverBody* rows,
                                           detail::SolverBody* warm) {
  const Stopwatch clock;
  const detail::RigidContacts& c = *contacts_;
  const detail::FreeMotionArrays f = free_motion(rows, warm, nullptr);
  std::uint32_t bad = 0;
  for (std::size_t k = 0; k < c.moving.size(); ++k) {
    const bool round = static_cast<detail::FreeRotation>(k) == detail::FreeRotation::Round;
    if (detail::integrate_velocities_wide(c.simd, round, c.moving[k].data(), c.moving[k].size(), f, h, gravity,
                                          contacts_->free_lanes_of(k), &bad))
      continue;
    if (rows) v_[bad] = get3(rows[bad].v), w_[bad] = get3(rows[bad].w);
    if (c.free_lanes_live) contacts_->scatter_free_motion(*this);  // (the message shows the pose now)
    fail(bad);  // throws
  }
  profile_.integrate += clock.seconds();
}

void RigidBodySystem::integrate_positions(double h, detail::SolverBody* rows, double* motion) {
  const Stopwatch clock;
  // dynamic bodies: symplectic Euler for the centre, the exact-flow splitting for the rotation
  // (bodies with equal principal moments: exact turns)
  const detail::RigidContacts& c = *contacts_;
  const detail::FreeMotionArrays f = free_motion(rows, nullptr, motion);
  for (std::size_t k = 0; k < c.moving.size(); ++k)
    detail::integrate_positions_wide(c.simd, static_cast<detail::FreeRotation>(k), c.moving[k].data(),
                                     c.moving[k].size(), f, h, contacts_->free_lanes_of(k));
  // kinematic bodies (listed by step()): constant velocities, exact translation and rotation
  for (const std::uint32_t i : c.kinematic) {
    const Vec3 v = rows ? get3(rows[i].v) : v_[i], w = rows ? get3(rows[i].w) : w_[i];
    com_[i] += h * v;
    const double wl = glm::length(w);
    if (wl > 0) q_[i] = glm::normalize(axis_angle(w / wl, wl * h) * q_[i]);
    if (motion) {
      const Vec3 dp = com_[i] - com0_[i];
      const Quat turn = q_[i] * glm::conjugate(q0_[i]);
      double* m = motion + 8 * i;
      m[0] = dp.x, m[1] = dp.y, m[2] = dp.z, m[3] = turn.w, m[4] = turn.x, m[5] = turn.y, m[6] = turn.z;
    }
  }
  profile_.integrate += clock.seconds();
}

void detail::RigidContacts::gather_free_motion(RigidBodySystem& s, double h, const Vec3& gravity) {
  const Stopwatch clock;
  // each kind's blocks after the last's, from the first 64-byte line of the storage (grown,
  // never shrunk)
  std::size_t blocks = 0;
  for (std::size_t k = 0; k < moving.size(); ++k) {
    free_lanes_at[k] = blocks * kFreeBlock;
    blocks += (moving[k].size() + kFreeLaneWidth - 1) / kFreeLaneWidth;
  }
  const std::size_t skip = line_aligned(free_lanes, blocks * kFreeBlock);
  const FreeMotionArrays f = s.free_motion(nullptr, nullptr, nullptr);
  for (std::size_t k = 0; k < moving.size(); ++k) {
    free_lanes_at[k] += skip;
    gather_free_motion_wide(simd, static_cast<FreeRotation>(k), moving[k].data(), moving[k].size(), f, h, gravity,
                            free_lanes.data() + free_lanes_at[k]);
  }
  free_lanes_live = true;
  s.profile_.integrate += clock.seconds();
}

void detail::RigidContacts::scatter_free_motion(RigidBodySystem& s) {
  const Stopwatch clock;
  const FreeMotionArrays f = s.free_motion(nullptr, nullptr, nullptr);
  for (std::size_t k = 0; k < moving.size(); ++k)
    scatter_free_motion_wide(simd, moving[k].data(), moving[k].size(), f, free_lanes_of(k));
  free_lanes_live = false;
  s.profile_.integrate += clock.seconds();
}

// a substep's change of a drifting body's velocity: h (gravity scale g + inverse mass force)
Vec3 detail::RigidContacts::drift_change(const RigidBodySystem& s, std::uint32_t i, double h, const Vec3& gravity) {
  return h * (s.gravity_scale_[i] * gravity + s.inv_mass_[i] * s.force_[i]);
}

void detail::RigidContacts::split_coasting(RigidBodySystem& s, double h, const Vec3& gravity, int substeps) {
  for (auto& list : coasting) list.clear();
  drifting.clear();
  const Stopwatch clock;
  // the bodies the lanes write (a lane writes only a moving body: dynamic and awake)
  in_lanes.assign(s.type_.size(), 0);
  auto mark = [&](const auto* b, std::size_t count) {
    for (std::size_t k = 0; k < count; ++k)
      for (int l = 0; l < b[k].lanes; ++l) {
        if (b[k].write_a >> l & 1) in_lanes[b[k].a[l]] = 1;
        if (b[k].write_b >> l & 1) in_lanes[b[k].b[l]] = 1;
      }
  };
  mark(blocks.data(), block_count);
  mark(ones.data(), one_blocks);
  // The drifting ones (2): those whose step has a closed form, coast(): no damping, no torque,
  // and no spin or three equal moments, whose spin then stays as it is. In a step that takes
  // one of them past the speed limit none drifts, so that the limit stops the step in the
  // substep it is passed (the coasting chunks' substeps run before the lane bodies', so a
  // coasting body past the limit is named first; such a step only ends in an exception)
  bool closed = true;
  const double steps = substeps;
  for (std::size_t k = 0; k < moving.size(); ++k) {
    const bool round = static_cast<FreeRotation>(k) == FreeRotation::Round;
    for (const std::uint32_t i : moving[k]) {
      if (in_lanes[i] || !(s.lin_damp_[i] == 0 && s.ang_damp_[i] == 0 && s.torque_[i] == Vec3(0) &&
                           (round || s.w_[i] == Vec3(0))))
        continue;
      in_lanes[i] = 2;
      // the substeps' speeds |v0 + k L| (k = 1..n) are convex in k, so the largest is at an end;
      // the spin stays as it is
      const Vec3 v0 = get3(rows[i].v), change = drift_change(s, i, h, gravity);
      closed = closed && speed_ok(v0 + change) && speed_ok(v0 + steps * change) && speed_ok(get3(rows[i].w));
    }
  }
  for (std::size_t k = 0; k < moving.size(); ++k) {
    std::vector<std::uint32_t>& list = moving[k];
    std::size_t kept = 0;
    for (const std::uint32_t i : list) {
      if (in_lanes[i] == 1) list[kept++] = i;
      else if (in_lanes[i] == 2 && closed) drifting.push_back(i);
      else coasting[k].push_back(i);
    }
    list.resize(kept);
  }
  s.profile_.integrate += clock.seconds();
}

void detail::RigidContacts::coast(RigidBodySystem& s, double h, const Vec3& gravity, int substeps) {
  const Stopwatch clock;
  // a chunk's lanes (2 KB a block of 8), rows and warm-start rows (64 bytes a body each) stay
  // in L1 over its substeps (the rain's 10,000 bodies' were 2.5 MB of lanes and 1.3 MB of rows
  // swept 8 times, past the 512 KB L2)
  constexpr std::size_t kChunk = 32;
  const std::size_t skip = line_aligned(coast_lanes, kChunk / kFreeLaneWidth * kFreeBlock);
  double* lanes = coast_lanes.data() + skip;
  // (no motion: only the contact lanes read it)
  const FreeMotionArrays f = s.free_motion(rows.data(), warm.data(), nullptr);
  std::uint32_t bad = 0;
  // The drifting bodies' step in closed form. Their substeps change v by the same L = h
  // (gravity scale g + inverse mass force) each, so v_k = v_0 + k L, and move the centre by h
  // v_k each, so x_n = x_0 + h (v_1 + ... + v_n) = x_0 + h (n v_0 + n (n + 1) / 2 L): the same
  // sums, so the same motion to rounding (the substeps' 2n adds a component, each rounded to
  // half an ulp of x or v, against four roundings here: a few ulps of the centre, 1e-15 m at
  // 10 m). Their w stays as it is (no torque, no damping) and the n turns of h w about it add
  // up to one turn of n h w exactly, the exact turn the kinematic bodies take
  // (integrate_positions); with w = 0 the frame stays as it is (the substeps turned it by
  // angles of exactly 0 and normalised it again, a rounding). Their warm start is zero (no
  // lane adds to it) and their motion is not written (only the contact lanes read it).
  // (split_coasting made sure none of them passes the speed limit: |v_k|^2 is a parabola in k,
  // so |v| is largest at one end of the step)
  const double steps = substeps, sum = 0.5 * steps * (steps + 1);
  for (const std::uint32_t i : drifting) {
    double* v = rows[i].v;
    const Vec3 v0 = get3(v), w = get3(rows[i].w);
    const Vec3 change = drift_change(s, i, h, gravity);
    const Vec3 vn = v0 + steps * change;
    s.com_[i] += h * (steps * v0 + sum * change);
    v[0] = vn.x, v[1] = vn.y, v[2] = vn.z;
    const double wl = glm::length(w);
    if (wl > 0) s.q_[i] = glm::normalize(axis_angle(w / wl, wl * steps * h) * s.q_[i]);
  }
  for (std::size_t k = 0; k < coasting.size(); ++k) {
    const auto kind = static_cast<FreeRotation>(k);
    const std::vector<std::uint32_t>& list = coasting[k];
    for (std::size_t first = 0; first < list.size(); first += kChunk) {
      const std::uint32_t* bodies = list.data() + first;
      const std::size_t count = std::min(kChunk, list.size() - first);
      gather_free_motion_wide(simd, kind, bodies, count, f, h, gravity, lanes);
      for (int n = 0; n < substeps; ++n) {
        if (!integrate_velocities_wide(simd, kind == FreeRotation::Round, bodies, count, f, h, gravity, lanes, &bad)) {
          // (the message shows the pose now: the drifting bodies' and the earlier chunks' at the
          // step's end, this chunk's at the substep, the lane bodies' at the step's start)
          scatter_free_motion_wide(simd, bodies, count, f, lanes);
          s.v_[bad] = get3(rows[bad].v), s.w_[bad] = get3(rows[bad].w);
          if (free_lanes_live) scatter_free_motion(s);
          s.fail(bad);  // throws
        }
        integrate_positions_wide(simd, kind, bodies, count, f, h, lanes);
      }
      scatter_free_motion_wide(simd, bodies, count, f, lanes);
    }
  }
  s.profile_.integrate += clock.seconds();
}

void RigidBodySystem::step(double dt, const Vec3& gravity) {
  if (!failure_.empty()) throw Error(failure_);
  contact_state(contacts_);  // a moved-from system's contact state made afresh: the step writes it
  if (!(std::isfinite(dt) && dt > 0)) require_positive(dt, "RigidBodySystem::step dt");
  if (!is_finite(gravity)) require_finite(gravity, "RigidBodySystem::step gravity");
  if (!(settings_ == validated_)) {
    settings_.validate("RigidBodySystem.settings");
    // sleeping turned off wakes the sleepers (as Box2D's b2World_EnableSleeping does): nothing
    // else would wake a pile asleep away from anything moving
    if (!settings_.sleep && validated_.sleep)
      for (std::size_t i = 0; i < type_.size(); ++i)
        if (asleep_[i]) wake_island(i);
    // a switch to XPBD from another solver wakes the sleepers too: the switch step brings the
    // overlap the old solver rested at to XPBD's own (RigidContacts::relax_overlap), but only
    // in the pairs that reach the solver; an island asleep through it kept the old overlap,
    // which XPBD, woken, pushed out as a velocity (a 10-stack asleep under sequential
    // impulses jumped to 0.45 m/s)
    if (settings_.solver == RigidSolverType::Xpbd && validated_.solver != RigidSolverType::Xpbd)
      for (std::size_t i = 0; i < type_.size(); ++i)
        if (asleep_[i]) wake_island(i);
    validated_ = settings_;
  }
  // a change of gravity wakes the sleepers it acts on (as set_gravity does in Box2D v3): an
  // island asleep under the old gravity would hang there under the new one
  if (gravity != gravity_) {
    for (std::size_t i = 0; i < type_.size(); ++i)
      if (asleep_[i] && gravity_scale_[i] != 0) wake_island(i);
    gravity_ = gravity;
  }
  last_dt_ = dt;
  Stopwatch total;
  const std::size_t n = type_.size();
  // the start of the step, which the solver measures separations from
  for (std::size_t i = 0; i < n; ++i) com0_[i] = com_[i], q0_[i] = q_[i];
  // pairs and manifolds, then the bodies that move freely this step
  contacts_->update(*this, dt);
  for (auto& list : contacts_->moving) list.clear();
  contacts_->kinematic.clear();
  bool damped = false;
  std::uint64_t torque_bits = 0;  // (their or: zero when every torque is +0, not -0)
  for (std::size_t i = 0; i < n; ++i) {
    if (type_[i] == BodyType::Kinematic) contacts_->kinematic.push_back(static_cast<std::uint32_t>(i));
    if (type_[i] != BodyType::Dynamic || asleep_[i]) continue;
    contacts_->moving[static_cast<std::size_t>(detail::free_rotation(inertia_[i]))].push_back(
        static_cast<std::uint32_t>(i));
    damped = damped || lin_damp_[i] != 0 || ang_damp_[i] != 0;
    torque_bits |= std::bit_cast<std::uint64_t>(torque_[i].x) | std::bit_cast<std::uint64_t>(torque_[i].y) |
                   std::bit_cast<std::uint64_t>(torque_[i].z);
  }
  contacts_->moving_damped = damped;
  contacts_->moving_torqued = torque_bits != 0;
  profile_.collide = total.seconds();
  profile_.integrate = 0;  // integrate_velocities and integrate_positions add to it
  const bool soft = settings_.solver == RigidSolverType::SoftStep;
  // the substeps this step takes (more than the setting for a tall column: auto_substeps,
  // columns.cpp; counted in profile_.prepare), the carried impulses at this solver's time
  // step, then the solver's arrays
  const int substeps = step_substeps(dt, gravity);
  profile_.substeps = substeps;
  contacts_->carry_impulses(dt / substeps);
  contacts_->prepare(*this);
  profile_.prepare = total.seconds() - profile_.collide;
  const double solver_start = total.seconds();
  detail::RigidContacts& c = *contacts_;
  const bool warm = settings_.warm_starting;
  c.gravity_speed = glm::length(gravity);
  if (settings_.solver == RigidSolverType::Tgs) {
    c.step_tgs(*this, dt, gravity);  // src/rigid/tgs.cpp
  } else if (settings_.solver == RigidSolverType::Xpbd) {
    c.step_xpbd(*this, dt, gravity);  // src/rigid/xpbd_rigid.cpp, restitution included
  } else if (soft) {
    // substeps: velocities with the carried impulses, soft solve, positions, relax (which
    // measures the separations at the new poses and carries the impulses to the next substep)
    // The free motion's fields live in lanes for the substeps (RigidContacts::free_lanes):
    // gathered once here, the centres and frames put back after the last (on an unwind too)
    const double h = dt / substeps;
    // (the bodies no contact lane holds take all the substeps at once, before the others')
    c.split_coasting(*this, h, gravity, substeps);
    const detail::RigidContacts::FreeLanesScope lanes(c, *this, h, gravity);
    c.coast(*this, h, gravity, substeps);
    for (int s = 0; s < substeps; ++s) {
      integrate_velocities(h, gravity, c.rows.data(), c.warm.data());
      c.pass(*this, h, true, true, false, false);
      integrate_positions(h, c.rows.data(), c.motion.data());
      c.refresh_inertia(*this);  // (the inverse inertias of bodies that turned far, at their poses now)
      c.pass(*this, h, false, true, true, warm && s + 1 < substeps);
    }
  } else {
    // one step: velocities with the carried impulses, iterated rigid solve with Baumgarte, positions
    integrate_velocities(dt, gravity, c.rows.data(), c.warm.data());
    for (int k = 0; k < settings_.iterations; ++k) c.pass(*this, dt, true, false, false, false);
    integrate_positions(dt, c.rows.data(), c.motion.data());
    c.refresh_inertia(*this);
  }
  c.last_solver = settings_.solver;
  if (settings_.solver != RigidSolverType::Xpbd) {
    c.restitution(*this, dt, gravity);
    c.finish_velocities(*this);  // the solver's rows back to the system's arrays
  }
  // contacts the springs left deeper than the slop (heavy bodies on light ones), put right
  if (soft) c.push_out(*this, gravity);  // src/rigid/push_out.cpp
  const double solver_end = total.seconds();
  profile_.contacts = solver_end - solver_start - profile_.integrate;
  contacts_->continuous(*this);
  contacts_->store();
  check_finite();
  update_sleep(dt);
  std::fill(force_.begin(), force_.end(), Vec3(0));
  std::fill(torque_.begin(), torque_.end(), Vec3(0));
  time_ += dt;
  profile_.total = total.seconds();
  profile_.solve = profile_.total - profile_.collide;
  profile_.finish = profile_.total - solver_end;
}

namespace detail {

namespace {

typedef double v4d_sum __attribute__((vector_size(32)));

// all_finite_wide's test: four sums of four lanes (on AVX2 one instruction a lane group, else
// two SSE2 halves), the last count % 16 one by one
[[gnu::always_inline]] inline bool all_finite_of(const double* p, std::size_t count) {
  v4d_sum acc[4] = {};
  std::size_t i = 0;
  for (; i + 16 <= count; i += 16)
    for (int k = 0; k < 4; ++k) {
      v4d_sum x;
      std::memcpy(&x, p + i + 4 * k, sizeof x);
      acc[k] += x - x;
    }
  double rest = 0;
  for (; i < count; ++i) rest += p[i] - p[i];
  const v4d_sum all = (acc[0] + acc[1]) + (acc[2] + acc[3]);
  return (all[0] + all[1]) + (all[2] + all[3]) + rest == 0;
}
typedef long long v4l_mask __attribute__((vector_size(32)));

// all_within_wide's test: -limit <= x <= limit as lane masks and-ed in four groups (a NaN
// fails both compares), the last count % 16 one by one
[[gnu::always_inline]] inline bool all_within_of(const double* p, std::size_t count, double limit) {
  v4l_mask acc[4] = {{-1, -1, -1, -1}, {-1, -1, -1, -1}, {-1, -1, -1, -1}, {-1, -1, -1, -1}};
  const v4d_sum hi = {limit, limit, limit, limit}, lo = -hi;
  std::size_t i = 0;
  for (; i + 16 <= count; i += 16)
    for (int k = 0; k < 4; ++k) {
      v4d_sum x;
      std::memcpy(&x, p + i + 4 * k, sizeof x);
      acc[k] &= (x <= hi) & (x >= lo);
    }
  bool ok = true;
  for (; i < count; ++i) ok &= std::abs(p[i]) <= limit;
  const v4l_mask all = (acc[0] & acc[1]) & (acc[2] & acc[3]);
  return ok & ((all[0] & all[1] & all[2] & all[3]) == -1);
}
#if defined(__GNUC__) && defined(__x86_64__)  // (PBA_RIGID_HAVE_X86 of contact_wide.h)
[[gnu::target("avx2")]] bool all_finite_avx2(const double* p, std::size_t count) { return all_finite_of(p, count); }
[[gnu::target("avx2")]] bool all_within_avx2(const double* p, std::size_t count, double limit) {
  return all_within_of(p, count, limit);
}
#endif

}  // namespace

bool all_finite_wide(SimdPath path, const double* p, std::size_t count) {
#if defined(__GNUC__) && defined(__x86_64__)
  return path == SimdPath::Scalar ? all_finite_of(p, count) : all_finite_avx2(p, count);
#else
  (void)path;  // a wide path is never chosen here (best_simd_path)
  return all_finite_of(p, count);
#endif
}

bool all_within_wide(SimdPath path, const double* p, std::size_t count, double limit) {
#if defined(__GNUC__) && defined(__x86_64__)
  return path == SimdPath::Scalar ? all_within_of(p, count, limit) : all_within_avx2(p, count, limit);
#else
  (void)path;
  return all_within_of(p, count, limit);
#endif
}

}  // namespace detail

void RigidBodySystem::check_finite() {
  // look for a body whose state stopped being finite (the forces, which last one step, are
  // cleared after update_sleep has seen which bodies they pushed)
  const std::size_t n = type_.size();
  // the centres, velocities and frames as flat arrays of doubles first (Vec3 and Quat are
  // 3 and 4 doubles without padding): a body at a time, the tests were 0.67 M instructions
  // of the rain's landing step, and as many in each of its resting steps, its 10,000 bodies
  // asleep; whole arrays in lanes, about a fifth. Only when some number is not finite, the
  // bodies one by one for the first such (the one named, as before)
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(Quat) == 4 * sizeof(double));
  const detail::SimdPath path = contacts_ ? contacts_->simd : detail::SimdPath::Scalar;
  auto all_finite = [&](const double* p, std::size_t count) { return detail::all_finite_wide(path, p, count); };
  // the centres within the float range less the farthest shape frame from any centre (the
  // colliders' range, which the narrow phase holds every shape's frame to: a body a step
  // carried past it went on, and two balls out there passed through each other), finite
  // too by the same compares; beyond that bound, each body's frames one by one
  const double limit =
      static_cast<double>(std::numeric_limits<float>::max()) - (contacts_ ? contacts_->frame_reach : 0.0);
  if (n == 0 || (detail::all_within_wide(path, &com_[0].x, 3 * n, limit) && all_finite(&v_[0].x, 3 * n) &&
                 all_finite(&w_[0].x, 3 * n) &&
                 all_finite(reinterpret_cast<const double*>(q_.data()), 4 * n)))
    return;
  for (std::size_t i = 0; i < n; ++i)
    if (!(is_finite(com_[i]) && is_finite(v_[i]) && is_finite(w_[i]) && finite_quat(q_[i]))) fail(i);
  for (std::size_t i = 0; i < n; ++i)
    if (!detail::RigidContacts::in_float_range(*this, i)) fail(i);
}

bool detail::RigidContacts::in_float_range(const RigidBodySystem& s, std::size_t i) {
  if (!fits_float(s.com_[i])) return false;
  const Pose body = s.body_pose(i);
  for (const RigidShapeDef& d : s.shapes_[i])
    if (!frame_fits_float(body, d)) return false;
  return true;
}

void detail::RigidContacts::poison_and_check(RigidBodySystem& s, int which, std::size_t i, int component,
                                             double value) {
  switch (which) {
    case 0: s.com_.at(i)[component] = value; break;
    case 1: s.v_.at(i)[component] = value; break;
    case 2: s.w_.at(i)[component] = value; break;
    default: s.q_.at(i)[component] = value; break;
  }
  s.check_finite();
}

void RigidBodySystem::fail(std::size_t i) {
  const bool finite = is_finite(com_[i]) && is_finite(v_[i]) && is_finite(w_[i]) && finite_quat(q_[i]);
  failed_ = id_at(i);
  failure_ = describe(i) +
             (finite && !detail::RigidContacts::in_float_range(*this, i)
                  ? " left the float range (a position's |component| <= " +
                        format_value(std::numeric_limits<float>::max()) +
                        " m, the colliders' range, for its centre and every shape's frame)"
              : finite ? " went faster than kMaxRigidSpeed (" + format_value(kMaxRigidSpeed) +
                           " m/s or rad/s, the contacts' float rows' limit: a force or torque, the gravity "
                           "times the body's gravity_scale, or the time step too large)"
                     : std::string(" became non-finite")) +
             " in the step to t = " + format_value(time_ + last_dt_) + " s: position " + format_vec3(com_[i]) +
             ", velocity " + format_vec3(v_[i]) + ", angular velocity " + format_vec3(w_[i]);
  throw Error(failure_);
}

// Islands by union-find over the contacts between awake dynamic bodies (static and kinematic
// bodies do not join islands: a floor holds many islands). An island sleeps when each of its
// bodies has been slower than the tolerances for time_to_sleep; one touching a moving
// kinematic body never does. A sleeping island keeps its members in a ring (island_), so
// waking it costs its size, and it costs nothing per step: the pairs of sleeping bodies are
// not stepped (contact_pairs.cpp) and the union-find runs over the awake ones.
void RigidBodySystem::update_sleep(double dt) {
  const Stopwatch clock;
  const std::size_t n = type_.size();
  const bool on = settings_.sleep;
  if (!on) {
    // with sleeping off no body rests: each awake dynamic body's window starts again where it
    // is, as the test below would leave it whatever it found (its windows, turns and reaches
    // were 118 instructions a body, 2.5% of the 1000 falling boxes' resting step), and the
    // islands, which only decide who falls asleep, are not made (the union-find over every
    // pair was 0.8 ms a step on the 2870-box pyramid)
    for (std::size_t i = 0; i < n; ++i) {
      if (type_[i] != BodyType::Dynamic || asleep_[i]) continue;
      sleep_time_[i] = 0;
      rest_com_[i] = com_[i], rest_q_[i] = q_[i], rest_v_[i] = v_[i], rest_w_[i] = w_[i];
    }
    profile_.islands = clock.seconds();
    return;
  }
  // a body rests while it stays within what the tolerances allow over time_to_sleep of where
  // its rest window began: its centre within sleep_linear * time_to_sleep, its frame turned by
  // less than sleep_angular * time_to_sleep (Jolt tests displacements over the window the same
  // way). A steady motion is held to the tolerances as before (it leaves the window as soon as
  // its mean speed exceeds them); an oscillation about a pose now rests when its amplitude is
  // within half that distance, where the instantaneous speeds of a slowly rocking column (the
  // top of a 10-box tower swaying at 0.1 m/s, 1 cm either way) kept it awake for seconds
  // The window is at least the step that measures it: with time_to_sleep under dt (0 is
  // valid) a window of time_to_sleep allowed no motion at all, every body failed it, and its
  // slow time of 0 still reached time_to_sleep, so every awake body fell asleep at the end of
  // each step. A step is not enough under gravity either. Under an acceleration a a body
  // starting from rest moves a W^2 / 2 over a window W, within sleep_linear * W while
  // W <= 2 sleep_linear / a; across a turning point (the apex of a throw or a bounce) the
  // least it strays from where the window began, at any of the window's steps, is when the
  // window starts (sqrt(2) - 1) W before the apex: (3 - 2 sqrt(2)) a W^2 / 2 = 0.086 a W^2 up
  // at the apex and as far down at the end (a W^2 / 8 with the apex in the middle), within
  // sleep_linear * W while W <= 11.7 sleep_linear / a. At 1/240 s a ball dropped from rest
  // slept after its first step, and thrown or bouncing balls froze at their apexes. So a
  // body's window is also at least 16 sleep_linear / a, a = |gravity * gravity_scale| (82 ms
  // at the defaults and 9.81 m/s^2): 16, not 11.7, as the steps only sample the path (its
  // apex strays 1.37 times the reach). That floor is capped at kMaxGravityWindow for a near
  // 0 (a body then sleeps at most a second after it stops; a flight under less than
  // 16 sleep_linear / 1 s, 0.8 m/s^2 at the defaults, can rest at its apex); with no
  // acceleration there is no floor. The default
  // 0.5 s is longer than the floor at 9.81 m/s^2 and keeps its bits.
  constexpr double kMaxGravityWindow = 1;  // s
  const double base = std::max(settings_.time_to_sleep, dt);
  const double base_reach = settings_.sleep_linear * base;
  const double base_cos_turn = std::cos(0.5 * std::min(settings_.sleep_angular * base, kPi));
  const double g = glm::length(gravity_);
  // the body's window: the base, or longer under a weak enough acceleration
  auto window_of = [&](std::size_t i) {
    const double a = g * std::abs(gravity_scale_[i]);
    const double floor_reach = 16 * settings_.sleep_linear;   // m/s: the floor's a * W
    if (a == 0 || floor_reach <= a * base) return base;        // sleep_linear 0 included
    return std::max(base, a * kMaxGravityWindow > floor_reach ? floor_reach / a : kMaxGravityWindow);
  };
  // Far out the window cannot see motion: a centre whose coordinate reaches `far` has doubles
  // spaced at least a substep's motion at the linear tolerance apart (2^-52 of it), so a
  // slower substep rounds away (at y = 1e17 m they are 16 m apart: a ball falling there
  // stayed put, passed the window's test and fell asleep mid-air). A substep, not a step:
  // bodies in contact and coasting ones move a substep at a time. Such a body must also be
  // slower than the tolerances to rest. Nearer in (below 4.7e11 m at the defaults, 1/60 s
  // and 8 substeps) nothing changes; with sleep_linear = 0, `far` is 0: a body then rests
  // only when still, by its speeds as by its window.
  const double far = settings_.sleep_linear * (dt / profile_.substeps) * 0x1p52;
  const double slow_v = settings_.sleep_linear * settings_.sleep_linear;
  const double slow_w = settings_.sleep_angular * settings_.sleep_angular;
  // A body speeding up is not at rest, though its window holds it: from rest under an
  // acceleration a it moves a W^2 / 2 over a window W, within the reach sleep_linear * W
  // while a <= 2 sleep_linear / W (0.2 m/s^2 at the defaults), and a box on a slope half a
  // degree past its friction angle, or tipping slowly past its critical one, fell asleep
  // after 1 cm and never woke. Against the velocities the window began with (v0, w0), a
  // steady acceleration shows as its excess motion e = d - v0 t, t the window's age, and the
  // change of velocity dv = v - v0 = a t with dv . e = a^2 t^3 / 2 = 2 |e|^2 / t (the steps'
  // sums: 2 t / (t + dt) of it); a body that settles or coasts has dv . e <= |e|^2 / t (1 when
  // dv came at the window's start) and one rocking about a pose only at moments. So a body
  // whose speed grew (|v| > |v0|), by more than a quarter of the tolerance (below that its
  // solver's noise), with dv . e >= 1.5 |e|^2 / t, is speeding up and does not fall asleep in
  // the step; the same for the turn (e the turn since the window began less w0 t). Its window
  // goes on: a body rocking about a pose still rests at a step it is not speeding up, and one
  // sliding leaves the window's reach. The least acceleration seen is the one that changes
  // the speed by a quarter of the tolerance over the window: sleep_linear / (4 W), 0.025
  // m/s^2 at the defaults (0.017 rad/s^2 for the turn)
  const double speeding_v = 0.0625 * slow_v, speeding_w = 0.0625 * slow_w;
  auto speeding = [&](std::size_t i, const Vec3& d, double t) {
    auto grows = [&](const Vec3& v, const Vec3& v0, const Vec3& moved, double floor) {
      const Vec3 dv = v - v0, e = moved - v0 * t;
      return glm::dot(dv, dv) > floor && glm::dot(v, v) > glm::dot(v0, v0) &&
             glm::dot(dv, e) * t >= 1.5 * glm::dot(e, e);
    };
    if (grows(v_[i], rest_v_[i], d, speeding_v)) return true;
    // the turn since the window began as a rotation vector, 2 sin(angle / 2) times the axis
    // (the angle is within the window's sleep_angular * W, where that is the angle to 1e-4)
    const Quat turn = q_[i] * glm::conjugate(rest_q_[i]);
    const Vec3 angle = (turn.w < 0 ? -2.0 : 2.0) * Vec3(turn.x, turn.y, turn.z);
    return grows(w_[i], rest_w_[i], angle, speeding_w);
  };
  // the awake dynamic bodies lie in [lo, hi): the islands are gathered and put to sleep
  // there only (at the end of the 1000 falling boxes' run most bodies sleep, and each loop
  // over them all was about 10 instructions a body)
  std::size_t lo = n, hi = 0;
  for (std::size_t i = 0; i < n; ++i) {
    parent_[i] = static_cast<std::uint32_t>(i);
    if (type_[i] != BodyType::Dynamic || asleep_[i]) {
      island_slow_[i] = INFINITY;  // no island's: never a root's least
      continue;
    }
    lo = std::min(lo, i), hi = i + 1;
    const double window = window_of(i);
    double reach = base_reach, cos_turn = base_cos_turn;
    if (window != base) {
      reach = settings_.sleep_linear * window;
      cos_turn = std::cos(0.5 * std::min(settings_.sleep_angular * window, kPi));
    }
    const Vec3 d = com_[i] - rest_com_[i];
    bool rests = glm::dot(d, d) <= reach * reach && std::abs(glm::dot(q_[i], rest_q_[i])) >= cos_turn;
    if (rests && std::max({std::abs(com_[i].x), std::abs(com_[i].y), std::abs(com_[i].z)}) >= far)
      rests = glm::dot(v_[i], v_[i]) <= slow_v && glm::dot(w_[i], w_[i]) <= slow_w;
    // a body a force or torque pushed this step does not rest (pba's own rule: a force means
    // the caller is moving it): with time_to_sleep 0 and no gravity floor on its
    // window, a box pushed from rest by a steady force moved within the one-step window,
    // fell asleep at the step's end with its velocity zeroed, and never gathered speed
    const bool pushed = force_[i] != Vec3(0) || torque_[i] != Vec3(0);
    // its slow time past its window (island_slow_, read below before its island's least is
    // gathered there): the island sleeps only when each member's is >= 0
    if (rests && !pushed) {
      sleep_time_[i] += dt;
      island_slow_[i] = sleep_time_[i] - window;
      // within reach but speeding up: its window goes on, and it does not fall asleep in
      // this step. Tested only for a body whose window is full: before that the island
      // stays awake whatever the test says (the test for every resting body each step was
      // an eighth of update_sleep's instructions on the 1000 falling boxes, a quarter under
      // TGS, where they stay awake)
      if (island_slow_[i] >= 0 && speeding(i, d, sleep_time_[i])) island_slow_[i] = -INFINITY;
    } else {
      sleep_time_[i] = 0;
      island_slow_[i] = -window;
      rest_com_[i] = com_[i], rest_q_[i] = q_[i], rest_v_[i] = v_[i], rest_w_[i] = w_[i];
    }
  }
  auto find = [&](std::uint32_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  };
  // A manifold whose friction sits at its Coulomb limit slides, by definition: the solver
  // wanted more tangential impulse than mu times the normal impulse allows and held it to
  // that disc (patch friction: the two tangents together against mu times the points' sum,
  // contacts.h). The speeding-up test above sees only accelerations above sleep_linear /
  // (4 W): a cube on a slope 0.1 degrees past atan(mu) (0.018 m/s^2) slept at 0.6 s after
  // 3 mm and never woke. So when a manifold is at its limit and one of its bodies is faster
  // than its window began, they do not fall asleep in the step, at any acceleration (their
  // window goes on, as for a body speeding up). Held by static friction a manifold sits
  // strictly inside the limit (a box 1 degree under atan(mu): 0.91 of it at mu 0.2, 0.96 at
  // 0.8). The speed that grew tells a slider from a body held at its limit by other contacts
  // (a box leaning on another: clamped each step while the other holds it still, five such
  // boxes were awake at 5 s) and from XPBD's resting pairs, whose stored normal impulse (the
  // position solve's) is not the load its static friction holds (a two-box stack's upper pair
  // at 2e5 times it); a slider that slows down stops within its window anyway. Grew by more
  // than the float rows' rounding of a step's fall, 2^-20 g |gravity_scale| dt (1.6e-7 m/s
  // at the defaults): bodies held still in the rain's heaps, friction at the limit, drift at
  // 1e-10-1e-8 m/s and kept 64 bodies awake at 10 s; a slider gains a W over its window.
  // "At" the limit is within 2^-20 of it either way: the soft step's and TGS's float rows
  // put a sliding manifold within 2e-7 of it, XPBD's exactly (measured). With no friction
  // (mu 0) or no load (a speculative manifold) the limit is 0 and nothing slides. Tested only
  // for a manifold whose awake bodies' windows are all full (before that the island stays
  // awake anyway).
  // That floor alone caught creep the tolerances are meant to hide: soft-step square pyramids
  // of 6-10 levels slept at 5.4-5.6 s (0.52 s before the rule; with sleeping off they move
  // 1 mm in all after it), a box set down at exactly atan(mu) at 5.3-5.7 s and never under
  // sequential impulses. So the gain must also show an acceleration of at least
  // sleep_linear / (64 W): a slide that would take 64 windows from rest to reach the linear
  // tolerance is rest, as a body that slow is (1.6e-3 m/s^2 at the defaults, 16 times below
  // the speeding-up test's). A choice: the slowest slide the tests keep awake is 5.6 times
  // above it (0.0087 m/s^2, 0.05 degrees past atan(mu) at mu 0.2), the pyramid's creep 18
  // times below (1 mm over 4.8 s, as a steady acceleration at most 2 d / t^2 = 8.7e-5 m/s^2),
  // and the box at atan(mu) does not speed up: it coasts, slowing, at the speed its first step
  // gave it (4.8 mm/s under the soft step at mu 0.5). The acceleration is the window's steady
  // one, the part of the gain a kick at the window's start does not explain: a kick k then
  // coasting gives dv = k and excess motion e = d - v0 t = k t, a steady a gives dv = a t and
  // e = a t^2 / 2 (the steps' sums: a t (t + dt) / 2), so dv t - e is a t^2 / 2
  // (a t (t - dt) / 2) and 0 for the kick. The soft step's and TGS's start-up slide is such a
  // kick, and counted as |dv| / t it kept that box awake for 3 s; a kick later in the window
  // counts as 2 k s / t^2, s its time into the window
  constexpr double kBelow = 1 - 0x1p-20, kAbove = 1 + 0x1p-20;
  auto sliding = [](const detail::ContactPair& c) {
    double load = 0;
    for (int k = 0; k < c.count; ++k) load += c.normal_impulse[k];
    const double limit = c.friction * load;
    const double t = c.tangent_impulse[0] * c.tangent_impulse[0] + c.tangent_impulse[1] * c.tangent_impulse[1];
    return limit > 0 && t >= (kBelow * limit) * (kBelow * limit) && t <= (kAbove * limit) * (kAbove * limit);
  };
  const double noise = 0x1p-20 * g * dt;  // m/s, over the body's |gravity_scale|
  const double creep = settings_.sleep_linear / 128;  // m/s, the least steady a t^2 / 2 over t^2 / W
  auto grew = [&](std::uint32_t i) {
    const Vec3 dv = v_[i] - rest_v_[i];
    const double floor = noise * std::abs(gravity_scale_[i]);
    if (glm::dot(v_[i], v_[i]) <= glm::dot(rest_v_[i], rest_v_[i]) || glm::dot(dv, dv) <= floor * floor) return false;
    const double t = sleep_time_[i];
    const Vec3 steady = dv * t - (com_[i] - rest_com_[i] - rest_v_[i] * t);  // m, a t^2 / 2
    const double least = creep * t * t / window_of(i);
    return glm::dot(steady, steady) > least * least;
  };
  for (const detail::ContactPair& c : contacts_->pairs) {
    const bool da = type_[c.a] == BodyType::Dynamic && !asleep_[c.a];
    const bool db = type_[c.b] == BodyType::Dynamic && !asleep_[c.b];
    if ((da || db) && (!da || island_slow_[c.a] >= 0) && (!db || island_slow_[c.b] >= 0) &&
        ((da && grew(c.a)) || (db && grew(c.b))) && sliding(c)) {
      if (da) island_slow_[c.a] = -INFINITY;
      if (db) island_slow_[c.b] = -INFINITY;
    }
    if (da && db) {
      // the smaller root wins, so the islands do not depend on the pair order
      const std::uint32_t ra = find(c.a), rb = find(c.b);
      if (ra != rb) parent_[std::max(ra, rb)] = std::min(ra, rb);
    } else {
      // a moving kinematic body keeps what it touches awake
      const std::uint32_t other = da ? c.a : c.b, k = da ? c.b : c.a;
      if ((da || db) && type_[k] == BodyType::Kinematic &&
          (glm::dot(v_[k], v_[k]) > 0 || glm::dot(w_[k], w_[k]) > 0))
        sleep_time_[other] = 0, island_slow_[other] = -INFINITY;
    }
  }
  // the least slow time past its body's window of each island (its root: the island's
  // smallest index); the island sleeps when that is >= 0 (a - b >= 0 exactly when a >= b)
  // (island_slow_[i] holds body i's own until i is reached: the root is an island's smallest
  // index, so only the entries before i have been written to. A body a moving kinematic body
  // touches holds -infinity, where its slow time was 0 less its window: as negative)
  for (std::size_t i = lo; i < hi; ++i) {
    if (type_[i] != BodyType::Dynamic || asleep_[i]) continue;
    const std::uint32_t r = find(static_cast<std::uint32_t>(i));
    parent_[i] = r;
    island_slow_[r] = std::min(island_slow_[r], island_slow_[i]);
  }
  // islands slow for long enough fall asleep, their members linked in a ring from the root
  // (which comes first in index order)
  for (std::size_t i = lo; i < hi; ++i) {
    if (type_[i] != BodyType::Dynamic || asleep_[i]) continue;
    const std::uint32_t r = parent_[i];
    if (island_slow_[r] < 0) continue;
    asleep_[i] = 1;
    v_[i] = Vec3(0);
    w_[i] = Vec3(0);
    if (r == i) {
      island_[i] = r;
    } else {
      island_[i] = island_[r];
      island_[r] = static_cast<std::uint32_t>(i);
    }
  }
  profile_.islands = clock.seconds();
}

void RigidBodySystem::wake_island(std::size_t i) {
  // a new rest window for the body, or for each body around its island's ring
  if (!asleep_[i]) {
    sleep_time_[i] = 0, rest_com_[i] = com_[i], rest_q_[i] = q_[i], rest_v_[i] = v_[i], rest_w_[i] = w_[i];
    return;
  }
  std::size_t k = i;
  do {
    const std::size_t next = island_[k];
    asleep_[k] = 0, sleep_time_[k] = 0, island_[k] = static_cast<std::uint32_t>(k);
    rest_com_[k] = com_[k], rest_q_[k] = q_[k], rest_v_[k] = v_[k], rest_w_[k] = w_[k];
    k = next;
  } while (k != i);
}

bool RigidBodySystem::awake(RigidBodyId id) const {
  const std::size_t i = index(id, "RigidBodySystem::awake");
  return type_[i] == BodyType::Kinematic || (type_[i] == BodyType::Dynamic && !asleep_[i]);
}

void RigidBodySystem::wake(RigidBodyId id) { wake_island(index(id, "RigidBodySystem::wake")); }

std::size_t RigidBodySystem::awake_count() const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < type_.size(); ++i) n += type_[i] == BodyType::Dynamic && !asleep_[i];
  return n;
}

std::vector<RigidContactPoint> RigidBodySystem::contacts() const {
  std::vector<RigidContactPoint> out;
  for (const detail::ContactPair& c : contact_state(contacts_).pairs)
    for (int k = 0; k < c.count; ++k) {
      const detail::SolverPoint& p = c.points[k];
      RigidContactPoint r;
      r.a = {c.slot_a, ids_.generation(c.slot_a)};
      r.b = {c.slot_b, ids_.generation(c.slot_b)};
      r.position = p.at;
      r.normal = c.normal;
      r.depth = c.depth[k];
      r.normal_impulse = c.normal_impulse[k];
      r.tangent_impulse = std::hypot(c.tangent_impulse[0], c.tangent_impulse[1]) / c.count;
      r.id = c.id[k];
      out.push_back(r);
    }
  return out;
}

std::size_t RigidBodySystem::manifold_count() const { return contact_state(contacts_).pairs.size(); }

RigidManifoldInfo RigidBodySystem::manifold(std::size_t k) const {
  if (k >= manifold_count())
    throw Error("RigidBodySystem::manifold: index " + std::to_string(k) + " out of range [0, " +
                std::to_string(manifold_count()) + ")");
  const detail::ContactPair& c = contacts_->pairs[k];
  RigidManifoldInfo m;
  m.a = {c.slot_a, ids_.generation(c.slot_a)};
  m.b = {c.slot_b, ids_.generation(c.slot_b)};
  m.normal = c.normal;
  m.points = c.count;
  const long color = contacts_->color_of_pair(k);
  m.color = color >= 0 && color < static_cast<long>(contacts_->color_count.size()) ? static_cast<int>(color) : -1;
  m.depth = -INFINITY;
  // the deepest point, the fastest approach (approach < 0 closes) and the largest push
  for (int i = 0; i < c.count; ++i) {
    if (c.depth[i] > m.depth) m.depth = c.depth[i], m.point = c.points[i].at;
    double approach = 0, max_impulse = 0;  // (0 when the solver keeps none: XPBD)
    contacts_->solver_report(k, i, approach, max_impulse);
    m.approach_speed = std::max(m.approach_speed, -approach);
    m.max_normal_impulse = std::max(m.max_normal_impulse, max_impulse);
  }
  return m;
}

std::vector<Aabb> RigidBodySystem::shape_bounds(RigidBodyId id) const {
  const std::size_t i = index(id, "RigidBodySystem::shape_bounds");
  const Pose body = body_pose(i);
  std::vector<Aabb> out;
  for (const RigidShapeDef& d : shapes_[i])
    out.push_back(bounds(d.shape, detail::shape_frame(body, d.local)));
  return out;
}

std::span<const RigidShapeDef> RigidBodySystem::shapes(RigidBodyId id) const {
  return shapes_[index(id, "RigidBodySystem::shapes")];
}

std::uint64_t RigidBodySystem::hash() const {
  std::uint64_t h = hash_span(std::span<const Vec3>(com_));
  h = hash_span(std::span<const Quat>(q_), h);
  h = hash_span(std::span<const Vec3>(v_), h);
  return hash_span(std::span<const Vec3>(w_), h);
}

}  // namespace pba
