// The JSON scene-file reader (docs/scene-format.md). nlohmann::json stays in this file.
//
// Every value is read through a Node that knows its JSON pointer (RFC 6901), so every
// error names the file, the path of the bad field and what is wrong with it. Unknown
// fields are errors too (a typo must not be silently ignored). A later module adds its
// array by adding a row to kSections below and a reader function beside the others.
#include <cmath>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pba/scene.h"
#include "pba/soft.h"

namespace pba {

namespace {

using json = nlohmann::json;

// the file name that prefixes every message
struct Context {
  std::string source;
};

// a JSON value and where it is
class Node {
 public:
  Node(const json& j, std::string path, const Context& ctx) : j_(j), path_(std::move(path)), ctx_(ctx) {}

  const std::string& path() const { return path_; }
  const json& raw() const { return j_; }
  [[noreturn]] void fail(const std::string& what) const {
    throw Error(ctx_.source + ": " + (path_.empty() ? "/" : path_) + ": " + what);
  }
  // the message prefix for library validation of this node
  std::string where() const { return ctx_.source + ": " + (path_.empty() ? "/" : path_); }

  // ---- structure ----
  void require_object() const {
    if (!j_.is_object()) fail("must be an object, got " + type_name(j_));
  }
  void require_array() const {
    if (!j_.is_array()) fail("must be an array, got " + type_name(j_));
  }
  // unknown fields are errors: list what is allowed
  void allow_only(std::initializer_list<const char*> keys) const {
    require_object();
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      bool ok = false;
      for (const char* k : keys) ok |= it.key() == k;
      if (ok) continue;
      std::string list;
      for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
      Node(it.value(), child_path(it.key()), ctx_).fail("unknown field (allowed here: " + list + ")");
    }
  }
  bool has(const char* key) const { return j_.is_object() && j_.contains(key); }
  Node at(const char* key) const {
    if (!has(key)) fail(std::string("missing required field \"") + key + "\"");
    return Node(j_.at(key), child_path(key), ctx_);
  }
  Node item(std::size_t i) const { return Node(j_.at(i), path_ + "/" + std::to_string(i), ctx_); }
  std::size_t size() const { return j_.size(); }

  // ---- leaves ----
  double number() const {
    if (!j_.is_number()) fail("must be a number, got " + type_name(j_));
    const double v = j_.get<double>();
    if (!std::isfinite(v)) fail("must be a finite number, got " + format_value(v));
    return v;
  }
  std::string string() const {
    if (!j_.is_string()) fail("must be a string, got " + type_name(j_));
    return j_.get<std::string>();
  }
  bool boolean() const {
    if (!j_.is_boolean()) fail("must be true or false, got " + type_name(j_));
    return j_.get<bool>();
  }
  Vec3 vec3() const {
    if (!j_.is_array() || j_.size() != 3) fail("must be an array of 3 numbers, got " + type_name(j_));
    return {item(0).number(), item(1).number(), item(2).number()};
  }
  long long integer(long long lo, long long hi) const {
    if (!j_.is_number_integer() && !j_.is_number_unsigned()) fail("must be an integer, got " + type_name(j_));
    const long long v = j_.is_number_unsigned() ? static_cast<long long>(j_.get<unsigned long long>())
                                                : j_.get<long long>();
    if (v < lo || v > hi)
      fail("must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
           std::to_string(v));
    return v;
  }

  // ---- optional fields with range checks ----
  double num(const char* key, double def) const { return has(key) ? at(key).number() : def; }
  double positive(const char* key, double def) const {
    const double v = num(key, def);
    if (!(v > 0)) at(key).fail("must be > 0, got " + format_value(v));
    return v;
  }
  double non_negative(const char* key, double def) const {
    const double v = num(key, def);
    if (!(v >= 0)) at(key).fail("must be >= 0, got " + format_value(v));
    return v;
  }
  double in_range(const char* key, double lo, double hi, double def) const {
    const double v = num(key, def);
    if (!(v >= lo && v <= hi))
      at(key).fail("must be in [" + format_value(lo) + ", " + format_value(hi) + "], got " + format_value(v));
    return v;
  }
  Vec3 vec(const char* key, const Vec3& def) const { return has(key) ? at(key).vec3() : def; }
  Vec3 nonzero_vec(const char* key, const Vec3& def) const {
    const Vec3 v = vec(key, def);
    if (glm::length(v) == 0) at(key).fail("must be a non-zero vector, got (0, 0, 0)");
    return v;
  }
  bool flag(const char* key, bool def) const { return has(key) ? at(key).boolean() : def; }
  std::string str(const char* key, const std::string& def) const { return has(key) ? at(key).string() : def; }
  // one of a fixed set of names
  template <class E>
  E choice(const char* key, std::initializer_list<std::pair<const char*, E>> options, E def) const {
    if (!has(key)) return def;
    const std::string s = at(key).string();
    std::string list;
    for (const auto& [name, value] : options) {
      if (s == name) return value;
      list += (list.empty() ? "\"" : ", \"") + std::string(name) + "\"";
    }
    at(key).fail("unknown value \"" + s + "\" (expected one of " + list + ")");
  }
  template <class E>
  E required_choice(const char* key, std::initializer_list<std::pair<const char*, E>> options) const {
    at(key);  // missing -> error
    return choice(key, options, options.begin()->second);
  }

  static std::string type_name(const json& j) {
    if (j.is_null()) return "null";
    if (j.is_boolean()) return j.get<bool>() ? "true" : "false";
    if (j.is_number()) return "the number " + format_value(j.get<double>());
    if (j.is_string()) return "the string \"" + j.get<std::string>() + "\"";
    if (j.is_array()) return "an array of " + std::to_string(j.size());
    return "an object";
  }

 private:
  // JSON pointer escaping: ~ -> ~0, / -> ~1
  std::string child_path(const std::string& key) const {
    std::string k;
    for (char c : key) {
      if (c == '~')
        k += "~0";
      else if (c == '/')
        k += "~1";
      else
        k += c;
    }
    return path_ + "/" + k;
  }

  const json& j_;
  std::string path_;
  const Context& ctx_;
};

// a rotation: "rotation_deg": [x, y, z] (applied about X, then Y, then Z) or
// "rotation": [w, x, y, z] (normalised; must be non-zero)
Quat read_rotation(const Node& n) {
  if (n.has("rotation") && n.has("rotation_deg")) n.at("rotation").fail("give either rotation or rotation_deg");
  if (n.has("rotation_deg")) {
    const Vec3 d = n.at("rotation_deg").vec3() * (kPi / 180);
    return glm::normalize(glm::angleAxis(d.z, Vec3(0, 0, 1)) * glm::angleAxis(d.y, Vec3(0, 1, 0)) *
                          glm::angleAxis(d.x, Vec3(1, 0, 0)));
  }
  if (n.has("rotation")) {
    const Node r = n.at("rotation");
    if (!r.raw().is_array() || r.size() != 4)
      r.fail("must be a quaternion [w, x, y, z], got " + Node::type_name(r.raw()));
    const Quat q(r.item(0).number(), r.item(1).number(), r.item(2).number(), r.item(3).number());
    const double len = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    if (len == 0) r.fail("must be a non-zero quaternion");
    return q / len;
  }
  return Quat(1, 0, 0, 0);
}

Pose read_pose(const Node& n) { return Pose{n.vec("position", Vec3(0)), read_rotation(n)}; }

// a colour: "#rrggbb", "#rrggbbaa" or [r, g, b] / [r, g, b, a] in [0, 1]
Color read_color(const Node& n, const char* key, Color def) {
  if (!n.has(key)) return def;
  const Node c = n.at(key);
  if (c.raw().is_string()) {
    const std::string s = c.string();
    const bool ok = (s.size() == 7 || s.size() == 9) && s[0] == '#' &&
                    s.find_first_not_of("0123456789abcdefABCDEF", 1) == std::string::npos;
    if (!ok) c.fail("must be \"#rrggbb\" or \"#rrggbbaa\", got \"" + s + "\"");
    const auto v = static_cast<std::uint32_t>(std::stoul(s.substr(1, 6), nullptr, 16));
    const float a = s.size() == 9 ? std::stoul(s.substr(7, 2), nullptr, 16) / 255.0f : 1.0f;
    return Color::hex(v, a);
  }
  if (!c.raw().is_array() || (c.size() != 3 && c.size() != 4))
    c.fail("must be \"#rrggbb\" or an array [r, g, b(, a)], got " + Node::type_name(c.raw()));
  float ch[4] = {1, 1, 1, 1};
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double v = c.item(i).number();
    if (!(v >= 0 && v <= 1)) c.item(i).fail("must be in [0, 1], got " + format_value(v));
    ch[i] = static_cast<float>(v);
  }
  return Color::rgb(ch[0], ch[1], ch[2], ch[3]);
}

KinematicDef read_kinematic(const Node& n) {
  n.allow_only({"path", "velocity", "center", "axis", "radius", "angular_speed", "phase", "waypoints", "speed",
                "loop", "spin", "thrust"});
  KinematicDef k;
  k.path = n.required_choice<PathType>("path", {{"linear", PathType::Linear},
                                                {"circular", PathType::Circular},
                                                {"waypoints", PathType::Waypoints},
                                                {"motor", PathType::Motor},
                                                {"thruster", PathType::Thruster}});
  k.velocity = n.vec("velocity", k.velocity);
  k.center = n.vec("center", k.center);
  k.axis = n.nonzero_vec("axis", k.axis);
  k.radius = n.positive("radius", k.radius);
  k.angular_speed = n.num("angular_speed", k.angular_speed);
  k.phase = n.num("phase", k.phase);
  k.speed = n.positive("speed", k.speed);
  k.loop = n.flag("loop", k.loop);
  k.spin = n.vec("spin", k.spin);
  k.thrust = n.vec("thrust", k.thrust);
  if (k.path == PathType::Waypoints) {
    const Node w = n.at("waypoints");
    w.require_array();
    if (w.size() < 2) w.fail("needs at least 2 points, got " + std::to_string(w.size()));
    for (std::size_t i = 0; i < w.size(); ++i) k.waypoints.push_back(w.item(i).vec3());
  } else if (n.has("waypoints")) {
    n.at("waypoints").fail("only for \"path\": \"waypoints\"");
  }
  k.validate(n.where());
  return k;
}

// fields every entity-like item may have
void read_common(const Node& n, World& w, EntityId e) {
  if (n.has("kinematic")) w.add_kinematic(e, read_kinematic(n.at("kinematic")));
}

EntityId make_entity(const Node& n, World& w) {
  return w.create_entity({.name = n.str("name", ""), .pose = read_pose(n)});
}

// an integrator name (the integrate module's message lists the valid names)
Method read_method(const Node& m) {
  try {
    return parse_method(m.string(), "integrator");
  } catch (const Error& err) {
    std::string msg = err.what();
    const std::string prefix = "integrator: ";
    if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
    m.fail(msg);
  }
}

void read_settings(const Node& n, WorldDef& def) {
  n.allow_only({"dt", "integrator", "strategy", "max_ticks_per_frame", "capacity", "gravity", "drag", "wind",
                "restitution_threshold"});
  def.stepper.fixed_dt = n.in_range("dt", 1e-6, 10, def.stepper.fixed_dt);
  if (n.has("integrator")) def.particles.method = read_method(n.at("integrator"));
  if (n.has("strategy")) {
    const Node s = n.at("strategy");
    try {
      def.stepper.strategy = parse_strategy(s.string(), "strategy");
    } catch (const Error& err) {
      std::string msg = err.what();
      const std::string prefix = "strategy: ";
      if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
      s.fail(msg);
    }
  }
  if (n.has("max_ticks_per_frame"))
    def.stepper.max_ticks_per_frame = static_cast<int>(n.at("max_ticks_per_frame").integer(1, 100000));
  if (n.has("capacity")) def.particles.capacity = static_cast<std::size_t>(n.at("capacity").integer(0, 1LL << 28));
  Forces& f = def.particles.forces;
  def.gravity = n.vec("gravity", def.gravity);  // the world's, read by every system
  f.gravity = def.gravity;
  if (n.has("drag")) {
    const Node d = n.at("drag");
    d.allow_only({"linear", "quadratic"});
    f.linear_drag = d.non_negative("linear", f.linear_drag);
    f.quadratic_drag = d.non_negative("quadratic", f.quadratic_drag);
  }
  if (n.has("wind")) {
    const Node d = n.at("wind");
    d.allow_only({"velocity", "gust", "gust_period", "seed"});
    f.wind.velocity = d.vec("velocity", f.wind.velocity);
    f.wind.gust = d.non_negative("gust", f.wind.gust);
    f.wind.gust_period = d.positive("gust_period", f.wind.gust_period);
    if (d.has("seed")) f.wind.seed = static_cast<std::uint32_t>(d.at("seed").integer(0, 0xffffffffLL));
  }
  def.particles.collision.restitution_threshold =
      n.num("restitution_threshold", def.particles.collision.restitution_threshold);
}

void read_particle(const Node& n, World& w) {
  n.allow_only({"name", "position", "rotation", "rotation_deg", "velocity", "mass", "radius", "lifetime", "color",
                "end_color", "kinematic"});
  ParticleDef d;
  d.velocity = n.vec("velocity", d.velocity);
  d.mass = n.positive("mass", d.mass);
  d.radius = n.positive("radius", d.radius);
  d.lifetime = n.has("lifetime") ? n.positive("lifetime", 1) : kForever;
  d.color = read_color(n, "color", d.color);
  d.end_color = read_color(n, "end_color", d.color);
  const EntityId e = make_entity(n, w);
  w.add_particle(e, d);
  read_common(n, w, e);
}

void read_emitter(const Node& n, World& w) {
  n.allow_only({"name", "position", "rotation", "rotation_deg", "direction", "spread", "spread_deg", "speed",
                "speed_jitter", "rate", "lifetime", "lifetime_jitter", "mass", "radius", "start_color", "end_color",
                "max_alive", "seed", "enabled", "kinematic"});
  EmitterDef d;
  d.direction = n.nonzero_vec("direction", d.direction);
  if (n.has("spread") && n.has("spread_deg")) n.at("spread").fail("give either spread or spread_deg");
  d.spread = n.has("spread_deg") ? n.in_range("spread_deg", 0, 180, 0) * kPi / 180 : n.in_range("spread", 0, kPi, d.spread);
  d.speed = n.non_negative("speed", d.speed);
  d.speed_jitter = n.in_range("speed_jitter", 0, 1, d.speed_jitter);
  d.rate = n.non_negative("rate", d.rate);
  d.lifetime = n.positive("lifetime", d.lifetime);
  d.lifetime_jitter = n.in_range("lifetime_jitter", 0, 0.999, d.lifetime_jitter);
  d.mass = n.positive("mass", d.mass);
  d.radius = n.positive("radius", d.radius);
  d.start_color = read_color(n, "start_color", d.start_color);
  d.end_color = read_color(n, "end_color", d.end_color);
  if (n.has("max_alive")) d.max_alive = static_cast<std::size_t>(n.at("max_alive").integer(0, 1LL << 28));
  if (n.has("seed")) d.seed = static_cast<std::uint64_t>(n.at("seed").integer(0, 1LL << 62));
  d.enabled = n.flag("enabled", d.enabled);
  const EntityId e = make_entity(n, w);
  w.add_emitter(e, d);
  read_common(n, w, e);
}

void read_forcer(const Node& n, World& w) {
  n.allow_only({"name", "kind", "shape", "position", "rotation", "rotation_deg", "half_extents", "radius",
                "half_height", "direction", "strength", "pull", "softening", "pulse_period", "pulse_duration",
                "kinematic"});
  Forcer f;
  f.kind = n.required_choice<ForcerKind>(
      "kind", {{"fan", ForcerKind::Fan}, {"vortex", ForcerKind::Vortex}, {"attractor", ForcerKind::Attractor}});
  f.shape = n.choice<ForcerShape>(
      "shape", {{"box", ForcerShape::Box}, {"cylinder", ForcerShape::Cylinder}, {"sphere", ForcerShape::Sphere}},
      f.shape);
  if (n.has("half_extents")) {
    f.half_extents = n.at("half_extents").vec3();
    for (int i = 0; i < 3; ++i)
      if (!(f.half_extents[i] > 0)) n.at("half_extents").item(i).fail("must be > 0, got " + format_value(f.half_extents[i]));
  }
  f.radius = n.positive("radius", f.radius);
  f.half_height = n.positive("half_height", f.half_height);
  f.direction = n.nonzero_vec("direction", f.direction);
  f.strength = n.num("strength", f.strength);
  f.pull = n.num("pull", f.pull);
  f.softening = n.positive("softening", f.softening);
  f.pulse_period = n.non_negative("pulse_period", f.pulse_period);
  f.pulse_duration = n.in_range("pulse_duration", 0, f.pulse_period > 0 ? f.pulse_period : 1e300, f.pulse_duration);
  const EntityId e = make_entity(n, w);
  w.add_forcer(e, f);  // the forcer's own pose is the entity's
  read_common(n, w, e);
}

void read_collider(const Node& n, World& w) {
  n.allow_only({"name", "type", "position", "rotation", "rotation_deg", "normal", "offset", "radius",
                "half_extents", "restitution", "friction", "kinematic"});
  ColliderDef c;
  c.shape.type = n.required_choice<ShapeType>(
      "type", {{"plane", ShapeType::Plane}, {"sphere", ShapeType::Sphere}, {"box", ShapeType::Box}});
  // shape fields belong to one type each
  auto only_for = [&](const char* key, ShapeType t, const char* type_name) {
    if (n.has(key) && c.shape.type != t) n.at(key).fail(std::string("only for \"type\": \"") + type_name + "\"");
  };
  only_for("normal", ShapeType::Plane, "plane");
  only_for("offset", ShapeType::Plane, "plane");
  only_for("radius", ShapeType::Sphere, "sphere");
  only_for("half_extents", ShapeType::Box, "box");
  c.shape.normal = n.nonzero_vec("normal", c.shape.normal);
  c.shape.offset = n.num("offset", c.shape.offset);
  if (c.shape.type == ShapeType::Sphere) c.shape.radius = n.positive("radius", c.shape.radius);
  if (n.has("half_extents")) {
    c.shape.half_extents = n.at("half_extents").vec3();
    for (int i = 0; i < 3; ++i)
      if (!(c.shape.half_extents[i] > 0))
        n.at("half_extents").item(i).fail("must be > 0, got " + format_value(c.shape.half_extents[i]));
  }
  c.material.restitution = n.in_range("restitution", 0, 1, c.material.restitution);
  c.material.friction = n.non_negative("friction", c.material.friction);
  const EntityId e = make_entity(n, w);
  w.add_collider(e, c);
  read_common(n, w, e);
}

// a jelly's shape fields: centre, size, rotation, cells, mass and velocity
JellyDef read_jelly_shape(const Node& n) {
  JellyDef j;
  j.center = n.vec("center", j.center);
  if (n.has("size")) {
    j.size = n.at("size").vec3();
    for (int i = 0; i < 3; ++i)
      if (!(j.size[i] > 0)) n.at("size").item(i).fail("must be > 0, got " + format_value(j.size[i]));
  }
  j.rotation = read_rotation(n);
  if (n.has("cells")) {
    const Node c = n.at("cells");
    if (!c.raw().is_array() || c.size() != 3) c.fail("must be an array of 3 integers, got " + Node::type_name(c.raw()));
    j.nx = static_cast<int>(c.item(0).integer(1, 64));
    j.ny = static_cast<int>(c.item(1).integer(1, 64));
    j.nz = static_cast<int>(c.item(2).integer(1, 64));
  }
  j.mass = n.positive("mass", j.mass);
  j.velocity = n.vec("velocity", j.velocity);
  return j;
}

// a jelly's optional "material": {"young": Pa, "poisson": nu, "damping_time": s}, with the
// ranges jelly_settings accepts (checked here so that the message names the JSON path)
JellyMaterial read_jelly_material(const Node& n) {
  JellyMaterial m;
  if (!n.has("material")) return m;
  const Node mn = n.at("material");
  mn.allow_only({"young", "poisson", "damping_time"});
  m.young = mn.positive("young", m.young);
  m.poisson = mn.in_range("poisson", 0.27, 0.49, m.poisson);
  m.damping_time = mn.non_negative("damping_time", m.damping_time);
  return m;
}

// A soft body (pba/soft.h): "type" is "spring", "rope", "cloth" or "jelly"; the solver
// settings are shared by all types, the shape fields belong to one type each. Gravity and
// wind are the world's (settings); drag is per body. A jelly's settings start from
// jelly_settings(shape, material, the world's step) (Error names the JSON path).
void read_soft_body(const Node& n, World& w) {
  enum class Type { Spring, Rope, Cloth, Jelly };
  const Type type = n.required_choice<Type>(
      "type", {{"spring", Type::Spring}, {"rope", Type::Rope}, {"cloth", Type::Cloth}, {"jelly", Type::Jelly}});
  // the allowed fields: common ones plus the type's
  switch (type) {
    case Type::Spring:
      n.allow_only({"type", "name", "solver", "integrator", "substeps", "iterations", "stretch_compliance",
                    "spring_damping", "damping", "drag", "thickness", "friction", "a", "b", "velocity_b", "mass",
                    "stiffness", "rest_length", "fixed_a"});
      break;
    case Type::Rope:
      n.allow_only({"type", "name", "solver", "integrator", "substeps", "iterations", "stretch_compliance",
                    "bend_compliance", "stretch_stiffness", "bend_stiffness", "spring_damping", "damping", "drag",
                    "tear_strain", "thickness", "friction", "from", "to", "segments", "mass", "pin_start", "pin_end",
                    "bending"});
      break;
    case Type::Cloth:
      n.allow_only({"type", "name", "solver", "integrator", "substeps", "iterations", "stretch_compliance",
                    "shear_compliance", "bend_compliance", "stretch_stiffness", "shear_stiffness", "bend_stiffness",
                    "spring_damping", "damping", "drag", "aero", "tear_strain", "thickness", "friction", "origin",
                    "edge_u", "edge_v", "nx", "ny", "mass", "pins", "shear", "bending"});
      break;
    case Type::Jelly:
      n.allow_only({"type", "name", "solver", "integrator", "substeps", "iterations", "stretch_compliance",
                    "volume_compliance", "stretch_stiffness", "volume_stiffness", "spring_damping", "damping", "drag",
                    "thickness", "friction", "center", "size", "rotation", "rotation_deg", "cells", "mass",
                    "velocity", "material"});
      break;
  }
  // a jelly's shape comes first: its settings start from its material at the world's step
  JellyDef j;
  if (type == Type::Jelly) j = read_jelly_shape(n);
  // solver settings (the fields given override the jelly's)
  SoftBodyDef d = type == Type::Jelly
                      ? jelly_settings(j, read_jelly_material(n), w.stepper().settings().fixed_dt)
                      : SoftBodyDef{};
  d.forces.gravity = w.gravity();
  d.forces.wind = w.particles().forces().wind;
  d.solver = n.choice<SoftSolver>("solver", {{"xpbd", SoftSolver::XPBD}, {"mass-spring", SoftSolver::MassSpring}},
                                  d.solver);
  if (n.has("integrator")) d.method = read_method(n.at("integrator"));
  if (type == Type::Spring) d.substeps = 1;  // one integrator step per tick unless asked
  if (n.has("substeps")) d.substeps = static_cast<int>(n.at("substeps").integer(1, 10000));
  if (n.has("iterations")) d.iterations = static_cast<int>(n.at("iterations").integer(1, 1000));
  d.stretch_compliance = n.non_negative("stretch_compliance", d.stretch_compliance);
  d.shear_compliance = n.non_negative("shear_compliance", d.shear_compliance);
  d.bend_compliance = n.non_negative("bend_compliance", d.bend_compliance);
  d.volume_compliance = n.non_negative("volume_compliance", d.volume_compliance);
  d.stretch_stiffness = n.non_negative("stretch_stiffness", d.stretch_stiffness);
  d.shear_stiffness = n.non_negative("shear_stiffness", d.shear_stiffness);
  d.bend_stiffness = n.non_negative("bend_stiffness", d.bend_stiffness);
  d.volume_stiffness = n.non_negative("volume_stiffness", d.volume_stiffness);
  d.spring_damping = n.non_negative("spring_damping", d.spring_damping);
  d.damping = n.non_negative("damping", d.damping);
  d.tear_strain = n.non_negative("tear_strain", d.tear_strain);
  d.thickness = n.non_negative("thickness", d.thickness);
  d.friction = n.non_negative("friction", d.friction);
  if (n.has("drag")) {
    const Node g = n.at("drag");
    g.allow_only({"linear", "quadratic"});
    d.forces.linear_drag = g.non_negative("linear", 0);
    d.forces.quadratic_drag = g.non_negative("quadratic", 0);
  }
  if (n.has("aero")) {
    const Node a = n.at("aero");
    a.allow_only({"air_density", "drag", "lift"});
    d.aero.air_density = a.non_negative("air_density", d.aero.air_density);
    d.aero.drag = a.non_negative("drag", d.aero.drag);
    d.aero.lift = a.non_negative("lift", d.aero.lift);
  }
  // the shape
  SoftBody body;
  switch (type) {
    case Type::Spring: {
      SpringDef sp;
      sp.a = n.vec("a", sp.a);
      sp.b = n.vec("b", sp.b);
      if (glm::length(sp.b - sp.a) == 0)
        n.at("b").fail("zero rest length: b coincides with a at " + format_vec3(sp.a));
      sp.velocity_b = n.vec("velocity_b", sp.velocity_b);
      sp.mass = n.positive("mass", sp.mass);
      sp.stiffness = n.positive("stiffness", sp.stiffness);
      sp.damping = d.spring_damping;
      sp.rest_length = n.has("rest_length") ? n.positive("rest_length", 1) : -1;
      sp.fixed_a = n.flag("fixed_a", sp.fixed_a);
      body = SoftBody::spring(sp, d);
      break;
    }
    case Type::Rope: {
      RopeDef r;
      r.from = n.vec("from", r.from);
      r.to = n.vec("to", r.to);
      if (glm::length(r.to - r.from) == 0) n.at("to").fail("must differ from \"from\" " + format_vec3(r.from));
      if (n.has("segments")) r.segments = static_cast<int>(n.at("segments").integer(1, 100000));
      r.mass = n.positive("mass", r.mass);
      r.pin_start = n.flag("pin_start", r.pin_start);
      r.pin_end = n.flag("pin_end", r.pin_end);
      r.bending = n.flag("bending", r.bending);
      body = SoftBody::rope(r, d);
      break;
    }
    case Type::Cloth: {
      ClothDef c;
      c.origin = n.vec("origin", c.origin);
      c.edge_u = n.nonzero_vec("edge_u", c.edge_u);
      c.edge_v = n.nonzero_vec("edge_v", c.edge_v);
      if (!(glm::length(glm::cross(c.edge_u, c.edge_v)) > 0))
        n.at("edge_v").fail("must not be parallel to edge_u " + format_vec3(c.edge_u));
      if (n.has("nx")) c.nx = static_cast<int>(n.at("nx").integer(2, 4096));
      if (n.has("ny")) c.ny = static_cast<int>(n.at("ny").integer(2, 4096));
      c.mass = n.positive("mass", c.mass);
      c.pins = n.choice<ClothPins>("pins",
                                   {{"none", ClothPins::None},
                                    {"first-row", ClothPins::FirstRow},
                                    {"first-row-corners", ClothPins::FirstRowCorners},
                                    {"first-column", ClothPins::FirstColumn}},
                                   c.pins);
      c.shear = n.flag("shear", c.shear);
      c.bending = n.flag("bending", c.bending);
      body = SoftBody::cloth_grid(c, d);
      break;
    }
    case Type::Jelly: {
      body = SoftBody::jelly_box(j, d);
      break;
    }
  }
  const EntityId e = w.create_entity({.name = n.str("name", "")});
  soft_system(w).add(w, e, std::move(body));
}

// Top-level arrays. A later module adds a row (its name and a reader of one item); the
// names below marked "later" are reserved for the modules that will fill them.
struct Section {
  const char* name;
  void (*read)(const Node&, World&);
};
constexpr Section kSections[] = {
    {"particles", read_particle},
    {"emitters", read_emitter},
    {"forcers", read_forcer},
    {"colliders", read_collider},
    {"soft_bodies", read_soft_body},
};
constexpr const char* kReserved[] = {"rigid_bodies", "skeletons"};

// 1-based line and column of a byte offset
void line_col(std::string_view text, std::size_t byte, std::size_t& line, std::size_t& col) {
  line = 1;
  col = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      col = 1;
    } else {
      ++col;
    }
  }
}

}  // namespace

Scene parse_scene(std::string_view text, std::string_view source) {
  const Context ctx{std::string(source)};
  // syntax: report line and column
  json doc;
  try {
    doc = json::parse(text.begin(), text.end());
  } catch (const json::parse_error& e) {
    std::size_t line = 0, col = 0;
    line_col(text, e.byte > 0 ? e.byte - 1 : 0, line, col);
    std::string what = e.what();
    // drop nlohmann's "[json.exception.parse_error.101] parse error at line 1, column 2: "
    const auto colon = what.find(": ");
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw Error(ctx.source + ":" + std::to_string(line) + ":" + std::to_string(col) + ": JSON syntax error: " + what);
  } catch (const json::exception& e) {
    // e.g. a number literal too large for a double: the parser does not say where, so
    // find the literal in the text
    std::string what = e.what();
    const auto close = what.find("] ");
    if (close != std::string::npos) what = what.substr(close + 2);
    std::size_t line = 1, col = 1;
    const auto q0 = what.find('\''), q1 = what.rfind('\'');
    if (q0 != std::string::npos && q1 > q0) {
      const auto at = text.find(what.substr(q0 + 1, q1 - q0 - 1));
      if (at != std::string_view::npos) line_col(text, at, line, col);
    }
    throw Error(ctx.source + ":" + std::to_string(line) + ":" + std::to_string(col) + ": JSON error: " + what +
                " (numbers must be finite doubles)");
  }
  const Node root(doc, "", ctx);
  root.require_object();
  // the version comes first: a newer file may have fields this reader does not know
  const long long version = root.at("version").integer(1, 1000000);
  if (version > kSceneFormatVersion)
    root.at("version").fail("this build reads scene format version " + std::to_string(kSceneFormatVersion) +
                            ", the file is version " + std::to_string(version));
  // unknown top-level fields, with the reserved ones named as such
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    const std::string& k = it.key();
    if (k == "version" || k == "name" || k == "description" || k == "settings") continue;
    bool known = false;
    for (const Section& s : kSections) known |= k == s.name;
    if (known) continue;
    for (const char* r : kReserved)
      if (k == r) root.at(r).fail("not supported yet by this build (reserved for a later module)");
    std::string list = "version, name, description, settings";
    for (const Section& s : kSections) list += ", " + std::string(s.name);
    root.at(k.c_str()).fail("unknown field (allowed here: " + list + ")");
  }
  // settings, then the world, then every section in a fixed order
  WorldDef def;
  if (root.has("settings")) read_settings(root.at("settings"), def);
  std::string name = root.str("name", "");
  if (name.empty()) name = std::filesystem::path(std::string(source)).stem().string();
  Scene scene{name, root.str("description", ""), World(def)};
  for (const Section& s : kSections) {
    if (!root.has(s.name)) continue;
    const Node arr = root.at(s.name);
    arr.require_array();
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const Node item = arr.item(i);
      item.require_object();
      try {
        s.read(item, scene.world);
      } catch (const Error& e) {
        // library validation messages get the item's location if they lack one
        const std::string msg = e.what();
        if (msg.rfind(ctx.source + ": ", 0) == 0) throw;
        throw Error(item.where() + ": " + msg);
      }
    }
  }
  return scene;
}

Scene load_scene(const std::filesystem::path& file) {
  // read the whole file; a missing file is an Error naming it
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(file.string() + ": cannot open scene file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_scene(ss.str(), file.string());
}

}  // namespace pba
