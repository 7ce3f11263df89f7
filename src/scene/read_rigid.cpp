// The scene reader's rigid-body module (docs/scene-format.md): "settings.rigid" (solver and
// contact settings) and one item of "rigid_bodies" (a RigidBody component of a new entity).
#include <string>

#include "json_node.h"

namespace pba::scene_detail {

void read_rigid_settings(const Node& n, RigidSystemDef& def) {
  n.allow_only({"solver", "substeps", "auto_substeps", "auto_substeps_sag", "auto_substeps_sag_fraction",
                "auto_substeps_least", "iterations", "substep_iterations", "relax_iterations", "manifold_iterations",
                "contact_hertz", "damping_ratio", "push_out_speed", "baumgarte", "contact_compliance", "linear_slop",
                "speculative_distance", "reuse_distance", "reuse_angle", "restitution_threshold", "friction_mix", "restitution_mix", "warm_starting",
                "sleep", "sleep_linear", "sleep_angular", "time_to_sleep", "capacity"});
  ContactSettings& c = def.contacts;
  c.solver = n.choice<RigidSolverType>(
      "solver",
      {{"soft-step", RigidSolverType::SoftStep},
       {"sequential-impulse", RigidSolverType::SequentialImpulse},
       {"tgs", RigidSolverType::Tgs},
       {"xpbd", RigidSolverType::Xpbd}},
      c.solver);
  // substeps given are taken exactly, unless auto_substeps asks for more for tall columns
  if (n.has("substeps")) c.substeps = static_cast<int>(n.at("substeps").integer(1, 64)), c.auto_substeps = false;
  c.auto_substeps = n.flag("auto_substeps", c.auto_substeps);
  // the halving's sag budgets: a fraction of each body's size (in [0, 1]) and metres (0: none);
  // with both 0 the substeps are never lowered
  c.auto_substeps_sag = n.non_negative("auto_substeps_sag", c.auto_substeps_sag);
  c.auto_substeps_sag_fraction = n.in_range("auto_substeps_sag_fraction", 0, 1, c.auto_substeps_sag_fraction);
  // the fewest substeps the lowering takes (its ladder's floor)
  if (n.has("auto_substeps_least"))
    c.auto_substeps_least = static_cast<int>(n.at("auto_substeps_least").integer(1, 64));
  if (n.has("iterations")) c.iterations = static_cast<int>(n.at("iterations").integer(1, 1000));
  if (n.has("substep_iterations"))
    c.substep_iterations = static_cast<int>(n.at("substep_iterations").integer(1, 100));
  if (n.has("relax_iterations")) c.relax_iterations = static_cast<int>(n.at("relax_iterations").integer(0, 100));
  if (n.has("manifold_iterations"))
    c.manifold_iterations = static_cast<int>(n.at("manifold_iterations").integer(1, 16));
  c.contact_hertz = n.positive("contact_hertz", c.contact_hertz);
  c.damping_ratio = n.non_negative("damping_ratio", c.damping_ratio);
  c.push_out_speed = n.positive("push_out_speed", c.push_out_speed);
  c.baumgarte = n.in_range("baumgarte", 0, 1, c.baumgarte);
  c.contact_compliance = n.non_negative("contact_compliance", c.contact_compliance);
  c.linear_slop = n.non_negative("linear_slop", c.linear_slop);
  c.speculative_distance = n.non_negative("speculative_distance", c.speculative_distance);
  // a manifold is carried to the next step while its pair moved less than these (m, rad)
  c.reuse_distance = n.non_negative("reuse_distance", c.reuse_distance);
  c.reuse_angle = n.non_negative("reuse_angle", c.reuse_angle);
  c.restitution_threshold = n.non_negative("restitution_threshold", c.restitution_threshold);
  const std::initializer_list<std::pair<const char*, MixRule>> rules = {{"geometric-mean", MixRule::GeometricMean},
                                                                        {"minimum", MixRule::Minimum},
                                                                        {"maximum", MixRule::Maximum},
                                                                        {"average", MixRule::Average},
                                                                        {"product", MixRule::Product}};
  c.friction_mix = n.choice<MixRule>("friction_mix", rules, c.friction_mix);
  c.restitution_mix = n.choice<MixRule>("restitution_mix", rules, c.restitution_mix);
  c.warm_starting = n.flag("warm_starting", c.warm_starting);
  c.sleep = n.flag("sleep", c.sleep);
  c.sleep_linear = n.non_negative("sleep_linear", c.sleep_linear);
  c.sleep_angular = n.non_negative("sleep_angular", c.sleep_angular);
  c.time_to_sleep = n.non_negative("time_to_sleep", c.time_to_sleep);
  if (n.has("capacity")) def.capacity = static_cast<std::size_t>(n.at("capacity").integer(0, 1LL << 26));
}

namespace {

// one item of a body's "shapes": the shape (the collider reader's: every shape type), its
// placement in the body frame, density and material
RigidShapeDef read_rigid_shape(const Node& n) {
  n.allow_only({"type", "normal", "offset", "radius", "half_extents", "half_height", "points", "vertices",
                "triangles", "children", "position", "rotation", "rotation_deg", "density", "restitution",
                "friction", "rolling_resistance"});
  RigidShapeDef s;
  s.shape = read_shape(n, false, 0);  // read_shapes.cpp: every collider shape
  s.local = read_pose(n);
  s.density = n.positive("density", s.density);
  s.material.restitution = n.in_range("restitution", 0, 1, s.material.restitution);
  s.material.friction = n.non_negative("friction", s.material.friction);
  s.rolling_resistance = n.non_negative("rolling_resistance", s.rolling_resistance);
  return s;
}

}  // namespace

void read_rigid_body(const Node& n, World& w) {
  n.allow_only({"name", "type", "position", "rotation", "rotation_deg", "linear_velocity", "angular_velocity",
                "shapes", "mass", "linear_damping", "angular_damping", "gravity_scale", "bullet", "kinematic"});
  RigidBodyDef d;
  d.type = n.choice<BodyType>(
      "type", {{"dynamic", BodyType::Dynamic}, {"kinematic", BodyType::Kinematic}, {"static", BodyType::Static}},
      d.type);
  d.linear_velocity = n.vec("linear_velocity", d.linear_velocity);
  d.angular_velocity = n.vec("angular_velocity", d.angular_velocity);
  if (n.has("linear_velocity")) require_rigid_speed(d.linear_velocity, n.at("linear_velocity").where(), "m/s");
  if (n.has("angular_velocity")) require_rigid_speed(d.angular_velocity, n.at("angular_velocity").where(), "rad/s");
  // a static body's velocities would be dropped silently (RigidBodySystem::create zeroes them)
  for (const char* key : {"linear_velocity", "angular_velocity"})
    if (d.type == BodyType::Static && n.has(key) && n.vec(key, Vec3(0)) != Vec3(0))
      n.at(key).fail("a \"static\" body does not move (make it \"kinematic\" to give it a velocity)");
  // nor would a path's body's: the kinematic stage sets its velocities from the path every tick
  for (const char* key : {"linear_velocity", "angular_velocity"})
    if (n.has("kinematic") && n.has(key) && n.vec(key, Vec3(0)) != Vec3(0))
      n.at(key).fail("a body on a \"kinematic\" path moves as the path says (give the velocity in " +
                     n.at("kinematic").path() + ")");
  // the shapes: at least one; planes and meshes only on static bodies
  const Node shapes = n.at("shapes");
  shapes.require_array();
  if (shapes.size() == 0) shapes.fail("a body needs at least one shape, got none");
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    const Node s = shapes.item(i);
    s.require_object();
    d.shapes.push_back(read_rigid_shape(s));
    const ShapeType type = d.shapes.back().shape.type;
    if (d.type != BodyType::Static && (type == ShapeType::Plane || type == ShapeType::Mesh))
      s.at("type").fail("a " + std::string(to_string(type)) + " has no volume, so only a \"static\" body can have one");
  }
  // a given mass scales the shapes' mass properties (density ratios kept): m I / M about the same centre
  if (n.has("mass")) {
    if (d.type != BodyType::Dynamic) n.at("mass").fail("only for a \"dynamic\" body");
    const double m = n.mass("mass", 1);  // its inverse a normal float, named by its path
    RigidMass total;
    for (std::size_t k = 0; k < d.shapes.size(); ++k) {
      const RigidMass part = RigidMass::of_shape(d.shapes[k].shape, d.shapes[k].density, d.shapes[k].local,
                                                 shapes.item(k).where());
      total = k == 0 ? part : total + part;
    }
    const double f = m / total.mass;
    d.mass = RigidMass{m, total.center, total.inertia * f};
  }
  d.linear_damping = n.non_negative("linear_damping", d.linear_damping);
  d.angular_damping = n.non_negative("angular_damping", d.angular_damping);
  d.gravity_scale = n.num("gravity_scale", d.gravity_scale);
  d.bullet = n.flag("bullet", d.bullet);
  // the entity at the item's pose, its kinematic path first (a path drives a kinematic body)
  const EntityId e = make_entity(n, w);
  if (n.has("kinematic") && d.type != BodyType::Kinematic)
    n.at("kinematic").fail("a path drives only a \"kinematic\" body (this one is \"" +
                           std::string(to_string(d.type)) + "\")");
  read_common(n, w, e);
  w.add_rigid_body(e, d);
}

}  // namespace pba::scene_detail
