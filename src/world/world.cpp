// The entity-component world: entities, component wiring, kinematic paths, constraints
// and the fixed phase order of a tick.
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>

#include "pba/collide/narrow_phase.h"
#include "pba/world.h"

#include "collide/query_internal.h"
#include "core/squarable.h"

namespace pba {

namespace {
// the entity whose body `id` is, or null: by slot, while the entity holds this very handle (a
// body destroyed in rigid() directly leaves its slot's owner behind, and the next body made
// there, in rigid() too, became the entity's: its owner, and the pose each tick wrote into it)
template <class Records>
EntityId owner_by_slot(const std::vector<EntityId>& owners, const Records& records, RigidBodyId id) {
  if (id.index >= owners.size()) return EntityId{};
  const EntityId e = owners[id.index];
  return !e.is_null() && records[e.index].body == id ? e : EntityId{};
}

// the rigid settings, validated with the WorldDef's field names
RigidSystemDef validated_rigid(const RigidSystemDef& d) {
  require_count(static_cast<long long>(d.capacity), 0, 1LL << 26, "WorldDef.rigid.capacity");
  d.contacts.validate("WorldDef.rigid.contacts");
  return d;
}

// true when two collider definitions make the same body (shape fields and material)
bool same_collider(const ColliderDef& a, const ColliderDef& b) {
  const ColliderShape &x = a.shape, &y = b.shape;
  return a.sensor == b.sensor && x.type == y.type && x.normal == y.normal && x.offset == y.offset &&
         x.radius == y.radius && x.half_extents == y.half_extents && x.half_height == y.half_height &&
         x.hull == y.hull && x.mesh == y.mesh && x.compound == y.compound &&
         a.material.restitution == b.material.restitution && a.material.friction == b.material.friction;
}

bool same_pose(const Pose& a, const Pose& b) { return a.position == b.position && a.rotation == b.rotation; }

// true when a sensor's shape `a` at `pa` and a body's shape `b` at `pb` overlap or touch:
// compounds by their children, meshes by their triangles against a convex shape
// (collide_mesh), the rest by collide(); the pairs with no narrow phase (plane against plane,
// a mesh against a plane or a mesh) never count. Never allocates.
bool sensor_overlaps(const ColliderShape& a, const Pose& pa, const ColliderShape& b, const Pose& pb) {
  if (a.type == ShapeType::Compound) {
    for (const CompoundChild& c : a.compound->children)
      if (sensor_overlaps(c.shape, compose(pa, c.pose), b, pb)) return true;
    return false;
  }
  if (b.type == ShapeType::Compound) {
    for (const CompoundChild& c : b.compound->children)
      if (sensor_overlaps(a, pa, c.shape, compose(pb, c.pose))) return true;
    return false;
  }
  const NarrowPhaseSettings touching{.speculative_margin = 0};
  auto deep = [](const Manifold& m) {
    for (int p = 0; p < m.count; ++p)
      if (m.points[p].depth >= 0) return true;
    return false;
  };
  if (a.type == ShapeType::Mesh || b.type == ShapeType::Mesh) {
    const bool a_mesh = a.type == ShapeType::Mesh;
    const ColliderShape& other = a_mesh ? b : a;
    if (!other.is_convex()) return false;
    std::array<Manifold, 8> out;
    const int n = collide_mesh(other, a_mesh ? pb : pa, a_mesh ? a : b, a_mesh ? pa : pb, out, touching);
    for (int i = 0; i < n; ++i)
      if (deep(out[static_cast<std::size_t>(i)])) return true;
    return false;
  }
  if (a.type == ShapeType::Plane && b.type == ShapeType::Plane) return false;
  return deep(collide(a, pa, b, pb, touching));
}

void require_pose(const Pose& p, std::string_view where) {
  if (!is_finite(p.position)) require_finite(p.position, field_path(where, "position"));
  const Quat& q = p.rotation;
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!std::isfinite(n) || std::abs(n - 1) > 1e-6)
    throw Error(field_path(where, "rotation") + ": must be a finite unit quaternion");
}

// Throws unless `placed`, the position of a component placed at `local` in the entity frame
// (`entity` * local), fits a float: both are finite, but their sum may not fit (or even
// overflow a double to inf, which require_float read as "must be finite"), so the message
// names the two terms ("the entity's position (x, y, z) + its rotation * <local_name> (x, y, z)").
void require_placed_float(const Pose& entity, const Vec3& local, const Vec3& placed, std::string_view local_name,
                          std::string_view where) {
  if (fits_float(placed) || !is_finite(local)) return;  // (a non-finite local is the definition's check)
  require_float_sum(placed,
                    "the entity's position " + format_vec3(entity.position) + " + its rotation * " +
                        std::string(local_name) + " " + format_vec3(entity.rotation * local),
                    where);
}

// |v| whatever its scale: glm::length (the same bits) while its squares are normal doubles;
// beyond (a component past ~1.3e154 overflowed them to an infinite length, one below ~1e-154
// underflowed them to 0), by the largest |component| first
double scaled_length(const Vec3& v) {
  const double l = glm::length(v);
  if (l > 1e-140 && l < 1e140) return l;
  const double m = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
  if (!(m > 0) || !std::isfinite(m)) return m;
  return m * glm::length(v / m);
}

// v / |v| (v non-zero and finite): glm::normalize's bits while its squares are normal doubles
Vec3 scaled_unit(const Vec3& v) {
  const double l = glm::length(v);
  return l > 1e-140 && l < 1e140 ? glm::normalize(v) : v / scaled_length(v);
}

// whether any collider (World's ColliderEntry) has a live stand-in body in `rigid`
template <class ColliderEntries>
bool any_stand_in(const ColliderEntries& colliders, const RigidBodySystem& rigid) {
  for (const auto& c : colliders)
    if (rigid.valid(c.mirror)) return true;
  return false;
}

double waypoint_length(const KinematicDef& d) {
  double len = 0;
  for (std::size_t i = 1; i < d.waypoints.size(); ++i) len += scaled_length(d.waypoints[i] - d.waypoints[i - 1]);
  if (d.loop && d.waypoints.size() > 1) len += scaled_length(d.waypoints.front() - d.waypoints.back());
  return len;
}

}  // namespace

void KinematicDef::validate(std::string_view where) const {
  if (!is_finite(velocity)) require_finite(velocity, field_path(where, "velocity"));
  if (!is_finite(spin)) require_finite(spin, field_path(where, "spin"));
  // finite components whose length overflows a double: the spin's rate (and, below, the
  // circle's axis) is that length, and the path's poses turned NaN
  if (!std::isfinite(scaled_length(spin)))
    throw Error(field_path(where, "spin") + ": its length overflows a double, got " + format_vec3(spin));
  switch (path) {
    case PathType::Linear:
    case PathType::Motor: break;
    case PathType::Thruster: if (!is_finite(thrust)) require_finite(thrust, field_path(where, "thrust")); break;
    case PathType::Circular:
      if (!is_finite(center)) require_finite(center, field_path(where, "center"));
      if (!is_finite(axis)) require_finite(axis, field_path(where, "axis"));
      if (scaled_length(axis) == 0) throw Error(field_path(where, "axis") + ": must be non-zero, got (0, 0, 0)");
      if (!std::isfinite(scaled_length(axis)))
        throw Error(field_path(where, "axis") + ": its length overflows a double, got " + format_vec3(axis));
      if (!(std::isfinite(radius) && (radius) > 0)) require_positive(radius, field_path(where, "radius"));
      if (!std::isfinite(angular_speed)) require_finite(angular_speed, field_path(where, "angular_speed"));
      if (!std::isfinite(phase)) require_finite(phase, field_path(where, "phase"));
      // the circle's points (within radius of center on each axis) and its speed must be
      // doubles: each finite input, their sum or product overflowed to inf, and the poses to NaN
      if (!std::isfinite(std::max({std::abs(center.x), std::abs(center.y), std::abs(center.z)}) + radius))
        throw Error(field_path(where, "radius") + ": a circle of radius " + format_value(radius) + " about center " +
                    format_vec3(center) + " reaches beyond a double's range");
      if (!std::isfinite(radius * angular_speed))
        throw Error(field_path(where, "angular_speed") + ": radius " + format_value(radius) + " m times angular_speed " +
                    format_value(angular_speed) + " rad/s, the path's speed, overflows a double");
      break;
    case PathType::Waypoints:
      if (waypoints.size() < 2)
        throw Error(field_path(where, "waypoints") + ": needs at least 2 points, got " +
                    std::to_string(waypoints.size()));
      for (std::size_t i = 0; i < waypoints.size(); ++i)
        if (!is_finite(waypoints[i]))
          require_finite(waypoints[i], field_path(where, "waypoints[" + std::to_string(i) + "]"));
      // a segment whose length overflows a double (points 1e308 either side of the origin)
      // gave NaN poses along it
      for (std::size_t i = 0; i < waypoints.size(); ++i) {
        const std::size_t j = i + 1 == waypoints.size() ? 0 : i + 1;
        if ((j == 0 && !loop) || std::isfinite(scaled_length(waypoints[j] - waypoints[i]))) continue;
        throw Error(field_path(where, "waypoints") + ": points " + std::to_string(i) + " " +
                    format_vec3(waypoints[i]) + " and " + std::to_string(j) + " " + format_vec3(waypoints[j]) +
                    " are farther apart than a double holds");
      }
      if (!std::isfinite(waypoint_length(*this)))
        throw Error(field_path(where, "waypoints") + ": the path's length overflows a double");
      if (!(std::isfinite(speed) && (speed) > 0)) require_positive(speed, field_path(where, "speed"));
      if (waypoint_length(*this) == 0) throw Error(field_path(where, "waypoints") + ": all points coincide");
      break;
  }
}

// closed-form paths: the pose and velocity at time t since the start
Pose kinematic_pose(const KinematicDef& d, const Pose& start, double t, Vec3* velocity, double length) {
  Pose p = start;
  Vec3 v(0);
  switch (d.path) {
    case PathType::Linear:
      p.position = start.position + d.velocity * t;
      v = d.velocity;
      break;
    case PathType::Motor: break;
    case PathType::Thruster:
      p.position = start.position + d.velocity * t + d.thrust * (0.5 * t * t);
      v = d.velocity + d.thrust * t;
      break;
    case PathType::Circular: {
      // a basis (u, w) of the circle's plane
      const Vec3 a = scaled_unit(d.axis);
      const Vec3 helper = std::abs(a.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
      const Vec3 u = glm::normalize(glm::cross(a, helper));
      const Vec3 w = glm::cross(a, u);
      const double th = d.phase + d.angular_speed * t;
      p.position = d.center + d.radius * (std::cos(th) * u + std::sin(th) * w);
      v = d.radius * d.angular_speed * (-std::sin(th) * u + std::cos(th) * w);
      break;
    }
    case PathType::Waypoints: {
      // distance along the path, wrapped (loop) or clamped (stop at the end)
      const double total = length > 0 ? length : waypoint_length(d);
      double s = d.speed * t;
      const std::size_t n = d.waypoints.size();
      const std::size_t segments = d.loop ? n : n - 1;
      if (d.loop) {
        s = std::fmod(s, total);
        if (s < 0) s += total;
      } else if (s >= total) {
        p.position = d.waypoints.back();
        break;
      }
      for (std::size_t i = 0; i < segments; ++i) {
        const Vec3 a = d.waypoints[i], b = d.waypoints[(i + 1) % n];
        const double len = scaled_length(b - a);
        if (s <= len || i + 1 == segments) {
          const double f = len > 0 ? std::min(s / len, 1.0) : 0.0;
          p.position = a + (b - a) * f;
          v = len > 0 ? (b - a) / len * d.speed : Vec3(0);
          break;
        }
        s -= len;
      }
      break;
    }
  }
  // spin about world axes: q(t) = exp(spin t) q0
  const double w = scaled_length(d.spin);
  if (w > 0) p.rotation = glm::normalize(glm::angleAxis(w * t, d.spin / w) * start.rotation);
  if (velocity) *velocity = v;
  return p;
}

// ---------------------------------------------------------------------------------------

namespace {

// finite and within a float's range: the particles and soft bodies hold gravity as floats,
// and a larger one accepted here stopped the world for good at the next tick, named as
// the particle system's ("ParticleSystem.forces.gravity: must fit a float")
void require_gravity(const Vec3& g, std::string_view where) {
  require_float(g, where);
}

}  // namespace

World::World(const WorldDef& def)
    : settings_(def.stepper),
      gravity_((require_gravity(def.gravity, "WorldDef.gravity"), def.gravity)),
      stepper_((def.stepper.validate("WorldDef.stepper"), def.stepper)),
      particles_(def.particles),
      rigid_(validated_rigid(def.rigid)) {
  particles_.forces().gravity = gravity_;
  // the particle entities' touch events read the colliders each particle met
  particles_.set_record_contacts(true);
}

std::string_view to_string(WorldStage s) {
  switch (s) {
    case WorldStage::Kinematic: return "kinematic";
    case WorldStage::Collide: return "collide";
    case WorldStage::Rigid: return "rigid";
    case WorldStage::Particles: return "particles";
    case WorldStage::Soft: return "soft";
    case WorldStage::Constraints: return "constraints";
    case WorldStage::Post: return "post";
  }
  return "unknown";
}

void World::set_gravity(const Vec3& g) {
  require_gravity(g, "World::set_gravity(g)");
  gravity_ = g;
}

World::~World() = default;
World::World(World&&) noexcept = default;
// a self-move keeps the world: member by member, each vector would be emptied (a vector
// moved into itself gives up its elements) under the counts and handles that still name them
World& World::operator=(World&& o) noexcept {
  if (this != &o) std::destroy_at(this), std::construct_at(this, std::move(o));
  return *this;
}

World::EntityRecord& World::record(EntityId e, std::string_view where) {
  if (!entities_.valid(e)) entities_.require(e, std::string(where) + ": entity");
  return records_[e.index];
}

const World::EntityRecord& World::record(EntityId e, std::string_view where) const {
  if (!entities_.valid(e)) entities_.require(e, std::string(where) + ": entity");
  return records_[e.index];
}

std::string World::describe(EntityId e) const {
  const std::string& n = records_[e.index].name;
  return "entity " + std::to_string(e.index) + (n.empty() ? "" : " '" + n + "'");
}

EntityId World::create_entity(const EntityDef& def) {
  require_pose(def.pose, "EntityDef" + (def.name.empty() ? std::string() : " '" + def.name + "'"));
  const EntityId e = entities_.create();
  if (records_.size() <= e.index) records_.resize(e.index + 1);
  records_[e.index] = EntityRecord{};
  records_[e.index].name = def.name;
  records_[e.index].pose = def.pose;
  return e;
}

template <class Entry>
void World::remove_dense(std::vector<Entry>& v, std::uint32_t EntityRecord::*member, std::uint32_t i) {
  // swap-remove and re-point the moved entry's entity
  if (i + 1 != v.size()) {
    v[i] = std::move(v.back());
    records_[v[i].owner.index].*member = i;
  }
  v.pop_back();
}

void World::destroy_entity(EntityId e) {
  EntityRecord& r = record(e, "World::destroy_entity");
  collision_stale_ = true;
  // components first, in a fixed order
  for (auto& s : systems_) s->on_destroy(e);
  if (particles_.valid(r.particle)) particles_.destroy(r.particle);
  if (!r.emitter.is_null()) particles_.remove_emitter(r.emitter);
  // (a body destroyed in rigid() directly is still counted in entity_bodies_: see there)
  if (!r.body.is_null()) --entity_bodies_;
  if (rigid_.valid(r.body)) {
    rigid_.destroy(r.body);
    body_owner_[r.body.index] = EntityId{};
    changed_between_ticks();
  }
  if (r.collider != kNone) {
    const std::uint32_t i = r.collider;
    destroy_mirror(colliders_[i]);
    collider_ids_.pool.destroy(colliders_[i].id, "World::destroy_entity collider");
    remove_dense(colliders_, &EntityRecord::collider, i);
    if (i + 1 != world_colliders_.size()) world_colliders_[i] = world_colliders_.back();
    world_colliders_.pop_back();
  }
  if (r.forcer != kNone) {
    const std::uint32_t i = r.forcer;
    forcer_ids_.pool.destroy(forcers_[i].id, "World::destroy_entity forcer");
    remove_dense(forcers_, &EntityRecord::forcer, i);
    if (i + 1 != world_forcers_.size()) world_forcers_[i] = world_forcers_.back();
    world_forcers_.pop_back();
  }
  if (r.kinematic != kNone) {
    kinematic_ids_.pool.destroy(kinematics_[r.kinematic].id, "World::destroy_entity kinematic");
    remove_dense(kinematics_, &EntityRecord::kinematic, r.kinematic);
  }
  if (r.constraint != kNone) {
    constraint_ids_.pool.destroy(constraints_[r.constraint].id, "World::destroy_entity constraint");
    remove_dense(constraints_, &EntityRecord::constraint, r.constraint);
  }
  // constraints that point at this entity go too
  for (std::size_t i = 0; i < constraints_.size();) {
    if (constraints_[i].def.other == e) {
      records_[constraints_[i].owner.index].constraint = kNone;
      constraint_ids_.pool.destroy(constraints_[i].id, "World::destroy_entity constraint");
      remove_dense(constraints_, &EntityRecord::constraint, static_cast<std::uint32_t>(i));
    } else {
      ++i;
    }
  }
  forget_pairs(e);
  records_[e.index] = EntityRecord{};
  entities_.destroy(e, "World::destroy_entity");
}

EntityId World::find(std::string_view name) const {
  for (std::uint32_t i = 0; i < records_.size(); ++i) {
    const EntityId e{i, entities_.slots() > i ? entities_.generation(i) : 0};
    if (entities_.valid(e) && records_[i].name == name) return e;
  }
  return EntityId{};
}

const std::string& World::name(EntityId e) const { return record(e, "World::name").name; }

Pose World::pose(EntityId e) const {
  const EntityRecord& r = record(e, "World::pose");
  if (particles_.valid(r.particle)) return Pose{particles_.position(r.particle), r.pose.rotation};
  if (rigid_.valid(r.body) && r.kinematic == kNone) return rigid_.pose(r.body);
  return r.pose;
}

Vec3 World::velocity(EntityId e) const {
  const EntityRecord& r = record(e, "World::velocity");
  if (particles_.valid(r.particle)) return particles_.velocity(r.particle);
  if (rigid_.valid(r.body) && r.kinematic == kNone) return rigid_.velocity_at(r.body, rigid_.pose(r.body).position);
  return r.velocity;
}

void World::set_pose(EntityId e, const Pose& pose) {
  require_pose(pose, "World::set_pose");
  EntityRecord& r = record(e, "World::set_pose");
  // a rigid body and a particle hold their positions as floats: refused before anything
  // moves (the body, and the particle system naming itself, refused it after the entity had
  // moved)
  if (rigid_.valid(r.body) || particles_.valid(r.particle)) require_float(pose.position, "World::set_pose.position");
  r.pose = pose;
  if (particles_.valid(r.particle)) particles_.set_position(particles_.index_of(r.particle), pose.position);
  // a body jumps there (and wakes with its island)
  if (rigid_.valid(r.body)) {
    rigid_.set_pose(r.body, pose);
    changed_between_ticks();
  }
  // a teleported collider does not sweep
  if (r.collider != kNone) {
    world_colliders_[r.collider].begin = world_colliders_[r.collider].end = pose;
    collision_stale_ = true;
  }
  if (r.kinematic != kNone) {
    // restart the path from here
    kinematics_[r.kinematic].start = time_;
    kinematics_[r.kinematic].start_pose = pose;
  }
}

ParticleId World::add_particle(EntityId e, const ParticleDef& def) {
  EntityRecord& r = record(e, "World::add_particle");
  if (!r.particle.is_null() && particles_.valid(r.particle))
    throw Error("World::add_particle: " + describe(e) + " already has a particle");
  // the body and the particle would both simulate the entity, each writing its pose
  if (rigid_.valid(r.body))
    throw Error(
        "World::add_particle: " + describe(e) +
        " has a rigid body, which moves it; a particle would move it too (give the particle an entity of its own)");
  ParticleDef d = def;
  d.position = r.pose.position + r.pose.rotation * def.position;
  require_placed_float(r.pose, def.position, d.position, "position", "particle of " + describe(e) + ".position");
  r.particle = particles_.create(d, "particle of " + describe(e));
  ++particle_entities_added_;
  reserve_touch_sets();
  return r.particle;
}

// A plane or mesh collider moved by a Kinematic (not a sensor, which has no stand-in): its
// stand-in among the rigid bodies is static and jumps along the path each tick (a kinematic
// body needs a volume), so it neither carries nor pushes a rigid body with its speed (a crate
// on a mesh floor moving at 1 m/s lagged 2 m after 2 s; a lift pushed crates out of it with no
// speed), and each jump woke every sleeping body. Refused beside a dynamic rigid body, in
// whichever order they are added: add_collider, add_kinematic, add_rigid_body (and the tick,
// for a collider or body changed in place).
namespace {
bool moving_floor_shape(const ColliderDef& c) {
  return !c.sensor && (c.shape.type == ShapeType::Plane || c.shape.type == ShapeType::Mesh);
}

// the first dynamic rigid body (null if none)
RigidBodyId first_dynamic_body(const RigidBodySystem& rigid) {
  for (std::size_t k = 0; k < rigid.size(); ++k)
    if (rigid.type(rigid.id_at(k)) == BodyType::Dynamic) return rigid.id_at(k);
  return {};
}

// the first plane or mesh collider on a Kinematic path (colliders.size() if none)
template <class Colliders, class Records, class Index>
std::size_t first_moving_floor(const Colliders& colliders, const Records& records, Index none) {
  for (std::size_t i = 0; i < colliders.size(); ++i)
    if (records[colliders[i].owner.index].kinematic != none && moving_floor_shape(colliders[i].def)) return i;
  return colliders.size();
}

[[noreturn]] void refuse_moving_floor(std::string_view where, const std::string& floor, ShapeType type,
                                      const std::string& body) {
  throw Error(std::string(where) + ": " + floor + " has a " + std::string(to_string(type)) +
              " collider on a Kinematic path, which cannot carry or push rigid bodies (it jumps along the path "
              "with no speed), beside " + body +
              ": give the moving floor a box or hull collider (a plane or mesh on a path moves particles, cloth "
              "and jelly only)");
}

// the dynamic body's words for refuse_moving_floor (describe: the World's words for its entity)
template <class Records, class Describe>
std::string dynamic_body_words(const std::vector<EntityId>& body_owner, const Records& records, RigidBodyId b,
                               Describe describe) {
  const EntityId owner = owner_by_slot(body_owner, records, b);
  return owner.is_null() ? "dynamic rigid body " + std::to_string(b.index) + " (made in rigid() directly)"
                         : "the dynamic rigid body of " + describe(owner);
}
}  // namespace

ColliderId World::add_collider(EntityId e, const ColliderDef& def) {
  EntityRecord& r = record(e, "World::add_collider");
  if (r.collider != kNone) throw Error("World::add_collider: " + describe(e) + " already has a collider");
  // validate as a world collider at the entity's pose
  Collider c;
  c.shape = def.shape;
  c.material = def.material;
  c.begin = c.end = r.pose;
  c.validate("collider of " + describe(e));
  if (r.kinematic != kNone && moving_floor_shape(def))
    if (const RigidBodyId b = first_dynamic_body(rigid_); !b.is_null())
      refuse_moving_floor("World::add_collider", describe(e), def.shape.type,
                          dynamic_body_words(body_owner_, records_, b, [&](EntityId o) { return describe(o); }));
  if (def.shape.type == ShapeType::Plane) c.shape.normal = glm::normalize(def.shape.normal);
  r.collider = static_cast<std::uint32_t>(colliders_.size());
  colliders_.push_back({e, def, collider_ids_.create(e)});
  colliders_.back().def.shape.normal = c.shape.normal;
  world_colliders_.push_back(c);
  collision_stale_ = true;
  return colliders_.back().id;
}

ForcerId World::add_forcer(EntityId e, const Forcer& def) {
  EntityRecord& r = record(e, "World::add_forcer");
  if (r.forcer != kNone) throw Error("World::add_forcer: " + describe(e) + " already has a forcer");
  def.validate("forcer of " + describe(e));
  // and as the world forcer it becomes at the entity's pose (an entity far out can put a
  // forcer beyond what the float kernels hold)
  Forcer w = def;
  w.pose = compose(r.pose, def.pose);
  require_placed_float(r.pose, def.pose.position, w.pose.position, "pose.position",
                       "forcer of " + describe(e) + " at the entity's pose: position");
  w.validate("forcer of " + describe(e) + " at the entity's pose");
  r.forcer = static_cast<std::uint32_t>(forcers_.size());
  forcers_.push_back({e, def, forcer_ids_.create(e)});
  world_forcers_.push_back(w);
  return forcers_.back().id;
}

EmitterId World::add_emitter(EntityId e, const EmitterDef& def) {
  EntityRecord& r = record(e, "World::add_emitter");
  if (!r.emitter.is_null()) throw Error("World::add_emitter: " + describe(e) + " already has an emitter");
  EmitterDef d = def;
  d.pose = compose(r.pose, def.pose);
  // the particles it emits are floats: its pose in the world must fit one
  if (!fits_float(d.pose.position))
    require_placed_float(r.pose, def.pose.position, d.pose.position, "pose.position",
                         "emitter of " + describe(e) + " at the entity's pose: position");
  r.emitter = particles_.add_emitter(d, "emitter of " + describe(e));
  r.emitter_local = def.pose;
  return r.emitter;
}

KinematicId World::add_kinematic(EntityId e, const KinematicDef& def) {
  EntityRecord& r = record(e, "World::add_kinematic");
  if (r.kinematic != kNone) throw Error("World::add_kinematic: " + describe(e) + " already has a kinematic");
  if (rigid_.valid(r.body) && rigid_.type(r.body) != BodyType::Kinematic)
    throw Error("World::add_kinematic: " + describe(e) + " has a " + std::string(to_string(rigid_.type(r.body))) +
                " rigid body, which a Kinematic cannot drive (only a kinematic body follows a path)");
  // nor one with velocities of its own: the kinematic stage sets them from the path every
  // tick, so they were dropped silently (add_rigid_body refuses them on an entity with a
  // Kinematic, in the other order of adding)
  if (rigid_.valid(r.body)) {
    const Vec3 v = rigid_.linear_velocity(r.body), w = rigid_.angular_velocity(r.body);
    if (v != Vec3(0) || w != Vec3(0))
      throw Error("World::add_kinematic: " + describe(e) + " has a kinematic rigid body moving at " + format_vec3(v) +
                  " m/s and " + format_vec3(w) +
                  " rad/s, and a body on a kinematic path moves as the path says (give the velocity in the "
                  "KinematicDef, or stop the body first: rigid().set_velocity(body, {0, 0, 0}, {0, 0, 0}))");
  }
  def.validate("kinematic of " + describe(e));
  if (r.collider != kNone && moving_floor_shape(colliders_[r.collider].def))
    if (const RigidBodyId b = first_dynamic_body(rigid_); !b.is_null())
      refuse_moving_floor("World::add_kinematic", describe(e), colliders_[r.collider].def.shape.type,
                          dynamic_body_words(body_owner_, records_, b, [&](EntityId o) { return describe(o); }));
  r.kinematic = static_cast<std::uint32_t>(kinematics_.size());
  KinematicEntry k{
      e, kinematic_ids_.create(e), def, time_, r.pose, def.path == PathType::Waypoints ? waypoint_length(def) : 0.0};
  // waypoint and circular paths start on the path
  Vec3 v;
  const Pose p = kinematic_pose(def, r.pose, 0, &v, k.length);
  r.pose = p;
  r.velocity = v;
  k.start_pose.rotation = r.pose.rotation;
  // a collider jumps to the path's start instead of sweeping there
  if (r.collider != kNone) {
    world_colliders_[r.collider].begin = world_colliders_[r.collider].end = r.pose;
    collision_stale_ = true;
  }
  kinematics_.push_back(std::move(k));
  // a kinematic body starts on the path too
  if (rigid_.valid(r.body)) {
    rigid_.set_pose(r.body, r.pose);
    changed_between_ticks();
  }
  return kinematics_.back().id;
}

ConstraintId World::add_constraint(EntityId e, const ConstraintDef& def) {
  EntityRecord& r = record(e, "World::add_constraint");
  if (r.constraint != kNone) throw Error("World::add_constraint: " + describe(e) + " already has a constraint");
  const std::string where = "constraint of " + describe(e);
  if (!particles_.valid(r.particle)) throw Error(where + ": the entity has no particle");
  const EntityRecord& o = record(def.other, where + ".other");
  if (!particles_.valid(o.particle)) throw Error(where + ".other: " + describe(def.other) + " has no particle");
  if (def.other == e) throw Error(where + ".other: must be another entity");
  require_in_range(def.stiffness, 0, 1, where + ".stiffness");
  ConstraintDef d = def;
  if (!(d.rest_length >= 0))
    d.rest_length = glm::length(particles_.position(r.particle) - particles_.position(o.particle));
  require_finite(d.rest_length, where + ".rest_length");
  r.constraint = static_cast<std::uint32_t>(constraints_.size());
  constraints_.push_back({e, d, constraint_ids_.create(e)});
  return constraints_.back().id;
}

RigidBodyId World::add_rigid_body(EntityId e, const RigidBodyDef& def) {
  EntityRecord& r = record(e, "World::add_rigid_body");
  if (rigid_.valid(r.body)) throw Error("World::add_rigid_body: " + describe(e) + " already has a rigid body");
  if (!r.particle.is_null() && particles_.valid(r.particle))
    throw Error("World::add_rigid_body: " + describe(e) +
                " has a particle, which moves it; a body would move it too (give the body an entity of its own)");
  const std::string where = "rigid body of " + describe(e);
  // the definition as given (its pose is relative to the entity), then in the world
  def.validate(where);
  if (r.kinematic != kNone && def.type != BodyType::Kinematic)
    throw Error(field_path(where, "type") + ": the entity has a Kinematic, which drives only a kinematic body, got " +
                std::string(to_string(def.type)));
  // nor would its own velocities: the kinematic stage sets them from the path every tick (the
  // scene reader refuses them the same way, src/scene/read_rigid.cpp)
  if (r.kinematic != kNone)
    for (const auto& [field, v] : {std::pair<const char*, Vec3>{"linear_velocity", def.linear_velocity},
                                   std::pair<const char*, Vec3>{"angular_velocity", def.angular_velocity}})
      if (v != Vec3(0))
        throw Error(field_path(where, field) + ": the entity has a Kinematic, and a body on a kinematic path moves as "
                    "the path says (give the velocity in its KinematicDef), got " + format_vec3(v));
  if (def.type == BodyType::Dynamic)
    if (const std::size_t f = first_moving_floor(colliders_, records_, kNone); f < colliders_.size())
      refuse_moving_floor("World::add_rigid_body", describe(colliders_[f].owner), colliders_[f].def.shape.type,
                          "the dynamic rigid body of " + describe(e));
  RigidBodyDef d = def;
  d.pose = compose(r.pose, def.pose);
  d.pose.rotation = glm::normalize(d.pose.rotation);
  require_placed_float(r.pose, def.pose.position, d.pose.position, "pose.position", field_path(where, "pose.position"));
  if (d.name.empty()) d.name = r.name;
  // (the system appends the body's name to `where`: the entity's, unless the body has its own)
  const RigidBodyId id =
      rigid_.create(d, d.name == r.name && !r.name.empty() ? "rigid body of entity " + std::to_string(e.index) : where);
  if (body_owner_.size() <= id.index) body_owner_.resize(id.index + 1);
  body_owner_[id.index] = e;
  // an entity whose body was destroyed in rigid() directly is counted already
  if (r.body.is_null()) ++entity_bodies_;
  r.body = id;
  reserve_touch_sets();
  // from now on the entity is where its body is (a path's entity stays on its path)
  if (r.kinematic == kNone) r.pose = rigid_.pose(id);
  changed_between_ticks();
  return id;
}

bool World::valid(RigidBodyId id) const {
  return rigid_.valid(id) && !owner_by_slot(body_owner_, records_, id).is_null();
}

RigidBodyId World::rigid_body_id(EntityId e) const {
  const RigidBodyId id = record(e, "World::rigid_body_id").body;
  return rigid_.valid(id) ? id : RigidBodyId{};
}

EntityId World::owner(RigidBodyId id) const {
  // null, stale or never issued, as the rigid bodies' handle table tells them apart
  if (!rigid_.valid(id)) rigid_.require(id, "World::owner(RigidBodyId): rigid body");
  if (!valid(id)) throw Error("World::owner(RigidBodyId): rigid body " + std::to_string(id.index) +
                              " belongs to no entity (it stands for a collider, or was made in rigid() directly)");
  return owner_by_slot(body_owner_, records_, id);
}

namespace {
// the handle of an entity's component at dense index i, or the null handle (i is
// World::kNone, 0xffffffff, when the entity has none)
template <class Entry>
auto component_id(const std::vector<Entry>& v, std::uint32_t i) {
  return i == 0xffffffffu ? decltype(v[0].id){} : v[i].id;
}
}  // namespace

ColliderId World::collider_id(EntityId e) const {
  return component_id(colliders_, record(e, "World::collider_id").collider);
}
ForcerId World::forcer_id(EntityId e) const { return component_id(forcers_, record(e, "World::forcer_id").forcer); }
KinematicId World::kinematic_id(EntityId e) const {
  return component_id(kinematics_, record(e, "World::kinematic_id").kinematic);
}
ConstraintId World::constraint_id(EntityId e) const {
  return component_id(constraints_, record(e, "World::constraint_id").constraint);
}
EntityId World::owner(ColliderId id) const { return collider_ids_.owner_of(id, "World::owner(ColliderId)"); }
EntityId World::owner(ForcerId id) const { return forcer_ids_.owner_of(id, "World::owner(ForcerId)"); }
EntityId World::owner(KinematicId id) const { return kinematic_ids_.owner_of(id, "World::owner(KinematicId)"); }
EntityId World::owner(ConstraintId id) const {
  return constraint_ids_.owner_of(id, "World::owner(ConstraintId)");
}

ParticleId World::particle(EntityId e) const { return record(e, "World::particle").particle; }
EmitterId World::emitter(EntityId e) const { return record(e, "World::emitter").emitter; }

ColliderDef& World::collider(EntityId e) {
  EntityRecord& r = record(e, "World::collider");
  if (r.collider == kNone) throw Error("World::collider: " + describe(e) + " has no collider");
  collision_stale_ = true;  // the caller may change the shape (queries() then shows it)
  return colliders_[r.collider].def;
}

Forcer& World::forcer(EntityId e) {
  EntityRecord& r = record(e, "World::forcer");
  if (r.forcer == kNone) throw Error("World::forcer: " + describe(e) + " has no forcer");
  return forcers_[r.forcer].def;
}

KinematicDef& World::kinematic(EntityId e) {
  EntityRecord& r = record(e, "World::kinematic");
  if (r.kinematic == kNone) throw Error("World::kinematic: " + describe(e) + " has no kinematic");
  return kinematics_[r.kinematic].def;
}

void World::add_system(std::unique_ptr<WorldSystem> system) {
  if (!system) throw Error("World::add_system: null system");
  systems_.push_back(std::move(system));
}

WorldSystem* World::find_system(std::string_view name) {
  for (auto& s : systems_)
    if (s->name() == name) return s.get();
  return nullptr;
}

const WorldSystem* World::find_system(std::string_view name) const {
  for (const auto& s : systems_)
    if (s->name() == name) return s.get();
  return nullptr;
}

// ---------------------------------------------------------------------------------------
// stepping

FrameStats World::advance(double frame_seconds) {
  return stepper_.advance(frame_seconds, [this](double t, double dt) { tick(t, dt); });
}

void World::step() {
  // one nominal frame through the stepper: one tick of fixed_dt for the fixed strategy
  stepper_.single_step([this](double t, double dt) { tick(t, dt); });
}

void World::run_kinematics(double t, double dt) {
  // each path's pose at the end of the tick, in closed form
  // World::kinematic hands out the definitions, changeable between ticks: checked again here,
  // by field and before any path moves (a NaN stopped the world as "left the range of a
  // double", emptied waypoints were read out of bounds), and a path's length recomputed (it
  // went stale). validate allocates only to throw: an empty `where`, named on the way out (its
  // messages are field_path(where, field), "" giving ".field").
  for (KinematicEntry& k : kinematics_) {
    try {
      k.def.validate("");
    } catch (const Error& err) {
      throw Error("kinematic of " + describe(k.owner) + err.what());
    }
    if (k.def.path == PathType::Waypoints) k.length = waypoint_length(k.def);
  }
  for (KinematicEntry& k : kinematics_) {
    EntityRecord& r = records_[k.owner.index];
    Vec3 v;
    const Pose p = kinematic_pose(k.def, k.start_pose, t + dt - k.start, &v, k.length);
    // a path that runs out of the doubles (a linear path at 1e308 m/s) stops the world by name,
    // as a non-finite state does: its entity's pose turned inf or NaN unseen
    if (!is_finite(p.position) || !is_finite(v) || !is_finite(p.rotation)) {
      failure_ = "the kinematic path of " + describe(k.owner) + " left the range of a double in the tick to t = " +
                 format_value(t + dt) + " s (position " + format_vec3(p.position) + ", velocity " + format_vec3(v) +
                 ")";
      throw Error("World::tick: " + failure_);
    }
    r.velocity = v;
    r.angular_velocity = k.def.spin;
    r.pose = p;
    if (particles_.valid(r.particle)) {
      const std::size_t i = particles_.index_of(r.particle);
      particles_.set_position(i, p.position);
      particles_.set_velocity(i, v);
    }
  }
}

void World::sync(double t, double dt) {
  // colliders sweep from last tick's end pose to this tick's
  for (std::size_t i = 0; i < colliders_.size(); ++i) {
    const EntityRecord& r = records_[colliders_[i].owner.index];
    Collider& c = world_colliders_[i];
    c.shape = colliders_[i].def.shape;
    c.material = colliders_[i].def.material;
    c.begin = c.end;
    c.end = r.pose;
    c.velocity = r.velocity;
    c.angular_velocity = r.angular_velocity;
  }
  // the colliders validated now, so a bad one stops the tick before any body moves (their
  // stand-ins included: validated after them, a collider moved beyond a float's range was
  // refused by its stand-in as "rigid body 1 'wall' set_pose position"); the tick's
  // collision world is built in the rigid stage, once the colliders riding on bodies are
  // where their bodies end the tick (built here as well, it was built twice a tick)
  validate_colliders();
  // the colliders' stand-ins among the rigid bodies follow them
  sync_mirrors(t, dt);
  collision_stale_ = true;  // until then (a tick that fails midway leaves queries() to rebuild)
  // forcers and emitters follow their entities
  for (std::size_t i = 0; i < forcers_.size(); ++i) {
    const EntityRecord& r = records_[forcers_[i].owner.index];
    world_forcers_[i] = forcers_[i].def;
    world_forcers_[i].pose = compose(r.pose, forcers_[i].def.pose);
    // an entity moved out of the floats' range takes its forcer with it: refused by name;
    // so is a forcer whose pose was changed between ticks (World::forcer hands out its
    // definition) to a non-finite one, by its own check (require_placed_float takes a
    // non-finite local for the definition's, which add_forcer alone ran)
    if (!fits_float(world_forcers_[i].pose.position) || !is_finite(forcers_[i].def.pose.rotation)) {
      if (!is_finite(forcers_[i].def.pose.position) || !is_finite(forcers_[i].def.pose.rotation))
        forcers_[i].def.validate("forcer of " + describe(forcers_[i].owner));
      require_placed_float(r.pose, forcers_[i].def.pose.position, world_forcers_[i].pose.position, "pose.position",
                           "forcer of " + describe(forcers_[i].owner) + " at the entity's pose: position");
    }
  }
  for (std::size_t i = 0; i < records_.size(); ++i) {
    const EntityRecord& r = records_[i];
    if (r.emitter.is_null()) continue;
    const Pose p = compose(r.pose, r.emitter_local);
    // an entity moved beyond a float's range would emit non-finite particles: refused by name
    if (!fits_float(p.position))
      require_placed_float(r.pose, r.emitter_local.position, p.position, "pose.position",
                           "emitter of entity " + std::to_string(i) + (r.name.empty() ? "" : " '" + r.name + "'") +
                               " at the entity's pose: position");
    particles_.set_emitter_pose(r.emitter, p);
  }
}

// ---------------------------------------------------------------------------------------
// rigid bodies

void World::destroy_mirror(ColliderEntry& c) {
  if (rigid_.valid(c.mirror)) {
    mirror_owner_[c.mirror.index] = EntityId{};
    rigid_.destroy(c.mirror);
  }
  c.mirror = RigidBodyId{};
}

// the entity a body stands for: its own, or the collider's of a stand-in (null for none)
EntityId World::body_entity(RigidBodyId id) const {
  const EntityId own = owner_by_slot(body_owner_, records_, id);
  if (!own.is_null()) return own;
  if (id.index < mirror_owner_.size()) {
    // (a stand-in destroyed in rigid() directly is no longer its collider's either)
    const EntityId e = mirror_owner_[id.index];
    const std::uint32_t c = e.is_null() ? kNone : records_[e.index].collider;
    if (c != kNone && colliders_[c].mirror == id) return e;
  }
  return EntityId{};
}

// the velocities that take kinematic body `id` from its pose now to `target` in dt: the
// translation over dt, and the rotation q1 q0^-1 as an angle about a fixed axis over dt (a
// kinematic body's frame is its centre of mass, and it moves at constant velocities, so it
// ends the step at `target` to rounding). A path faster than kMaxRigidSpeed is named by its
// entity `owner`, what it drives (`what`: its body or its collider's stand-in) and the tick
// ending at t + dt, the body's own message ("rigid body 0 set_velocity linear: ...") kept as
// the reason: alone it did not say which path or entity.
void World::drive_body(EntityId owner, std::string_view what, RigidBodyId id, const Pose& target, double t,
                       double dt) {
  const Pose now = rigid_.pose(id);
  const Vec3 v = (target.position - now.position) / dt;
  Quat dq = glm::normalize(target.rotation * glm::conjugate(now.rotation));
  if (dq.w < 0) dq = -dq;
  const Vec3 axis(dq.x, dq.y, dq.z);
  const double s = glm::length(axis);
  const Vec3 w = s > 0 ? axis / s * (2 * std::atan2(s, static_cast<double>(dq.w)) / dt) : Vec3(0);
  try {
    rigid_.set_velocity(id, v, w);
  } catch (const Error& err) {
    throw Error("World::tick: the kinematic path of " + describe(owner) + " cannot drive its " + std::string(what) +
                " in the tick to t = " + format_value(t + dt) + " s (" + err.what() + ")");
  }
}

// The World's static colliders are the rigid bodies' static geometry: each collider of an
// entity without a body has a stand-in body with its shape and material, static, or
// kinematic when a Kinematic drives the entity (planes and meshes stay static and jump: a
// kinematic body needs a volume), remade when the collider's definition changes and moved
// with its entity. Only once an entity has a body: a world of particles pays nothing.
void World::sync_mirrors(double t, double dt) {
  // (stand-ins made while an entity had a body keep following their entities after the last
  // entity body is gone: destroyed in rigid() directly, then its entity, the count drops to 0)
  if (entity_bodies_ == 0 && !any_stand_in(colliders_, rigid_)) return;
  for (std::size_t i = 0; i < colliders_.size(); ++i) {
    ColliderEntry& c = colliders_[i];
    const EntityRecord& r = records_[c.owner.index];
    const Collider& wc = world_colliders_[i];
    // what the stand-in should be: none for an entity with a body, or for a sensor
    const bool wanted = !rigid_.valid(r.body) && !c.def.sensor;
    // (a plane's or a mesh's stays static and jumps: a kinematic body needs a volume)
    const bool solid = c.def.shape.type != ShapeType::Plane && c.def.shape.type != ShapeType::Mesh;
    const BodyType type = r.kinematic != kNone && solid ? BodyType::Kinematic : BodyType::Static;
    // such a floor on a path carries no rigid body: refused beside a dynamic one (add_collider
    // and the others refuse it; here a collider or body changed in place since)
    if (wanted && r.kinematic != kNone && !solid)
      if (const RigidBodyId b = first_dynamic_body(rigid_); !b.is_null())
        refuse_moving_floor("World::tick", describe(c.owner), c.def.shape.type,
                            dynamic_body_words(body_owner_, records_, b, [&](EntityId o) { return describe(o); }));
    if (rigid_.valid(c.mirror) && (!wanted || c.mirror_type != type || !same_collider(c.mirrored, c.def)))
      destroy_mirror(c);
    if (!wanted) continue;
    if (!rigid_.valid(c.mirror)) {
      // a new stand-in at the start of the tick's sweep
      RigidBodyDef d;
      d.name = r.name;
      d.type = type;
      d.pose = wc.begin;
      d.shapes = {{.shape = c.def.shape, .material = c.def.material}};
      // create() appends the body's name (the entity's) to `where`: the index alone here
      c.mirror = rigid_.create(d, "collider of entity " + std::to_string(c.owner.index));
      if (mirror_owner_.size() <= c.mirror.index) mirror_owner_.resize(c.mirror.index + 1);
      mirror_owner_[c.mirror.index] = c.owner;
      c.mirror_type = type;
      c.mirrored = c.def;
      c.mirrored_pose = wc.begin;
    }
    // static stand-ins jump to their entity's pose; kinematic ones move there over the tick
    if (type == BodyType::Kinematic) {
      // a teleported collider (set_pose) jumps there instead of sweeping
      if (!same_pose(c.mirrored_pose, wc.begin)) rigid_.set_pose(c.mirror, wc.begin);
      drive_body(c.owner, "collider", c.mirror, wc.end, t, dt);
    } else if (!same_pose(c.mirrored_pose, wc.end)) {
      // a jump (a user's set_pose) moves what rested on it: set_pose wakes the sleeping bodies
      // the stand-in's bounds reach before or after the move (every sleeping body in the
      // World was woken here, at each jump)
      rigid_.set_pose(c.mirror, wc.end);
    }
    c.mirrored_pose = wc.end;
  }
}

// The bodies' shapes as world colliders (planes, spheres, boxes, capsules; hulls and meshes
// have no point contact yet): at the end pose, from the begin pose of the tick (`tick`) or
// without a sweep, with the velocity of the body's material point at each shape's origin.
std::span<const Collider> World::body_colliders() const {
  if (body_colliders_stale_) refresh_body_colliders(false);
  return body_colliders_;
}

void World::refresh_body_colliders(bool tick) const {
  body_colliders_stale_ = false;
  ++build_counts_.body_collider_builds;
  body_colliders_.clear();
  body_collider_owner_.clear();
  const std::size_t n = rigid_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const RigidBodyId id = rigid_.id_at(i);
    const EntityId owner = owner_by_slot(body_owner_, records_, id);
    if (owner.is_null()) continue;  // a collider's stand-in: the collider is there already
    const Pose end = rigid_.pose(id);
    const Pose begin = tick && i < body_begin_.size() ? body_begin_[i] : end;
    const Vec3 w = rigid_.angular_velocity(id);
    // every shape type: particles and soft bodies collide with hulls, meshes and compounds too
    for (const RigidShapeDef& sd : rigid_.shapes(id)) {
      Collider c;
      c.shape = sd.shape;
      c.material = sd.material;
      c.begin = compose(begin, sd.local);
      c.end = compose(end, sd.local);
      c.velocity = rigid_.velocity_at(id, c.end.position);
      c.angular_velocity = w;
      body_colliders_.push_back(c);
      body_collider_owner_.push_back(owner.index);
    }
  }
  build_counts_.body_colliders_made += body_colliders_.size();
}

const QueryWorld& World::queries() {
  if (collision_stale_) rebuild_collision();
  if (queries_revision_ != collision_.revision()) {
    queries_.build(collision_);
    queries_revision_ = collision_.revision();
  }
  return queries_;
}

void World::validate_colliders() {
  // sensors too: they push nothing, but their shapes are tested against the bodies and the
  // particles each tick (a sensor's radius set to NaN between ticks went unchecked, and the
  // narrow phase stopped the tick naming no collider, or the sensor silently sensed nothing)
  for (std::size_t i = 0; i < world_colliders_.size(); ++i)
    if (!world_colliders_[i].ok()) world_colliders_[i].validate("collider of " + describe(colliders_[i].owner));
}

void World::collide_colliders() {
  validate_colliders();
  collision_stale_ = false;
  ++build_counts_.collision_builds;
  collision_.clear();
  for (std::size_t i = 0; i < world_colliders_.size(); ++i)
    if (!colliders_[i].def.sensor)
      collision_.add(world_colliders_[i], colliders_[i].owner.index);  // a sensor pushes nothing
}

bool World::systems_at(WorldStage stage) const {
  for (const auto& s : systems_)
    if (s->stage() == stage) return true;
  return false;
}

void World::rebuild_collision() {
  // the colliders at their poses now, with their definitions as they are (World::collider()
  // may have changed one) ...
  for (std::size_t i = 0; i < colliders_.size(); ++i)
    world_colliders_[i].shape = colliders_[i].def.shape, world_colliders_[i].material = colliders_[i].def.material;
  collide_colliders();
  // ... then the bodies' shapes as they are now
  if (body_colliders_stale_) refresh_body_colliders(false);
  for (std::size_t k = 0; k < body_colliders_.size(); ++k) collision_.add(body_colliders_[k], body_collider_owner_[k]);
}

// The rigid stage: kinematic bodies driven to their paths' poses, one step of every body
// under the World's gravity, the simulated entities' poses from their bodies, and the
// bodies' shapes added to the tick's collision world (so particles and soft bodies meet this
// tick's bodies).
void World::step_rigid(double t, double dt) {
  touch_begin_.clear(), touch_end_.clear(), sensor_enter_.clear(), sensor_leave_.clear();
  if (rigid_.size() == 0) {
    touching_.clear();  // no bodies, no rigid contacts
    collide_colliders();  // the tick's collision world: the colliders alone
    return;
  }
  // a kinematic body on a path reaches the path's pose at the end of the tick
  for (const KinematicEntry& k : kinematics_) {
    const EntityRecord& r = records_[k.owner.index];
    if (rigid_.valid(r.body)) drive_body(k.owner, "rigid body", r.body, r.pose, t, dt);
  }
  // where every body starts, for the sweeps
  const std::size_t n = rigid_.size();
  if (body_begin_.size() < n) body_begin_.resize(n);
  for (std::size_t i = 0; i < n; ++i) body_begin_[i] = rigid_.pose(rigid_.id_at(i));
  try {
    rigid_.step(dt, gravity_);
  } catch (const Error& err) {
    // a body whose state stopped being finite (or that a force took past kMaxRigidSpeed)
    // stops the world, naming its entity and the time
    const RigidBodyId id = rigid_.failed_body();
    if (id.is_null()) throw;
    const EntityId owner = owner_by_slot(body_owner_, records_, id);
    failure_ = (owner.is_null() ? std::string("a rigid body") : "the rigid body of " + describe(owner)) +
               " stopped the world in the tick to t = " + format_value(t + dt) + " s (" + err.what() + ")";
    throw Error("World::tick: " + failure_);
  }
  // whichever system simulates an entity writes its pose: the body, unless a path drives it
  for (std::size_t i = 0; i < n; ++i) {
    const RigidBodyId id = rigid_.id_at(i);
    const EntityId owner = owner_by_slot(body_owner_, records_, id);
    if (owner.is_null()) continue;
    EntityRecord& r = records_[owner.index];
    if (r.kinematic != kNone || rigid_.type(id) == BodyType::Static) continue;
    r.pose = rigid_.pose(id);
    r.velocity = rigid_.velocity_at(id, r.pose.position);
    r.angular_velocity = rigid_.angular_velocity(id);
  }
  // a collider on the entity of a body that the rigid stage moves follows the body to this
  // tick's pose: sync() placed it at the entity's pose of the tick's start, a tick behind the
  // body (a particle riding a rising body sat v dt inside its collider; a sensor on a body
  // tested last tick's place). It sweeps from there to the body's new pose.
  for (std::size_t i = 0; i < colliders_.size(); ++i) {
    const EntityRecord& r = records_[colliders_[i].owner.index];
    if (!rigid_.valid(r.body) || r.kinematic != kNone || rigid_.type(r.body) == BodyType::Static) continue;
    Collider& c = world_colliders_[i];
    c.end = r.pose;
    c.velocity = r.velocity;
    c.angular_velocity = r.angular_velocity;
  }
  // the tick's collision world, built once: the colliders where they end the tick ...
  collide_colliders();
  // ... then this tick's bodies
  refresh_body_colliders(true);
  for (std::size_t k = 0; k < body_colliders_.size(); ++k) {
    if (!body_colliders_[k].ok()) {
      // finite but beyond what the collision world holds (its bounds are floats): a body flung
      // past 3.4e38 m stops the world like a non-finite one, naming its entity and the time
      const std::uint32_t e = body_collider_owner_[k];
      try {
        body_colliders_[k].validate("shape");
      } catch (const Error& err) {
        failure_ = "the rigid body of entity " + std::to_string(e) +
                   (records_[e].name.empty() ? "" : " '" + records_[e].name + "'") +
                   " left the range of the collision world in the tick to t = " + format_value(t + dt) +
                   " s (" + err.what() + ")";
        throw Error("World::tick: " + failure_);
      }
    }
    collision_.add(body_colliders_[k], body_collider_owner_[k]);
  }
  // the bodies' touching pairs (their events wait for the particles: tick())
  update_rigid_touches();
}

namespace {
std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) { return (std::uint64_t{a} << 32) | b; }
}  // namespace

namespace {
// Sorts touch records by pair and keeps one record a pair: the fastest approach.
template <class Record>
void one_per_pair(std::vector<Record>& v) {
  std::sort(v.begin(), v.end(),
            [](const Record& x, const Record& y) { return x.key != y.key ? x.key < y.key : x.approach > y.approach; });
  v.erase(std::unique(v.begin(), v.end(), [](const Record& x, const Record& y) { return x.key == y.key; }), v.end());
}
// true when a sphere of radius r (m) about x may reach into bounds b: b grown by r holds x
bool sphere_in_bounds(const Aabb& b, const Vec3& x, double r) {
  return !(x.x < b.lo.x - r || x.y < b.lo.y - r || x.z < b.lo.z - r || x.x > b.hi.x + r || x.y > b.hi.y + r ||
           x.z > b.hi.z + r);
}
// Room for `need` elements in each vector, at least doubling (so a tick with more pairs than
// ever before allocates once, not every tick); sets that swap each tick grow together.
template <class... V>
void room(std::size_t need, V&... v) {
  ((v.capacity() < need ? v.reserve(std::max(need, 2 * v.capacity())) : void()), ...);
}
}  // namespace

// The bodies' touching pairs, in the manner of Box2D v3's contact begin/end events: an
// entity pair touches in a tick when a manifold between their bodies (or a body and a
// collider's stand-in) was pushed by the solver; pairs whose bodies sleep are not stepped
// and stay touching. Sorted by key, one record per pair.
void World::update_rigid_touches() {
  std::swap(touching_, touching_prev_);
  touching_.clear();
  // at most every manifold and every pair kept from last tick
  room(rigid_.manifold_count() + touching_prev_.size(), touching_, touching_prev_);
  for (std::size_t k = 0; k < rigid_.manifold_count(); ++k) {
    const RigidManifoldInfo m = rigid_.manifold(k);
    if (!(m.max_normal_impulse > 0)) continue;  // speculative: no contact yet
    EntityId a = body_entity(m.a), b = body_entity(m.b);
    if (a.is_null() || b.is_null() || a == b) continue;
    Vec3 n = m.normal;
    if (a.index > b.index) std::swap(a, b), n = -n;
    touching_.push_back({pair_key(a.index, b.index), n, m.point, m.approach_speed});
  }
  one_per_pair(touching_);
  // a pair of last tick that a sleeping body is in goes on touching
  auto sleeping = [&](std::uint32_t e) {
    const RigidBodyId id = records_[e].body;
    return rigid_.valid(id) && rigid_.type(id) == BodyType::Dynamic && !rigid_.awake(id);
  };
  const std::size_t fresh = touching_.size();
  for (const TouchRecord& r : touching_prev_) {
    const auto at = std::lower_bound(touching_.begin(), touching_.begin() + static_cast<std::ptrdiff_t>(fresh), r,
                                     [](const TouchRecord& x, const TouchRecord& y) { return x.key < y.key; });
    const bool present = at != touching_.begin() + static_cast<std::ptrdiff_t>(fresh) && at->key == r.key;
    if (!present && (sleeping(static_cast<std::uint32_t>(r.key >> 32)) || sleeping(static_cast<std::uint32_t>(r.key))))
      touching_.push_back(r);
  }
  one_per_pair(touching_);  // the kept pairs in key order (their keys are new here)
}

// The particle entities' touching pairs: a particle entity touches a collider's entity (a
// collider, or a shape of a rigid body) in a tick when the particle kernels met that
// collider during the tick (ParticleSystem::contacts: an impact, resting or sliding on it,
// a push out of it), at the impact's normal, point and approach speed. A bounce whose
// impact and rebound fall inside one tick is seen: the kernels record it at the impact,
// not from where the tick left the particle. Emitted particles have no entity and record
// nothing. Sorted by key, one record per pair (the fastest approach).
//
// A particle whose entity a path drives touches at the pose pin_kinematic_particles put it
// on: the particle stage moved it on from there and met the colliders where it would have
// gone (until 2026-12-07 a particle on a path at 10 m/s toward a wall began touching it a
// tick early, 5 cm short, and one held 1 mm above the ground, which gravity pulled into it
// each tick, touched it for good). It is tested as a sensor tests a particle: its sphere
// against each collider's shape at the end of the tick, touching while the signed distance
// from its centre is at most its radius, at the closest surface point, the approach speed
// the path's velocity into the surface relative to the surface's. A path that crosses a
// thin collider within one tick is not seen (as by a sensor). As the kernels, it keeps the
// first kMaxParticleContacts colliders it meets (the room reserve_touch_sets made).
void World::update_particle_touches() {
  particle_touching_.clear();
  const std::span<const std::uint32_t> owners = collision_.owners();
  const std::span<const Collider> colliders = collision_.colliders();
  const auto at_path_pose = [&](std::uint32_t e, std::size_t i) {
    const Vec3 x = particles_.position(i), v = particles_.velocity(i);
    const double r = particles_.radius(i);
    std::size_t met = 0;
    for (std::size_t k = 0; k < colliders.size() && met < kMaxParticleContacts; ++k) {
      const std::uint32_t o = owners[k];
      if (o == CollisionWorld::kNoOwner || o == e || !entities_.valid({o, entities_.generation(o)})) continue;
      const Collider& c = colliders[k];
      if (!sphere_in_bounds(bounds(c.shape, c.end), x, r)) continue;
      const PointDistance d = query::point_distance_unchecked(c.shape, c.end, x);
      if (!(d.distance <= r)) continue;
      const Vec3 surface = c.velocity + glm::cross(c.angular_velocity, d.point - c.end.position);
      const double vn = glm::dot(v - surface, d.normal);
      // the normal out of the collider, toward the particle; the event's from the smaller
      // entity index to the larger
      particle_touching_.push_back({e < o ? pair_key(e, o) : pair_key(o, e), e < o ? -d.normal : d.normal, d.point,
                                    vn < 0 ? -vn : 0.0});
      ++met;
    }
  };
  for (std::uint32_t e = 0; e < records_.size(); ++e) {
    const ParticleId pid = records_[e].particle;
    if (pid.is_null() || !particles_.valid(pid)) continue;
    if (records_[e].kinematic != kNone) {
      at_path_pose(e, particles_.index_of(pid));
      continue;
    }
    for (const ParticleContact& c : particles_.contacts(pid)) {
      const std::uint32_t o = c.collider < owners.size() ? owners[c.collider] : CollisionWorld::kNoOwner;
      if (o == CollisionWorld::kNoOwner || o == e || !entities_.valid({o, entities_.generation(o)})) continue;
      // the contact normal points out of the collider, toward the particle; the event's
      // from the smaller entity index to the larger
      const Vec3 n(c.normal);
      particle_touching_.push_back({e < o ? pair_key(e, o) : pair_key(o, e), e < o ? -n : n, Vec3(c.point),
                                    static_cast<double>(c.approach_speed)});
    }
  }
  one_per_pair(particle_touching_);
}

// Room in the touch pair sets for the entities added so far, so that a tick in which more
// pairs touch at once than before does not allocate: kTouchesPerBody pairs a body entity,
// kMaxParticleContacts a particle entity (grown geometrically, never shrunk). The event sets
// swap each tick, so both of a pair of sets get the same room.
void World::reserve_touch_sets() {
  constexpr std::size_t kTouchesPerBody = 8;  // a box in a pyramid touches about 8 others and 2 share a pair
  const std::size_t bodies = entity_bodies_ * kTouchesPerBody,
                    particles = particle_entities_added_ * kMaxParticleContacts;
  room(bodies, touching_, touching_prev_);
  room(particles, particle_touching_);
  room(bodies + particles, touched_, touched_prev_, touch_begin_, touch_end_);
}

// This tick's touching pairs (the bodies' and the particles', one record per pair, the
// bodies' first when both touch) against last tick's give the begin and end events, in
// key order: by the smaller entity index, then the larger.
void World::update_touch_events() {
  update_particle_touches();
  std::swap(touched_, touched_prev_);
  touched_.clear();
  // the union's pairs, and the events: at most a begin a pair now, an end a pair before
  const std::size_t need = touching_.size() + particle_touching_.size();
  room(need, touched_, touched_prev_, touch_begin_);
  room(touched_prev_.size(), touch_end_);
  // the union of the two sorted sets
  std::size_t i = 0, j = 0;
  while (i < touching_.size() || j < particle_touching_.size()) {
    if (j == particle_touching_.size() ||
        (i < touching_.size() && touching_[i].key <= particle_touching_[j].key)) {
      if (j < particle_touching_.size() && touching_[i].key == particle_touching_[j].key) ++j;
      touched_.push_back(touching_[i++]);
    } else {
      touched_.push_back(particle_touching_[j++]);
    }
  }
  // begin: now and not before; end: before and not now
  auto entity = [&](std::uint32_t e) { return EntityId{e, entities_.generation(e)}; };
  i = 0, j = 0;
  while (i < touched_.size() || j < touched_prev_.size()) {
    if (j == touched_prev_.size() || (i < touched_.size() && touched_[i].key < touched_prev_[j].key)) {
      const TouchRecord& r = touched_[i++];
      touch_begin_.push_back({entity(static_cast<std::uint32_t>(r.key >> 32)),
                              entity(static_cast<std::uint32_t>(r.key)), r.normal, r.point, r.approach});
    } else if (i == touched_.size() || touched_prev_[j].key < touched_[i].key) {
      const std::uint64_t k = touched_prev_[j++].key;
      touch_end_.push_back({entity(static_cast<std::uint32_t>(k >> 32)), entity(static_cast<std::uint32_t>(k))});
    } else {
      ++i, ++j;
    }
  }
}

// Sensor events: a body's entity is in a sensor while one of its shapes overlaps the
// sensor's shape at the end of the tick (bounds first, then the narrow phase with no
// speculative margin), a particle entity while its sphere does (the signed distance from
// its centre to the shape at most its radius); this tick's set against last tick's gives
// enter and leave. An emitter's particles are counted instead (sensor_counts_), per sensor
// and emitter: a fountain through a sensor would otherwise make hundreds of events a tick,
// and its particles have no entity to name (Box2D v3 leaves sensor events to shapes that
// ask for them, for the same reason).
void World::update_sensor_events() {
  std::swap(sensing_, sensing_prev_);
  sensing_.clear();
  sensor_counts_.clear();
  const std::size_t slots = particles_.emitter_count();
  if (inside_by_slot_.size() < slots) inside_by_slot_.resize(slots);
  for (std::size_t i = 0; i < colliders_.size(); ++i) {
    if (!colliders_[i].def.sensor) continue;
    const Collider& sc = world_colliders_[i];
    const std::uint32_t sensor = colliders_[i].owner.index;
    const Aabb sb = bounds(sc.shape, sc.end);
    // a particle's sphere against the sensor: bounds grown by the radius, then the distance
    auto overlaps = [&](std::size_t p) {
      const Vec3 x = particles_.position(p);
      const double r = particles_.radius(p);
      return sphere_in_bounds(sb, x, r) && query::point_distance_unchecked(sc.shape, sc.end, x).distance <= r;
    };
    // particle entities
    for (std::uint32_t e = 0; e < records_.size(); ++e) {
      const ParticleId pid = records_[e].particle;
      if (e == sensor || pid.is_null() || !particles_.valid(pid)) continue;
      if (overlaps(particles_.index_of(pid))) sensing_.push_back(pair_key(sensor, e));
    }
    // emitted particles, counted per emitter slot, then named by the emitters' entities
    if (slots > 0) {
      std::fill(inside_by_slot_.begin(), inside_by_slot_.begin() + static_cast<std::ptrdiff_t>(slots), 0);
      bool any = false;
      for (std::size_t p = 0; p < particles_.size(); ++p) {
        const std::uint32_t src = particles_.source(p);
        if (src != 0 && overlaps(p)) ++inside_by_slot_[src - 1], any = true;
      }
      if (any)
        for (std::uint32_t e = 0; e < records_.size(); ++e) {
          const EmitterId id = records_[e].emitter;
          if (id.is_null()) continue;
          for (std::size_t slot = 0; slot < slots; ++slot)
            if (particles_.emitter_at(slot) == id && inside_by_slot_[slot] > 0)
              sensor_counts_.push_back({{sensor, entities_.generation(sensor)}, {e, entities_.generation(e)},
                                        inside_by_slot_[slot]});
        }
    }
    if (rigid_.size() == 0) continue;
    for (std::size_t k = 0; k < body_colliders_.size(); ++k) {
      const Collider& bc = body_colliders_[k];
      const std::uint32_t visitor = body_collider_owner_[k];
      if (visitor == sensor) continue;
      if (!bounds(bc.shape, bc.end).overlaps(sb)) continue;
      if (sensor_overlaps(sc.shape, sc.end, bc.shape, bc.end)) sensing_.push_back(pair_key(sensor, visitor));
    }
  }
  std::sort(sensing_.begin(), sensing_.end());
  sensing_.erase(std::unique(sensing_.begin(), sensing_.end()), sensing_.end());
  std::sort(sensor_counts_.begin(), sensor_counts_.end(), [](const SensorCount& a, const SensorCount& b) {
    return a.sensor.index != b.sensor.index ? a.sensor.index < b.sensor.index : a.emitter.index < b.emitter.index;
  });
  // enter: now and not before; leave: before and not now
  auto event = [&](std::uint64_t k) {
    const auto a = static_cast<std::uint32_t>(k >> 32), b = static_cast<std::uint32_t>(k);
    return SensorEvent{{a, entities_.generation(a)}, {b, entities_.generation(b)}};
  };
  std::size_t i = 0, j = 0;
  while (i < sensing_.size() || j < sensing_prev_.size()) {
    if (j == sensing_prev_.size() || (i < sensing_.size() && sensing_[i] < sensing_prev_[j]))
      sensor_enter_.push_back(event(sensing_[i++]));
    else if (i == sensing_.size() || sensing_prev_[j] < sensing_[i])
      sensor_leave_.push_back(event(sensing_prev_[j++]));
    else
      ++i, ++j;
  }
}

// a destroyed entity's pairs end without an event
void World::forget_pairs(EntityId e) {
  auto involves = [&](std::uint64_t k) { return (k >> 32) == e.index || (k & 0xffffffffu) == e.index; };
  std::erase_if(touching_, [&](const TouchRecord& r) { return involves(r.key); });
  std::erase_if(touched_, [&](const TouchRecord& r) { return involves(r.key); });
  std::erase_if(sensing_, involves);
}

// mass-weighted projection of each distance constraint (Jakobsen, "Advanced character
// physics", GDC 2001; Mueller et al., "Position based dynamics", 2007, eq. 9-10), with
// the velocity change that the displacement implies
void World::solve_constraints(double dt) {
  for (const ConstraintEntry& c : constraints_) {
    const ParticleId pa = records_[c.owner.index].particle;
    const ParticleId pb = records_[c.def.other.index].particle;
    if (!particles_.valid(pa) || !particles_.valid(pb)) continue;
    const std::size_t a = particles_.index_of(pa), b = particles_.index_of(pb);
    const Vec3 xa = particles_.position(a), xb = particles_.position(b);
    const Vec3 d = xb - xa;
    const double len = glm::length(d);
    if (len <= 0) continue;
    // a particle on a path gives way to nothing (its inverse mass 0): it stays on its path
    const double wa = records_[c.owner.index].kinematic != kNone ? 0 : 1 / particles_.mass(a);
    const double wb = records_[c.def.other.index].kinematic != kNone ? 0 : 1 / particles_.mass(b);
    if (wa + wb == 0) continue;
    const Vec3 corr = c.def.stiffness * (len - c.def.rest_length) / (len * (wa + wb)) * d;
    particles_.set_position(a, xa + wa * corr);
    particles_.set_position(b, xb - wb * corr);
    particles_.set_velocity(a, particles_.velocity(a) + wa * corr / dt);
    particles_.set_velocity(b, particles_.velocity(b) - wb * corr / dt);
  }
}

// every system registered at `stage`, in the order added
void World::run_systems(WorldStage stage, double t, double dt) {
  if (systems_.empty()) return;
  Stopwatch sw;
  for (auto& s : systems_)
    if (s->stage() == stage) s->step(*this, t, dt);
  profile_.systems += sw.seconds();
}

// a particle whose entity a path drives is on the path's pose at the end of the tick: the
// particle stage integrated it on from there (v dt ahead, and pulled by gravity), so it is
// put back, its velocity the path's (a distance constraint does not move it either)
void World::pin_kinematic_particles() {
  for (const KinematicEntry& k : kinematics_) {
    const EntityRecord& r = records_[k.owner.index];
    if (r.particle.is_null() || !particles_.valid(r.particle)) continue;
    const std::size_t i = particles_.index_of(r.particle);
    particles_.set_position(i, r.pose.position);
    particles_.set_velocity(i, r.velocity);
  }
}

// whichever system simulates an entity writes its pose: the particle system for
// particle entities that no kinematic path drives
void World::write_particle_poses() {
  for (EntityRecord& r : records_) {
    if (r.particle.is_null() || r.kinematic != kNone || !particles_.valid(r.particle)) continue;
    r.pose.position = particles_.position(r.particle);
  }
}

void World::tick(double t, double dt) {
  if (!failure_.empty()) throw Error("World::tick: the simulation stopped: " + failure_);
  // a bad t or dt is the caller's, not the state's: refused before any stage moves anything,
  // so the world stays as it was and may tick again (a stage's own check would stop it)
  if (!std::isfinite(t)) require_finite(t, "World::tick(t)");
  if (!(std::isfinite(dt) && dt > 0)) require_positive(dt, "World::tick(dt)");
  if (!detail::squarable<float>(dt))
    detail::throw_not_squarable<float>(dt, "World::tick(dt)", "s",
                                       detail::kParticleStepWhy);
  Stopwatch total, sw;
  profile_ = {};
  auto stage_done = [&](WorldStage s) {
    profile_.stages[static_cast<std::size_t>(s)] = sw.seconds();
    sw.reset();
  };
  // World::forcer hands out the definitions, changeable between ticks: checked again here by
  // field, before anything moves (a strength or radius set to NaN or inf went on unchecked,
  // add_forcer alone having validated them, and pushed the particles in it to NaN or stopped
  // the rigid bodies naming a body's apply_force). The pose is checked at its entity's pose
  // (sync). validate allocates only to throw: an empty `where`, named on the way out
  for (const ForcerEntry& f : forcers_) {
    try {
      f.def.validate("");
    } catch (const Error& err) {
      throw Error("forcer of " + describe(f.owner) + err.what());
    }
  }
  // the colliders' definitions likewise (World::collider hands them out; sync checked them
  // only after run_kinematics had moved the kinematic entities, so a refused tick left them
  // a tick ahead): the shape and material read in place (its pose is checked in sync; a copy
  // of the Collider to ask ok() copied the shape's shared hull, mesh or compound, two atomic
  // counts a collider a tick), and copied with last tick's poses only to name the bad field
  for (std::size_t i = 0; i < colliders_.size(); ++i) {
    if (Collider::shape_ok(colliders_[i].def.shape, colliders_[i].def.material)) continue;
    Collider c = world_colliders_[i];
    c.shape = colliders_[i].def.shape, c.material = colliders_[i].def.material;
    c.validate("collider of " + describe(colliders_[i].owner));
  }
  // 1. kinematic: paths, motors and thrusters
  run_kinematics(t, dt);
  profile_.kinematic = sw.seconds();
  run_systems(WorldStage::Kinematic, t, dt);
  stage_done(WorldStage::Kinematic);
  // 2. collide: poses of colliders, forcers and emitters
  sync(t, dt);
  profile_.sync = sw.seconds();
  // a system of this stage may read the collision world: the colliders at this tick's poses
  // (the rigid stage builds it again, with the colliders riding on bodies moved and the bodies)
  if (systems_at(WorldStage::Collide)) collide_colliders();
  run_systems(WorldStage::Collide, t, dt);
  stage_done(WorldStage::Collide);
  // 3. rigid: the bodies, then the tick's collision world: the colliders and the bodies' shapes
  step_rigid(t, dt);
  run_systems(WorldStage::Rigid, t, dt);
  stage_done(WorldStage::Rigid);
  // 4. particles: emit, integrate, collide, recycle, under the world's gravity
  particles_.forces().gravity = gravity_;
  try {
    particles_.step(t, dt, collision_, world_forcers_);
  } catch (const Error& err) {
    failure_ = err.what();  // the world refuses to tick again and repeats this
    throw;
  }
  const ParticleProfile& pp = particles_.profile();
  profile_.emit = pp.emit;
  profile_.integrate = pp.integrate;
  profile_.collide = pp.collide;
  profile_.recycle = pp.recycle;
  pin_kinematic_particles();
  write_particle_poses();
  // what began and stopped touching (bodies and particle entities), what entered and left
  // the sensors: bodies (moved in the rigid stage) and particles
  update_touch_events();
  update_sensor_events();
  run_systems(WorldStage::Particles, t, dt);
  stage_done(WorldStage::Particles);
  // 5. soft bodies
  run_systems(WorldStage::Soft, t, dt);
  stage_done(WorldStage::Soft);
  // 6. constraints
  solve_constraints(dt);
  profile_.constraints = sw.seconds();
  run_systems(WorldStage::Constraints, t, dt);
  stage_done(WorldStage::Constraints);
  // 7. post
  run_systems(WorldStage::Post, t, dt);
  stage_done(WorldStage::Post);
  time_ = t + dt;
  ++ticks_;
  profile_.total = total.seconds();
}

std::uint64_t World::hash() const {
  std::uint64_t h = particles_.hash();
  for (const KinematicEntry& k : kinematics_) {
    const Pose& p = records_[k.owner.index].pose;
    h = hash_bytes(&p.position, sizeof(p.position), h);
  }
  if (entity_bodies_ > 0 || any_stand_in(colliders_, rigid_)) h = rigid_.hash() ^ (h * 0x9e3779b97f4a7c15ull);
  for (const auto& s : systems_) h = s->hash(h);
  return h;
}

void World::draw(DebugDraw& draw, const DrawFlags& flags) const {
  // colliders (shapes, bounds), forcers, particles, then every system
  for (const Collider& c : world_colliders_) c.draw(draw, colors::grey, flags);
  draw_rigid_bodies(draw, flags);
  for (const Forcer& f : world_forcers_) f.draw(draw, colors::cyan, flags);
  particles_.draw(draw, flags, particles_.size() <= 2000);
  // the entities' distance constraints
  if (flags.constraints)
    for (const ConstraintEntry& c : constraints_) {
      const ParticleId pa = records_[c.owner.index].particle, pb = records_[c.def.other.index].particle;
      if (particles_.valid(pa) && particles_.valid(pb))
        draw.line(particles_.position(pa), particles_.position(pb), colors::yellow);
    }
  for (const auto& s : systems_) s->draw(*this, draw, flags);
}

void World::draw_rigid_bodies(DebugDraw& draw, const DrawFlags& flags, const RigidBodyColors& colors) const {
  // each shape of each entity's body at the body's pose now (horizontal planes are left to a
  // client's ground grid), then the last tick's contact points and normals
  const RigidDrawOptions options{.horizontal_planes = false};
  for (std::size_t i = 0; i < rigid_.size(); ++i) {
    const RigidBodyId id = rigid_.id_at(i);
    if (!valid(id)) continue;  // a collider's stand-in: drawn as its collider
    const BodyType type = rigid_.type(id);
    const Color col = type == BodyType::Static      ? colors.fixed
                      : type == BodyType::Kinematic ? colors.kinematic
                      : rigid_.awake(id)            ? colors.awake
                                                    : colors.asleep;
    // neighbouring entities in three shades of their colour, so the boxes of a stack read apart
    const float shade = 1.0f - 0.12f * static_cast<float>(owner_by_slot(body_owner_, records_, id).index % 3);
    rigid_.draw_body(draw, id, {col.r * shade, col.g * shade, col.b * shade, col.a}, flags, options);
  }
  rigid_.draw_contacts(draw, flags);
}

}  // namespace pba
