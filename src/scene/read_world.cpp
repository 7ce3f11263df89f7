// The scene reader's world-level fields (docs/scene-format.md): rotations, poses and
// colours shared by every module, kinematic paths, the settings, shapes and colliders.
#include <algorithm>
#include <cmath>
#include <string>

#include "json_node.h"

namespace pba::scene_detail {

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
    const double big = std::max({std::abs(q.w), std::abs(q.x), std::abs(q.y), std::abs(q.z)});
    if (big == 0) r.fail("must be a non-zero quaternion");
    // far from 1, scaled by its largest component first: the squares of [1e200, 1e200, 0, 0]
    // overflowed (normalised to zeros, refused as "a finite unit quaternion" without the
    // field's path) and those of [1e-200, 0, 0, 0] underflowed (refused as zero)
    const Quat u = big > 1e150 || big < 1e-150 ? q / big : q;
    return u / std::sqrt(u.w * u.w + u.x * u.x + u.y * u.y + u.z * u.z);
  }
  return Quat(1, 0, 0, 0);
}

Pose read_pose(const Node& n) { return Pose{n.float_vec("position", Vec3(0)), read_rotation(n)}; }

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
  // each field belongs to its paths (docs/scene-format.md, "kinematic"); on another path it
  // would be ignored silently
  auto only_for = [&](const char* key, std::initializer_list<PathType> paths, const char* names) {
    if (!n.has(key)) return;
    for (PathType p : paths)
      if (k.path == p) return;
    n.at(key).fail(std::string("only for \"path\": ") + names);
  };
  only_for("velocity", {PathType::Linear, PathType::Thruster}, "\"linear\" or \"thruster\"");
  for (const char* key : {"center", "axis", "radius", "angular_speed", "phase"})
    only_for(key, {PathType::Circular}, "\"circular\"");
  for (const char* key : {"speed", "loop"}) only_for(key, {PathType::Waypoints}, "\"waypoints\"");
  only_for("thrust", {PathType::Thruster}, "\"thruster\"");
  // velocities, the spin and the thrust are stored as floats by the colliders they move
  k.velocity = n.float_vec("velocity", k.velocity);
  k.center = n.vec("center", k.center);
  k.axis = n.nonzero_vec("axis", k.axis);
  k.radius = n.positive("radius", k.radius);
  k.angular_speed = n.num("angular_speed", k.angular_speed);
  k.phase = n.num("phase", k.phase);
  k.speed = n.positive("speed", k.speed);
  k.loop = n.flag("loop", k.loop);
  k.spin = n.float_vec("spin", k.spin);
  k.thrust = n.float_vec("thrust", k.thrust);
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

void read_common(const Node& n, World& w, EntityId e) {
  if (n.has("kinematic")) w.add_kinematic(e, read_kinematic(n.at("kinematic")));
}

EntityId make_entity(const Node& n, World& w) {
  return w.create_entity({.name = n.entity_name(), .pose = read_pose(n)});
}

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
                "restitution_threshold", "rigid"});
  if (n.has("rigid")) read_rigid_settings(n.at("rigid"), def.rigid);
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
  if (n.has("capacity")) {
    // the reserve must fit the particle system's memory budget
    def.particles.capacity = static_cast<std::size_t>(n.at("capacity").integer(0, 1LL << 28));
    require_particle_memory(static_cast<double>(def.particles.capacity), def.particles.memory_budget,
                            n.at("capacity").where());
  }
  Forces& f = def.particles.forces;
  def.gravity = n.float_vec("gravity", def.gravity);  // the world's, read by every system
  f.gravity = def.gravity;
  if (n.has("drag")) {
    const Node d = n.at("drag");
    d.allow_only({"linear", "quadratic"});
    f.linear_drag = d.float_non_negative("linear", f.linear_drag);
    f.quadratic_drag = d.float_non_negative("quadratic", f.quadratic_drag);
  }
  if (n.has("wind")) {
    const Node d = n.at("wind");
    d.allow_only({"velocity", "gust", "gust_period", "seed"});
    f.wind.velocity = d.float_vec("velocity", f.wind.velocity);
    f.wind.gust = d.float_non_negative("gust", f.wind.gust);
    require_particle_speed(glm::length(glm::abs(f.wind.velocity) + Vec3(f.wind.gust)),
                           d.where() + " (velocity + gust)");
    f.wind.gust_period = d.positive("gust_period", f.wind.gust_period);
    if (d.has("seed")) f.wind.seed = static_cast<std::uint32_t>(d.at("seed").integer(0, 0xffffffffLL));
  }
  def.particles.collision.restitution_threshold =
      n.num("restitution_threshold", def.particles.collision.restitution_threshold);
}

void read_collider(const Node& n, World& w) {
  n.allow_only({"name", "type", "position", "rotation", "rotation_deg", "normal", "offset", "radius",
                "half_extents", "half_height", "points", "vertices", "triangles", "children", "restitution",
                "friction", "sensor", "kinematic"});
  ColliderDef c;
  c.shape = read_shape(n, false, 0);  // read_shapes.cpp
  c.sensor = n.flag("sensor", c.sensor);
  c.material.restitution = n.in_range("restitution", 0, 1, c.material.restitution);
  c.material.friction = n.non_negative("friction", c.material.friction);
  const EntityId e = make_entity(n, w);
  w.add_collider(e, c);
  read_common(n, w, e);
}

}  // namespace pba::scene_detail
