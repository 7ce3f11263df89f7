// The entity-component world: entities, component wiring, kinematic paths, constraints
// and the fixed phase order of a tick.
#include <algorithm>
#include <cmath>
#include <string>

#include "pba/world.h"

namespace pba {

namespace {




void require_pose(const Pose& p, std::string_view where) {
  if (!is_finite(p.position)) require_finite(p.position, field_path(where, "position"));
  const Quat& q = p.rotation;
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!std::isfinite(n) || std::abs(n - 1) > 1e-6)
    throw Error(field_path(where, "rotation") + ": must be a finite unit quaternion");
}

double waypoint_length(const KinematicDef& d) {
  double len = 0;
  for (std::size_t i = 1; i < d.waypoints.size(); ++i) len += glm::length(d.waypoints[i] - d.waypoints[i - 1]);
  if (d.loop && d.waypoints.size() > 1) len += glm::length(d.waypoints.front() - d.waypoints.back());
  return len;
}

}  // namespace

void KinematicDef::validate(std::string_view where) const {
  if (!is_finite(velocity)) require_finite(velocity, field_path(where, "velocity"));
  if (!is_finite(spin)) require_finite(spin, field_path(where, "spin"));
  switch (path) {
    case PathType::Linear:
    case PathType::Motor: break;
    case PathType::Thruster: if (!is_finite(thrust)) require_finite(thrust, field_path(where, "thrust")); break;
    case PathType::Circular:
      if (!is_finite(center)) require_finite(center, field_path(where, "center"));
      if (!is_finite(axis)) require_finite(axis, field_path(where, "axis"));
      if (glm::length(axis) == 0) throw Error(field_path(where, "axis") + ": must be non-zero, got (0, 0, 0)");
      if (!(std::isfinite(radius) && (radius) > 0)) require_positive(radius, field_path(where, "radius"));
      if (!std::isfinite(angular_speed)) require_finite(angular_speed, field_path(where, "angular_speed"));
      if (!std::isfinite(phase)) require_finite(phase, field_path(where, "phase"));
      break;
    case PathType::Waypoints:
      if (waypoints.size() < 2)
        throw Error(field_path(where, "waypoints") + ": needs at least 2 points, got " + std::to_string(waypoints.size()));
      for (std::size_t i = 0; i < waypoints.size(); ++i)
        require_finite(waypoints[i], field_path(where, "waypoints[" + std::to_string(i) + "]"));
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
      const Vec3 a = glm::normalize(d.axis);
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
        const double len = glm::length(b - a);
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
  const double w = glm::length(d.spin);
  if (w > 0) p.rotation = glm::normalize(glm::angleAxis(w * t, d.spin / w) * start.rotation);
  if (velocity) *velocity = v;
  return p;
}

// ---------------------------------------------------------------------------------------

World::World(const WorldDef& def)
    : settings_(def.stepper),
      gravity_((require_finite(def.gravity, "WorldDef.gravity"), def.gravity)),
      stepper_((def.stepper.validate("WorldDef.stepper"), def.stepper)),
      particles_(def.particles) {
  particles_.forces().gravity = gravity_;
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
  require_finite(g, "World::set_gravity(g)");
  gravity_ = g;
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

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
  // components first, in a fixed order
  for (auto& s : systems_) s->on_destroy(e);
  if (particles_.valid(r.particle)) particles_.destroy(r.particle);
  if (!r.emitter.is_null()) particles_.remove_emitter(r.emitter);
  if (r.collider != kNone) {
    const std::uint32_t i = r.collider;
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
  return r.pose;
}

Vec3 World::velocity(EntityId e) const {
  const EntityRecord& r = record(e, "World::velocity");
  if (particles_.valid(r.particle)) return particles_.velocity(r.particle);
  return r.velocity;
}

void World::set_pose(EntityId e, const Pose& pose) {
  require_pose(pose, "World::set_pose");
  EntityRecord& r = record(e, "World::set_pose");
  r.pose = pose;
  if (particles_.valid(r.particle)) particles_.set_position(particles_.index_of(r.particle), pose.position);
  // a teleported collider does not sweep
  if (r.collider != kNone) world_colliders_[r.collider].begin = world_colliders_[r.collider].end = pose;
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
  ParticleDef d = def;
  d.position = r.pose.position + r.pose.rotation * def.position;
  r.particle = particles_.create(d, "particle of " + describe(e));
  return r.particle;
}

ColliderId World::add_collider(EntityId e, const ColliderDef& def) {
  EntityRecord& r = record(e, "World::add_collider");
  if (r.collider != kNone) throw Error("World::add_collider: " + describe(e) + " already has a collider");
  // validate as a world collider at the entity's pose
  Collider c;
  c.shape = def.shape;
  c.material = def.material;
  c.begin = c.end = r.pose;
  c.validate("collider of " + describe(e));
  if (def.shape.type == ShapeType::Plane) c.shape.normal = glm::normalize(def.shape.normal);
  r.collider = static_cast<std::uint32_t>(colliders_.size());
  colliders_.push_back({e, def, collider_ids_.create(e)});
  colliders_.back().def.shape.normal = c.shape.normal;
  world_colliders_.push_back(c);
  return colliders_.back().id;
}

ForcerId World::add_forcer(EntityId e, const Forcer& def) {
  EntityRecord& r = record(e, "World::add_forcer");
  if (r.forcer != kNone) throw Error("World::add_forcer: " + describe(e) + " already has a forcer");
  def.validate("forcer of " + describe(e));
  r.forcer = static_cast<std::uint32_t>(forcers_.size());
  forcers_.push_back({e, def, forcer_ids_.create(e)});
  Forcer w = def;
  w.pose = compose(r.pose, def.pose);
  world_forcers_.push_back(w);
  return forcers_.back().id;
}

EmitterId World::add_emitter(EntityId e, const EmitterDef& def) {
  EntityRecord& r = record(e, "World::add_emitter");
  if (!r.emitter.is_null()) throw Error("World::add_emitter: " + describe(e) + " already has an emitter");
  EmitterDef d = def;
  d.pose = compose(r.pose, def.pose);
  r.emitter = particles_.add_emitter(d, "emitter of " + describe(e));
  r.emitter_local = def.pose;
  return r.emitter;
}

KinematicId World::add_kinematic(EntityId e, const KinematicDef& def) {
  EntityRecord& r = record(e, "World::add_kinematic");
  if (r.kinematic != kNone) throw Error("World::add_kinematic: " + describe(e) + " already has a kinematic");
  def.validate("kinematic of " + describe(e));
  r.kinematic = static_cast<std::uint32_t>(kinematics_.size());
  KinematicEntry k{e, kinematic_ids_.create(e), def, time_, r.pose, def.path == PathType::Waypoints ? waypoint_length(def) : 0.0};
  // waypoint and circular paths start on the path
  Vec3 v;
  const Pose p = kinematic_pose(def, r.pose, 0, &v, k.length);
  r.pose = p;
  r.velocity = v;
  k.start_pose.rotation = r.pose.rotation;
  // a collider jumps to the path's start instead of sweeping there
  if (r.collider != kNone) world_colliders_[r.collider].begin = world_colliders_[r.collider].end = r.pose;
  kinematics_.push_back(std::move(k));
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
  for (KinematicEntry& k : kinematics_) {
    EntityRecord& r = records_[k.owner.index];
    Vec3 v;
    const Pose p = kinematic_pose(k.def, k.start_pose, t + dt - k.start, &v, k.length);
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

void World::sync(double /*t*/, double /*dt*/) {
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
  // the collision world of the tick (validated and flattened once for every client)
  collision_.clear();
  for (std::size_t i = 0; i < world_colliders_.size(); ++i) {
    const EntityId owner = colliders_[i].owner;
    if (!world_colliders_[i].ok()) world_colliders_[i].validate("collider of " + describe(owner));
    collision_.add(world_colliders_[i], owner.index);
  }
  // forcers and emitters follow their entities
  for (std::size_t i = 0; i < forcers_.size(); ++i) {
    const EntityRecord& r = records_[forcers_[i].owner.index];
    world_forcers_[i] = forcers_[i].def;
    world_forcers_[i].pose = compose(r.pose, forcers_[i].def.pose);
  }
  for (const EntityRecord& r : records_)
    if (!r.emitter.is_null()) particles_.set_emitter_pose(r.emitter, compose(r.pose, r.emitter_local));
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
    const double wa = 1 / particles_.mass(a), wb = 1 / particles_.mass(b);
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
  Stopwatch total, sw;
  profile_ = {};
  auto stage_done = [&](WorldStage s) {
    profile_.stages[static_cast<std::size_t>(s)] = sw.seconds();
    sw.reset();
  };
  // 1. kinematic: paths, motors and thrusters
  run_kinematics(t, dt);
  profile_.kinematic = sw.seconds();
  run_systems(WorldStage::Kinematic, t, dt);
  stage_done(WorldStage::Kinematic);
  // 2. collide: poses of colliders, forcers and emitters; the tick's collision world
  sync(t, dt);
  profile_.sync = sw.seconds();
  run_systems(WorldStage::Collide, t, dt);
  stage_done(WorldStage::Collide);
  // 3. rigid: systems only, for now
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
  write_particle_poses();
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
  for (const auto& s : systems_) h = s->hash(h);
  return h;
}

void World::draw(DebugDraw& draw, const DrawFlags& flags) const {
  // colliders (shapes, bounds), forcers, particles, then every system
  for (const Collider& c : world_colliders_) c.draw(draw, colors::grey, flags);
  for (const Forcer& f : world_forcers_) f.draw(draw, colors::cyan, flags);
  particles_.draw(draw, flags, particles_.size() <= 2000);
  // the entities' distance constraints
  if (flags.constraints)
    for (const ConstraintEntry& c : constraints_) {
      const ParticleId pa = records_[c.owner.index].particle, pb = records_[c.def.other.index].particle;
      if (particles_.valid(pa) && particles_.valid(pb)) draw.line(particles_.position(pa), particles_.position(pb), colors::yellow);
    }
  for (const auto& s : systems_) s->draw(*this, draw, flags);
}

}  // namespace pba
