// pba world (workbook 4.1): the entity-component model that ties the physics together.
//
// An entity is a generation-checked handle (EntityId) with a name and a pose. Components
// attach behaviour to it: Particle, RigidBody, Collider, Forcer, Emitter, Kinematic and
// Constraint; soft bodies and IK are WorldSystems (see add_system).
// Components are plain data stored contiguously by the system that steps them (particles
// in the ParticleSystem's arrays, colliders and forcers in the World's dense arrays); the
// World wires entities to systems and never dispatches per entity.
//
// Each tick runs named stages in this documented order and times each (Box2D's
// b2Profile; WorldProfile::stages). A stage runs the World's own work for it, then the
// systems registered at it (WorldSystem::stage()), in the order they were added:
//   1. kinematic    scripted paths, motors and thrusters move their entities (and write
//                   their poses)
//   2. collide      collider, forcer and emitter poses follow their entities; the
//                   collision world of the tick is built (validated and flattened once)
//   3. rigid        kinematic bodies get the velocities that take them to their entity's
//                   pose, the World's RigidBodySystem steps under gravity() (the static
//                   colliders of entities without a body are its static geometry), each
//                   body's entity gets its pose, and the bodies' shapes join the tick's
//                   collision world with their begin and end poses
//   4. particles    emit, forces + integration, swept collisions, recycling; particle
//                   entities without a kinematic get their particle's position as pose;
//                   then the tick's touch events (bodies and particle entities) and
//                   sensor events
//   5. soft         soft bodies (SoftSystem), against the tick's collision world
//   6. constraints  distance constraints between particle entities
//   7. post         everything else (the default stage of a WorldSystem)
// Gravity is the World's (WorldDef::gravity): every system reads World::gravity() each
// tick, so the particles' and every soft body's gravity follow it.
//
//   pba::World world({.stepper = {.fixed_dt = 1.0 / 120}});
//   auto ground = world.create_entity({.name = "ground"});
//   world.add_collider(ground, {.shape = {.type = pba::ShapeType::Plane}});
//   auto ball = world.create_entity({.name = "ball"});
//   world.add_particle(ball, {.position = {0, 1, 0}, .radius = 0.05});
//   world.advance(frame_seconds);   // as many fixed ticks as real time asks for
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pba/collide.h"
#include "pba/core.h"
#include "pba/draw.h"
#include "pba/handle.h"
#include "pba/particles.h"
#include "pba/rigid.h"
#include "pba/time.h"

namespace pba {

/// Tag for entity handles.
struct EntityTag {};
/// Generation-checked entity handle: index + generation. A handle kept after
/// destroy_entity() is stale and every World call rejects it with an Error.
using EntityId = Handle<EntityTag>;

/// Definition of an entity.
struct EntityDef {
  std::string name{};  ///< optional; used by find() and in error messages
  Pose pose{};         ///< initial pose (finite position, unit rotation)
};

/// A collision surface component: the shape in the entity's frame and its material.
/// The World turns it into a world-space Collider each tick from the entity's pose.
struct ColliderDef {
  ColliderShape shape{};       ///< shape in the entity frame
  SurfaceMaterial material{};  ///< restitution and friction
  /// A sensor pushes nothing (particles, soft and rigid bodies pass through it) and reports
  /// the entities whose rigid bodies or particles enter and leave it
  /// (World::sensor_enter_events(), World::sensor_leave_events()), and counts the emitters'
  /// particles inside it (World::sensor_counts()).
  bool sensor = false;
};

/// Two entities began touching in the last tick: a contact of their rigid bodies (or of a
/// body and a collider) that the solver pushed, or a particle entity's particle meeting a
/// collider's entity (a collider, or a shape of its rigid body) during the tick. `a` has
/// the smaller entity index.
struct TouchBeginEvent {
  EntityId a{}, b{};          ///< the two entities (a.index < b.index)
  Vec3 normal{0, 1, 0};       ///< unit contact normal from a to b
  Vec3 point{0, 0, 0};        ///< the deepest contact point, or the particle's on the surface at impact (world, m)
  double approach_speed = 0;  ///< how fast they closed along the normal before the contact (m/s, >= 0)
};
/// Two entities stopped touching in the last tick (`a` has the smaller entity index).
struct TouchEndEvent {
  EntityId a{}, b{};  ///< the two entities (a.index < b.index)
};
/// An entity (`visitor`) entered or left a sensor collider's entity (`sensor`) in the last
/// tick: some shape of its rigid body, or its particle's sphere, overlaps the sensor's shape.
struct SensorEvent {
  EntityId sensor{}, visitor{};  ///< the sensor collider's entity and the visiting entity
};
/// How many live particles of an emitter's entity (`emitter`) overlap a sensor collider's
/// entity (`sensor`) at the end of the last tick (emitted particles are counted, not
/// reported one by one).
struct SensorCount {
  EntityId sensor{}, emitter{};  ///< the sensor collider's entity and the emitter's entity
  std::size_t inside = 0;        ///< particles whose sphere overlaps the sensor's shape (> 0)
};

/// How a Kinematic component moves its entity. Paths are closed-form functions of the
/// time since the component was added, so they never drift.
enum class PathType : std::uint8_t {
  Linear,     ///< p(t) = p0 + velocity t
  Circular,   ///< a circle of `radius` about `center` and `axis` at `angular_speed`
  Waypoints,  ///< straight segments through `waypoints` at `speed`, looping or stopping
  Motor,      ///< stays at p0 and spins at `spin` (a motor); spin applies to every path
  Thruster,   ///< constant acceleration: p(t) = p0 + velocity t + thrust t^2 / 2
};

/// A Kinematic component: drives its entity along a scripted path, by a motor or by a
/// thruster. Moving colliders, forcers and emitters are entities with one of these.
struct KinematicDef {
  PathType path = PathType::Linear;  ///< which motion
  Vec3 velocity{0, 0, 0};  ///< Linear: velocity (m/s); Thruster: initial velocity (m/s)
  Vec3 center{0, 0, 0};    ///< Circular: centre (m)
  Vec3 axis{0, 1, 0};      ///< Circular: axis of the circle (non-zero)
  double radius = 1;       ///< Circular: radius (m), finite and > 0
  double angular_speed = 1;  ///< Circular: rad/s, finite
  double phase = 0;        ///< Circular: starting angle (rad)
  std::vector<Vec3> waypoints{};  ///< Waypoints: at least 2 points (m)
  double speed = 1;        ///< Waypoints: speed along the path (m/s), finite and > 0
  bool loop = true;        ///< Waypoints: return to the first point and repeat; else stop at the last
  Vec3 spin{0, 0, 0};      ///< angular velocity (rad/s, world axes) added to any path
  Vec3 thrust{0, 0, 0};    ///< Thruster: acceleration (m/s^2)

  /// Throws Error naming `where` and the bad field.
  void validate(std::string_view where) const;
};

/// A Constraint component (placeholder until the springs issue): keeps this entity's
/// particle at `rest_length` from `other`'s particle by projecting both positions after
/// the particle step (mass-weighted), correcting velocities by the displacement / dt.
struct ConstraintDef {
  EntityId other{};          ///< the other end: an entity with a Particle component
  double rest_length = -1; ///< target distance (m); negative means "the distance when added"
  double stiffness = 1;    ///< fraction of the error removed per tick, in [0, 1]
};

/// The stages of a World tick, in the order they run (see the top of this header).
enum class WorldStage : std::uint8_t {
  Kinematic,    ///< scripted paths, motors, thrusters
  Collide,      ///< poses of colliders, forcers, emitters; the collision world of the tick
  Rigid,        ///< rigid bodies, then their shapes join the tick's collision world
  Particles,    ///< the particle system
  Soft,         ///< soft bodies
  Constraints,  ///< distance constraints
  Post,         ///< anything after the physics (the default)
};
/// Number of stages.
inline constexpr std::size_t kWorldStageCount = 7;
/// Lower-case name of a stage ("kinematic", "collide", ...), for profiles and messages.
std::string_view to_string(WorldStage s);

/// Tag for collider component handles.
struct ColliderTag {};
/// Generation-checked handle to a Collider component (World::add_collider).
using ColliderId = Handle<ColliderTag>;
/// Tag for forcer component handles.
struct ForcerTag {};
/// Generation-checked handle to a Forcer component (World::add_forcer).
using ForcerId = Handle<ForcerTag>;
/// Tag for kinematic component handles.
struct KinematicTag {};
/// Generation-checked handle to a Kinematic component (World::add_kinematic).
using KinematicId = Handle<KinematicTag>;
/// Tag for constraint component handles.
struct ConstraintTag {};
/// Generation-checked handle to a Constraint component (World::add_constraint).
using ConstraintId = Handle<ConstraintTag>;

/// Wall-clock seconds per phase of the last tick (b2Profile style).
struct WorldProfile {
  double stages[kWorldStageCount] = {};  ///< each stage, its systems included, indexed by WorldStage
  double kinematic = 0;    ///< scripted paths
  double sync = 0;         ///< collider, forcer and emitter poses (validated; the collision world: rigid stage)
  double emit = 0;         ///< particle emission
  double integrate = 0;    ///< forces and integration (fused with collisions for semi-implicit Euler)
  double collide = 0;      ///< collisions (generic integrator path only)
  double recycle = 0;      ///< removing dead particles
  double constraints = 0;  ///< constraint projection
  double systems = 0;      ///< extension systems (all stages)
  double total = 0;        ///< the whole tick
};

/// How often the World has made its derived collision data again, since it was made: counts
/// of work, not time, so a test can assert that a change or a tick does O(1) rebuilds (a
/// wall-clock ratio flaked on a loaded machine).
struct WorldBuildCounts {
  /// The collision world cleared and filled again (once a tick; once on the first read after
  /// a change between ticks).
  std::uint64_t collision_builds = 0;
  /// The bodies' shapes made again as colliders (body_colliders()), every body each time.
  std::uint64_t body_collider_builds = 0;
  /// Colliders made in those builds, summed (the work of a build is its collider count).
  std::uint64_t body_colliders_made = 0;
};

class World;

/// Extension point for the modules (soft bodies, rigid bodies, IK): a system with its own
/// contiguous component storage, stepped once per tick at its stage. One virtual call
/// per system per tick, never per entity.
class WorldSystem {
 public:
  virtual ~WorldSystem() = default;
  /// A short name for profiles and errors.
  virtual std::string_view name() const = 0;
  /// The stage the system runs at (after the World's own work for that stage).
  virtual WorldStage stage() const { return WorldStage::Post; }
  /// Advances the system from t to t + dt (s).
  virtual void step(World& world, double t, double dt) = 0;
  /// Removes whatever the system keeps for an entity that is being destroyed.
  virtual void on_destroy(EntityId) {}
  /// Draws the system.
  virtual void draw(const World&, DebugDraw&, const DrawFlags&) const {}
  /// Mixes the system's state into a hash.
  virtual std::uint64_t hash(std::uint64_t seed) const { return seed; }
};

/// Settings of a World.
struct WorldDef {
  StepperSettings stepper{};      ///< time stepping (fixed_dt is the tick)
  /// Gravitational acceleration (m/s^2), finite and within a float's range (|component| <=
  /// 3.4e38): the World's, read by every system each tick (it replaces
  /// particles.forces.gravity and each soft body's forces.gravity).
  Vec3 gravity{0, -9.81, 0};
  ParticleSystemDef particles{};  ///< integrator, drag, wind, capacity (forces.gravity: see gravity)
  /// The rigid bodies: solver, substeps, iterations, sleep and the other contact settings,
  /// and the bodies reserved up front (the World's gravity replaces any other).
  RigidSystemDef rigid{};
};

/// Colours of the rigid bodies in World::draw_rigid_bodies().
struct RigidBodyColors {
  Color awake = colors::orange;         ///< dynamic, awake
  Color asleep = Color::hex(0x8c3d0b);  ///< dynamic, asleep
  Color kinematic = colors::grey;       ///< kinematic
  Color fixed = colors::grey;           ///< static
};

/// The entity-component world. Movable, not copyable. Not thread-safe.
class World {
 public:
  /// Validates `def` (throws Error naming the bad field).
  explicit World(const WorldDef& def = {});
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // ---- entities ----

  /// Creates an entity (validates the pose).
  EntityId create_entity(const EntityDef& def = {});
  /// Destroys an entity and all its components (its particle, emitter... go too).
  void destroy_entity(EntityId e);
  /// True when `e` names a live entity.
  bool valid(EntityId e) const { return entities_.valid(e); }
  /// Live entities.
  std::size_t entity_count() const { return entities_.size(); }
  /// The first live entity with this name, or the null handle.
  EntityId find(std::string_view name) const;
  /// The entity's name.
  const std::string& name(EntityId e) const;
  /// The entity's pose: its particle's position for particle entities.
  Pose pose(EntityId e) const;
  /// Moves an entity (and its particle; restarts position Verlet's history).
  void set_pose(EntityId e, const Pose& pose);
  /// The entity's linear velocity (m/s): its particle's, or its kinematic path's.
  Vec3 velocity(EntityId e) const;

  // ---- components (one of each kind per entity; each throws Error for a stale handle,
  //      a duplicate component or bad data, naming the entity) ----

  /// Gives the entity a particle; `def.position` is taken relative to the entity pose.
  /// Refused on an entity with a rigid body (both would move it).
  ParticleId add_particle(EntityId e, const ParticleDef& def);
  /// Makes the entity a collision surface. A plane or mesh (not a sensor) on an entity with
  /// a Kinematic is refused once the World has a dynamic rigid body (see add_kinematic).
  ColliderId add_collider(EntityId e, const ColliderDef& def);
  /// Makes the entity a Forcer volume; `def.pose` is relative to the entity pose.
  ForcerId add_forcer(EntityId e, const Forcer& def);
  /// Makes the entity an emitter; `def.pose` is relative to the entity pose.
  EmitterId add_emitter(EntityId e, const EmitterDef& def);
  /// Drives the entity by a path, motor or thruster, from the current time. The entity's
  /// rigid body, if it has one, must be kinematic and at rest: a static or dynamic body, or a
  /// kinematic one with a velocity of its own (the path sets it), is refused, naming the
  /// entity (and the velocity). A plane or mesh collider (not a sensor) on a path jumps among
  /// the rigid bodies with no speed, carrying and pushing none, so it is refused beside a
  /// dynamic rigid body, naming both, by whichever of add_collider, add_kinematic and
  /// add_rigid_body completes the pair (give a moving floor a box or hull collider);
  /// particles and soft bodies ride it.
  KinematicId add_kinematic(EntityId e, const KinematicDef& def);
  /// Constrains the entity's particle to another particle entity.
  ConstraintId add_constraint(EntityId e, const ConstraintDef& def);
  /// Gives the entity a rigid body in the World's RigidBodySystem; `def.pose` is relative
  /// to the entity pose (the body starts at entity pose * def.pose; from then on the
  /// entity's pose is the body's). An unnamed body takes the entity's name. A Kinematic
  /// component drives only a kinematic body, so a static or dynamic body on an entity with
  /// one is refused, and so is a body on an entity with a particle (both would move it), or
  /// a body with velocities of its own on an entity with a Kinematic (the path sets them),
  /// and a dynamic body in a World with a plane or mesh collider on a Kinematic path (see
  /// add_kinematic). Errors name the entity and the field.
  RigidBodyId add_rigid_body(EntityId e, const RigidBodyDef& def);

  /// True when the handle names a live component (false once its entity is destroyed).
  bool valid(ColliderId id) const { return collider_ids_.valid(id); }
  bool valid(ForcerId id) const { return forcer_ids_.valid(id); }          ///< see valid(ColliderId)
  bool valid(KinematicId id) const { return kinematic_ids_.valid(id); }    ///< see valid(ColliderId)
  bool valid(ConstraintId id) const { return constraint_ids_.valid(id); }  ///< see valid(ColliderId)
  /// True when the handle names a live rigid body that belongs to an entity of this World.
  bool valid(RigidBodyId id) const;
  /// The entity's collider handle, or the null handle.
  ColliderId collider_id(EntityId e) const;
  /// The entity's forcer handle, or the null handle.
  ForcerId forcer_id(EntityId e) const;
  /// The entity's kinematic handle, or the null handle.
  KinematicId kinematic_id(EntityId e) const;
  /// The entity's constraint handle, or the null handle.
  ConstraintId constraint_id(EntityId e) const;
  /// The entity's rigid body handle, or the null handle.
  RigidBodyId rigid_body_id(EntityId e) const;
  /// The entity a component belongs to (throws Error for a stale handle).
  EntityId owner(ColliderId id) const;
  EntityId owner(ForcerId id) const;       ///< see owner(ColliderId)
  EntityId owner(KinematicId id) const;    ///< see owner(ColliderId)
  EntityId owner(ConstraintId id) const;   ///< see owner(ColliderId)
  EntityId owner(RigidBodyId id) const;    ///< see owner(ColliderId)

  /// The entity's particle handle, or the null handle.
  ParticleId particle(EntityId e) const;
  /// The entity's emitter handle, or the null handle.
  EmitterId emitter(EntityId e) const;
  /// The entity's collider definition, changeable between ticks (throws if it has none);
  /// the next tick checks it (a sensor's too) and refuses a bad field by name before any
  /// body moves.
  ColliderDef& collider(EntityId e);
  /// The entity's forcer definition, changeable between ticks (throws if it has none); the
  /// next tick checks every field and refuses a bad one by name before anything moves.
  Forcer& forcer(EntityId e);
  /// The entity's kinematic definition, changeable between ticks (throws if it has none).
  KinematicDef& kinematic(EntityId e);

  /// Gravity (m/s^2), read by every system each tick.
  const Vec3& gravity() const { return gravity_; }
  /// Changes gravity from the next tick on (finite, |component| <= 3.4e38; throws Error
  /// naming the value); the rigid bodies asleep under the old gravity wake at that tick.
  void set_gravity(const Vec3& g);

  /// The particle system (particles, emitters, forces, integrator).
  ParticleSystem& particles() { return particles_; }
  /// The particle system.
  const ParticleSystem& particles() const { return particles_; }
  /// The rigid bodies: the entities' bodies and the static (or kinematic) bodies that
  /// mirror the colliders of entities without a body. Read anything, apply forces and
  /// impulses, change settings(); create and destroy bodies through the World
  /// (add_rigid_body, destroy_entity), which keeps the entities in step.
  RigidBodySystem& rigid() { return rigid_; }
  /// The rigid bodies.
  const RigidBodySystem& rigid() const { return rigid_; }
  /// The entities' rigid-body shapes as world-space colliders (begin and end poses of the
  /// last tick, velocities at the shape origins; every shape type), as
  /// they joined the tick's collision world after the rigid stage. Refreshed when a body is
  /// added, moved or destroyed between ticks (then begin = end), on the first read after it.
  std::span<const Collider> body_colliders() const;
  /// World-space colliders of the last tick (or of now, before the first).
  std::span<const Collider> colliders() const { return world_colliders_; }
  /// The collision world of the last tick: its colliders, then the bodies' shapes
  /// (body_colliders()), with their owners (entity indices) and flat forms, which
  /// particles and soft bodies query.
  const CollisionWorld& collision() const { return collision_; }
  /// World-space forcers of the last tick.
  std::span<const Forcer> forcers() const { return world_forcers_; }

  /// Adds an extension system (stepped at its stage(), after the systems added before it).
  void add_system(std::unique_ptr<WorldSystem> system);
  /// The first extension system whose name() is `name`, or nullptr.
  WorldSystem* find_system(std::string_view name);
  /// The first extension system whose name() is `name`, or nullptr.
  const WorldSystem* find_system(std::string_view name) const;

  // ---- stepping ----

  /// The time stepper (settings, totals).
  TimeStepper& stepper() { return stepper_; }
  /// Advances by one frame of real time: as many ticks as the stepper's strategy asks.
  FrameStats advance(double frame_seconds);
  /// Exactly one tick of fixed_dt (TimeStepper::single_step with the fixed strategy).
  void step();
  /// One tick from t to t + dt (s; t finite, dt finite and > 0, else an Error naming it and
  /// the world is left as it was): the stages in their order. advance() and step() call it.
  /// Throws Error if the state becomes non-finite (which particle or which body's entity,
  /// when); the world then refuses to tick again and repeats that message.
  void tick(double t, double dt);
  /// Simulated time (s) of the state.
  double time() const { return time_; }
  /// Ticks run.
  long long ticks() const { return ticks_; }
  /// Timings of the last tick.
  const WorldProfile& profile() const { return profile_; }
  /// How often the collision world and the bodies' colliders were made, since construction.
  const WorldBuildCounts& build_counts() const { return build_counts_; }
  /// Entity pairs that began touching in the last tick, in entity-index order: rigid
  /// contacts the solver pushed (between bodies or a body and a collider), and particle
  /// entities whose particle met a collider's entity during the tick (at the impact, so a
  /// bounce inside one tick counts; resting on it keeps touching). Emitted particles have
  /// no entity and make none. Needs particles().record_contacts() (on by default here).
  /// The handles are the entities' when the events were made (stage 4): an entity destroyed
  /// since, by a later stage's system in the same tick or by the caller before reading, stays
  /// named here by its now stale handle (as Box2D's event ids may be). Check valid(): every
  /// World call refuses a stale handle with an Error, and an entity that took its slot since
  /// has a new generation, so an event never names it. The same holds for the end and
  /// sensor events.
  std::span<const TouchBeginEvent> touch_begin_events() const { return touch_begin_; }
  /// Entity pairs that stopped touching in the last tick: a particle entity after a tick in
  /// which its particle met none of the entity's colliders (a pair stays touching while its
  /// bodies sleep; a destroyed entity's pairs end silently).
  std::span<const TouchEndEvent> touch_end_events() const { return touch_end_; }
  /// Entities (rigid bodies, particles) that entered a sensor collider in the last tick.
  std::span<const SensorEvent> sensor_enter_events() const { return sensor_enter_; }
  /// Entities (rigid bodies, particles) that left a sensor collider in the last tick.
  std::span<const SensorEvent> sensor_leave_events() const { return sensor_leave_; }
  /// Per sensor and emitter, the emitter's particles inside the sensor after the last tick
  /// (pairs with none are left out), in sensor then emitter entity order.
  std::span<const SensorCount> sensor_counts() const { return sensor_counts_; }
  /// Hash of the particle state, the kinematic entity poses, the rigid bodies (once an
  /// entity has one) and every extension system.
  std::uint64_t hash() const;
  /// Draws what `flags` select: colliders (shapes, aabbs), the rigid bodies' shapes
  /// (dynamic orange, asleep darker, kinematic and static grey), forcers, particles, every
  /// system (soft bodies: particles, constraints) and the entities' constraints.
  void draw(DebugDraw& draw, const DrawFlags& flags = {}) const;
  /// Draws the entities' rigid bodies (not the colliders' stand-ins) at their poses now:
  /// each shape as the flags select (shapes, aabbs; planes but horizontal ones), coloured by
  /// type and sleep (entities in turn at 100, 88 and 76% of the colour, so stacked bodies read
  /// apart), and the last tick's contact points and normals (contacts, normals).
  void draw_rigid_bodies(DebugDraw& draw, const DrawFlags& flags = {}, const RigidBodyColors& colors = {}) const;

  // ---- queries ----

  /// Ray casts, shape casts, overlap and distance queries (collide/query.h) over the
  /// colliders of the last tick, collision(), as the World stands now: a body or collider
  /// added, moved (World::set_pose) or destroyed since the tick is where it is now (before
  /// the first tick, the colliders and bodies as added); a hit's owner is the entity's index.
  /// Built on the first call after the collision world changed (the same collider count
  /// refits the tree and does not allocate); not thread-safe, the queries on the result are.
  const QueryWorld& queries();

 private:
  // collision_ made again from the colliders and the bodies' shapes as they are now (after a
  // change between ticks: queries() must not report a destroyed entity or a moved body's old pose)
  void rebuild_collision();
  // collision_ cleared and given the colliders (sensors push nothing): the tick's collision
  // world starts so (step_rigid), and so does rebuild_collision
  void collide_colliders();
  // every collider validated, sensors too, an Error naming its entity (sync, before the
  // rigid stage moves anything; collide_colliders)
  void validate_colliders();
  // whether an extension system is registered at `stage`
  bool systems_at(WorldStage stage) const;
  bool collision_stale_ = true;            // the World changed since collision_ was made
  QueryWorld queries_;                     // queries(), built from collision_ when stale
  std::uint64_t queries_revision_ = ~0ull;  // collision_.revision() it was built from
  struct EntityRecord {
    std::string name;
    Pose pose;
    Vec3 velocity{0, 0, 0};
    Vec3 angular_velocity{0, 0, 0};
    ParticleId particle;
    RigidBodyId body;
    EmitterId emitter;
    Pose emitter_local;
    std::uint32_t collider = kNone, forcer = kNone, kinematic = kNone, constraint = kNone;
  };
  struct ColliderEntry {
    EntityId owner;
    ColliderDef def;
    ColliderId id;
    // the body that stands for the collider in the RigidBodySystem (entities without a
    // body), and what it was made from
    RigidBodyId mirror{};
    BodyType mirror_type = BodyType::Static;
    ColliderDef mirrored{};
    Pose mirrored_pose{};
  };
  struct ForcerEntry {
    EntityId owner;
    Forcer def;  // pose relative to the entity
    ForcerId id;
  };
  struct KinematicEntry {
    EntityId owner;
    KinematicId id;
    KinematicDef def;
    double start = 0;  // time it was added (s)
    Pose start_pose;
    double length = 0;  // waypoints: total path length (m)
  };
  struct ConstraintEntry {
    EntityId owner;
    ConstraintDef def;
    ConstraintId id;
  };
  static constexpr std::uint32_t kNone = 0xffffffffu;

  EntityRecord& record(EntityId e, std::string_view where);
  const EntityRecord& record(EntityId e, std::string_view where) const;
  std::string describe(EntityId e) const;
  void run_kinematics(double t, double dt);
  void sync(double t, double dt);
  void solve_constraints(double dt);
  void sync_mirrors(double t, double dt);
  void destroy_mirror(ColliderEntry& c);
  void drive_body(EntityId owner, std::string_view what, RigidBodyId id, const Pose& target, double t, double dt);
  void step_rigid(double t, double dt);
  // the bodies' shapes as colliders: for the tick (swept from body_begin_), or as they are
  // now (a change between ticks; mutable: body_colliders() makes them on the first read)
  void refresh_body_colliders(bool tick) const;
  // a body or collider changed between ticks: the bodies' colliders and the collision world
  // are made again when next read (making them at each change cost O(n) per body added, and
  // a scene of 20,000 bodies took 24 s to load)
  void changed_between_ticks() { body_colliders_stale_ = true, collision_stale_ = true; }
  void update_rigid_touches();
  void update_particle_touches();
  void update_touch_events();
  void reserve_touch_sets();
  void update_sensor_events();
  void forget_pairs(EntityId e);
  EntityId body_entity(RigidBodyId id) const;
  void pin_kinematic_particles();
  void write_particle_poses();
  void run_systems(WorldStage stage, double t, double dt);
  template <class Entry>
  void remove_dense(std::vector<Entry>& v, std::uint32_t EntityRecord::*member, std::uint32_t i);

  StepperSettings settings_;
  Vec3 gravity_{0, -9.81, 0};
  TimeStepper stepper_;
  ParticleSystem particles_;
  HandlePool<EntityTag> entities_;
  std::vector<EntityRecord> records_;  // by handle slot
  std::vector<ColliderEntry> colliders_;
  std::vector<Collider> world_colliders_;  // parallel to colliders_
  CollisionWorld collision_;               // world_colliders_ of this tick, for the clients
  std::vector<ForcerEntry> forcers_;
  std::vector<Forcer> world_forcers_;      // parallel to forcers_
  std::vector<KinematicEntry> kinematics_;
  std::vector<ConstraintEntry> constraints_;
  std::vector<std::unique_ptr<WorldSystem>> systems_;
  RigidBodySystem rigid_;
  std::vector<EntityId> body_owner_;        // by rigid-body handle slot: the entity (null for mirrors)
  // entities that hold a body handle: their bodies, and those destroyed in rigid() directly
  // (the World cannot see that; counted until the entity gets a new body or is destroyed, so
  // the count, and the touch sets' room it sizes, stay bounded by the entities)
  std::size_t entity_bodies_ = 0;
  std::vector<Pose> body_begin_;            // by dense body index: the pose at the start of the tick
  mutable std::vector<Collider> body_colliders_;    // the entities' body shapes this tick
  mutable std::vector<std::uint32_t> body_collider_owner_;  // parallel: the entity index
  mutable bool body_colliders_stale_ = false;  // a body changed since they were made
  mutable WorldBuildCounts build_counts_;   // build_counts() (body_colliders() counts its builds)
  std::vector<EntityId> mirror_owner_;      // by rigid-body handle slot: the collider's entity of a stand-in
  // touching entity pairs and sensor overlaps, as sorted keys (smaller index << 32 | larger,
  // sensor << 32 | visitor), this tick's and last tick's, and the events between them
  struct TouchRecord {
    std::uint64_t key;
    Vec3 normal, point;
    double approach;
  };
  std::vector<TouchRecord> touching_, touching_prev_;  // the bodies' pairs (with sleeping ones kept)
  std::vector<TouchRecord> particle_touching_;        // the particle entities' pairs
  std::vector<TouchRecord> touched_, touched_prev_;   // both, this tick and last: the events' sets
  std::size_t particle_entities_added_ = 0;           // particles added to entities (room in the sets)
  std::vector<std::uint64_t> sensing_, sensing_prev_;
  std::vector<TouchBeginEvent> touch_begin_;
  std::vector<TouchEndEvent> touch_end_;
  std::vector<SensorEvent> sensor_enter_, sensor_leave_;
  std::vector<SensorCount> sensor_counts_;
  std::vector<std::size_t> inside_by_slot_;  // one sensor's count per emitter slot
  // component handles: a pool per kind and the owning entity of each handle slot (the
  // entity record holds the component's dense index)
  template <class Tag>
  struct ComponentIds {
    HandlePool<Tag> pool;
    std::vector<EntityId> owner;  // by handle slot
    bool valid(Handle<Tag> id) const { return pool.valid(id); }
    Handle<Tag> create(EntityId e) {
      const Handle<Tag> id = pool.create();
      if (owner.size() <= id.index) owner.resize(id.index + 1);
      owner[id.index] = e;
      return id;
    }
    EntityId owner_of(Handle<Tag> id, std::string_view where) const {
      pool.require(id, where);
      return owner[id.index];
    }
  };
  ComponentIds<ColliderTag> collider_ids_;
  ComponentIds<ForcerTag> forcer_ids_;
  ComponentIds<KinematicTag> kinematic_ids_;
  ComponentIds<ConstraintTag> constraint_ids_;
  double time_ = 0;
  long long ticks_ = 0;
  WorldProfile profile_;
  std::string failure_;
};

/// The pose a kinematic path gives at `t` seconds after it started from `start`, and its
/// linear velocity (m/s). `length` is the waypoint path length (0 to compute it).
Pose kinematic_pose(const KinematicDef& def, const Pose& start, double t, Vec3* velocity = nullptr,
                    double length = 0);

}  // namespace pba
