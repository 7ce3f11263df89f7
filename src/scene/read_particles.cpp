// The scene reader's particle module (docs/scene-format.md): one item of "particles",
// "emitters" and "forcers".
#include <string>

#include "json_node.h"

namespace pba::scene_detail {

void read_particle(const Node& n, World& w) {
  n.allow_only({"name", "position", "rotation", "rotation_deg", "velocity", "mass", "radius", "lifetime", "color",
                "end_color", "kinematic"});
  ParticleDef d;
  d.velocity = n.float_vec("velocity", d.velocity);
  if (n.has("velocity")) require_particle_speed(glm::length(d.velocity), n.at("velocity").where());
  d.mass = n.mass("mass", d.mass);
  d.radius = n.float_positive("radius", d.radius);
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
  d.spread =
      n.has("spread_deg") ? n.in_range("spread_deg", 0, 180, 0) * kPi / 180 : n.in_range("spread", 0, kPi, d.spread);
  d.speed = n.float_non_negative("speed", d.speed);
  d.speed_jitter = n.in_range("speed_jitter", 0, 1, d.speed_jitter);
  if (n.has("speed"))
    require_particle_speed(d.speed * (1 + d.speed_jitter), n.at("speed").where() + " (with its jitter)");
  d.rate = n.non_negative("rate", d.rate);
  d.lifetime = n.positive("lifetime", d.lifetime);
  d.lifetime_jitter = n.in_range("lifetime_jitter", 0, 0.999, d.lifetime_jitter);
  d.mass = n.mass("mass", d.mass);
  d.radius = n.float_positive("radius", d.radius);
  d.start_color = read_color(n, "start_color", d.start_color);
  d.end_color = read_color(n, "end_color", d.end_color);
  if (n.has("max_alive")) d.max_alive = static_cast<std::size_t>(n.at("max_alive").integer(0, 1LL << 28));
  if (n.has("seed")) d.seed = static_cast<std::uint64_t>(n.at("seed").integer(0, 1LL << 62));
  d.enabled = n.flag("enabled", d.enabled);
  // its live particles must fit the particle system's memory budget
  require_emitter_memory(d, w.particles().memory_budget(), n.where("rate"), n.where("max_alive"));
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
      if (!(f.half_extents[i] > 0))
        n.at("half_extents").item(i).fail("must be > 0, got " + format_value(f.half_extents[i]));
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

}  // namespace pba::scene_detail
