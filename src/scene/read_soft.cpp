// The scene reader's soft-body module (docs/scene-format.md): one item of "soft_bodies".
#include <string>
#include <utility>

#include "json_node.h"
#include "pba/soft.h"

namespace pba::scene_detail {

namespace {

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

// A field of a builder's definition and the JSON key (and the part of it) it is read from.
struct FieldKey {
  const char* field;          // "RopeDef.mass": how the builder names it
  const char* key;            // "mass"
  const char* sub = nullptr;  // "JellyDef.nx" is "cells" item "0", "...linear_drag" "drag" "linear"
};

// The settings every type reads under their own names (the builders validate them as
// "SoftBodyDef.<field>"; the reader's own checks refuse most values first, not all: a
// drag beyond a float; a thickness past what one substep's push keeps finite is refused at
// the step, which knows the substep).
constexpr FieldKey kSettingsKeys[] = {
    {"SoftBodyDef.substeps", "substeps"},
    {"SoftBodyDef.iterations", "iterations"},
    {"SoftBodyDef.stretch_compliance", "stretch_compliance"},
    {"SoftBodyDef.shear_compliance", "shear_compliance"},
    {"SoftBodyDef.bend_compliance", "bend_compliance"},
    {"SoftBodyDef.volume_compliance", "volume_compliance"},
    {"SoftBodyDef.stretch_stiffness", "stretch_stiffness"},
    {"SoftBodyDef.shear_stiffness", "shear_stiffness"},
    {"SoftBodyDef.bend_stiffness", "bend_stiffness"},
    {"SoftBodyDef.volume_stiffness", "volume_stiffness"},
    {"SoftBodyDef.spring_damping", "spring_damping"},
    {"SoftBodyDef.tear_strain", "tear_strain"},
    {"SoftBodyDef.thickness", "thickness"},
    {"SoftBodyDef.friction", "friction"},
    {"SoftBodyDef.damping", "damping"},
    {"SoftBodyDef.forces.linear_drag", "drag", "linear"},
    {"SoftBodyDef.forces.quadratic_drag", "drag", "quadratic"},
};

// Rethrows a builder's Error "<Def>.<field>...: what" under the JSON path of the key that
// field was read from, "<file>: /soft_bodies/i/<key>: what" (a field within it, such as
// "RopeDef.constraints[0].rest_length", keeps the builder's whole message after the path);
// a message no field speaks for (a particle beyond a float, set by several fields, which
// it names) goes under the item's path.
[[noreturn]] void fail_by_field(const Node& n, const Error& e, std::initializer_list<FieldKey> fields) {
  const std::string m = e.what();
  const auto rethrow = [&](const FieldKey& f) {
    const std::string field = f.field;
    if (m.rfind(field, 0) != 0 || m.size() == field.size()) return;
    const std::string where = n.where(f.key) + (f.sub ? "/" + std::string(f.sub) : "");
    const char next = m[field.size()];
    if (next == ':' && m.compare(field.size(), 2, ": ") == 0) throw Error(where + m.substr(field.size()));
    if (next == ' ') throw Error(where + ":" + m.substr(field.size()));
    if (next == '.' || next == '[') throw Error(where + ": " + m);
  };
  for (const FieldKey& f : fields) rethrow(f);
  for (const FieldKey& f : kSettingsKeys) rethrow(f);
  throw Error(n.where() + ": " + m);
}

// build(), a builder's call, with its Error put under the JSON path of the field it names
template <class Build>
SoftBody build_by_field(const Node& n, std::initializer_list<FieldKey> fields, Build build) {
  try {
    return build();
  } catch (const Error& e) {
    fail_by_field(n, e, fields);
  }
}

// The fields one solver takes and the other ignores: given for the other solver they are
// refused by path, with the field that solver takes instead (they used to be read and
// dropped without a word).
void refuse_other_solvers_fields(const Node& n, SoftSolver solver, bool spring) {
  const bool xpbd = solver == SoftSolver::Xpbd;
  // the solver's single field: an integrator (mass-spring), iterations (XPBD)
  const char* single = xpbd ? "integrator" : "iterations";
  if (n.has(single))
    n.at(single).fail(xpbd ? "an integrator is the mass-spring solver's (\"solver\": \"mass-spring\"); the XPBD "
                             "solver projects constraints in \"substeps\" of \"iterations\" sweeps and takes none"
                           : "constraint iterations are the XPBD solver's; the mass-spring solver integrates in "
                             "\"substeps\" with its \"integrator\"");
  // each kind's stiffness (mass-spring, N/m) or compliance (XPBD, m/N), its inverse
  const std::string mine = xpbd ? "_compliance" : "_stiffness", other = xpbd ? "_stiffness" : "_compliance";
  // (a spring's stretch under either solver is its "stiffness", N/m)
  for (const std::string kind : {"stretch", "shear", "bend", "volume"})
    if (const std::string key = kind + other; n.has(key.c_str()))
      n.at(key.c_str())
          .fail(std::string(xpbd ? "a stiffness (N/m) is the mass-spring solver's (\"solver\": \"mass-spring\")"
                                 : "a compliance (m/N) is the XPBD solver's (\"solver\": \"xpbd\")") +
                "; the " + (xpbd ? "XPBD" : "mass-spring") + " solver takes " +
                (spring && kind == "stretch" ? std::string("a spring's \"stiffness\" (N/m)")
                                             : "\"" + kind + mine + "\", its inverse (" + (xpbd ? "m/N" : "N/m") + ")"));
}

}  // namespace

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
  SoftBodyDef d;
  if (type == Type::Jelly) {
    const JellyMaterial material = read_jelly_material(n);
    try {
      d = jelly_settings(j, material, w.stepper().settings().fixed_dt);
    } catch (const Error& e) {
      // a material field alone (a damping time whose c = tau k overflows): its path under
      // "material"; size, cells and material together (the message names them): the item
      fail_by_field(n, e,
                    {{"JellyMaterial.young", "material", "young"},
                     {"JellyMaterial.poisson", "material", "poisson"},
                     {"JellyMaterial.damping_time", "material", "damping_time"}});
    }
  }
  d.forces.gravity = w.gravity();
  d.forces.wind = w.particles().forces().wind;
  d.solver = n.choice<SoftSolver>("solver", {{"xpbd", SoftSolver::Xpbd}, {"mass-spring", SoftSolver::MassSpring}},
                                  d.solver);
  refuse_other_solvers_fields(n, d.solver, type == Type::Spring);
  // a spring's stiffness sets its compliance (1 / k)
  if (type == Type::Spring && n.has("stretch_compliance"))
    n.at("stretch_compliance").fail("a spring's compliance is 1 / \"stiffness\" (N/m): give its stiffness");
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
      body = build_by_field(n,
                            {{"SpringDef.a", "a"}, {"SpringDef.b", "b"}, {"SpringDef.velocity_b", "velocity_b"},
                             {"SpringDef.mass", "mass"}, {"SpringDef.stiffness", "stiffness"},
                             {"SpringDef.damping", "spring_damping"}, {"SpringDef.rest_length", "rest_length"}},
                            [&] { return SoftBody::spring(sp, d); });
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
      body = build_by_field(n,
                            {{"RopeDef.from", "from"}, {"RopeDef.to", "to"}, {"RopeDef.segments", "segments"},
                             {"RopeDef.mass", "mass"}},
                            [&] { return SoftBody::rope(r, d); });
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
      body = build_by_field(n,
                            {{"ClothDef.origin", "origin"}, {"ClothDef.edge_u", "edge_u"},
                             {"ClothDef.edge_v", "edge_v"}, {"ClothDef.nx", "nx"}, {"ClothDef.ny", "ny"},
                             {"ClothDef.mass", "mass"}},
                            [&] { return SoftBody::cloth_grid(c, d); });
      break;
    }
    case Type::Jelly: {
      body = build_by_field(n,
                            {{"JellyDef.center", "center"}, {"JellyDef.size.x", "size", "0"},
                             {"JellyDef.size.y", "size", "1"}, {"JellyDef.size.z", "size", "2"}, {"JellyDef.size", "size"},
                             {"JellyDef.rotation", "rotation"}, {"JellyDef.nx", "cells", "0"},
                             {"JellyDef.ny", "cells", "1"}, {"JellyDef.nz", "cells", "2"}, {"JellyDef.mass", "mass"},
                             {"JellyDef.velocity", "velocity"}},
                            [&] { return SoftBody::jelly_box(j, d); });
      break;
    }
  }
  const EntityId e = w.create_entity({.name = n.entity_name()});
  soft_system(w).add(w, e, std::move(body));
}

}  // namespace pba::scene_detail
