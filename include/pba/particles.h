// pba particles (workbook 4.2): objects with mass and size that move in every direction
// and never rotate. A ParticleSystem stores its particles as a structure of arrays of
// floats (x, y, z, vx, vy, vz, inverse mass, radius; birth and death times), steps them with any
// of the foundation's integrators under gravity, linear and quadratic drag, steady and
// gusting wind and Forcer volumes, collides them continuously with every collider shape
// (planes, spheres, boxes, capsules, convex hulls, triangle meshes and compounds; static
// or moving), emits them from emitters, and recycles the dead without allocating.
//
//   pba::ParticleSystem ps({.capacity = 4096});
//   ps.forces().quadratic_drag = 0.01;
//   auto ball = ps.create({.position = {0, 1, 0}, .mass = 0.1, .radius = 0.05});
//   pba::CollisionWorld colliders;
//   colliders.add(pba::Collider::plane({0, 1, 0}, 0.0, {.restitution = 0.8}));
//   ps.step(t, dt, colliders, {});
//
// Everything here is usable without a World (the benchmark and many tests do that); the
// World (pba/world.h) wires entities, kinematic paths and poses to it. See docs/particles.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pba/collide.h"
#include "pba/core.h"
#include "pba/draw.h"
#include "pba/handle.h"
#include "pba/integrate.h"

namespace pba {

// ---------------------------------------------------------------------------------------
// forcer volumes

/// What a Forcer volume does to the particles inside it.
enum class ForcerKind : std::uint8_t {
  Fan,        ///< a force along `direction` (a fan, or an air cannon with a pulse)
  Vortex,     ///< a force around the local +Y axis (tangential), plus an inward pull
  Attractor,  ///< a force toward the volume's centre (negative strength repels)
};

/// The volume a Forcer acts in, in its local frame centred at its pose.
enum class ForcerShape : std::uint8_t {
  Box,       ///< |x| <= half.x, |y| <= half.y, |z| <= half.z
  Cylinder,  ///< x^2 + z^2 <= radius^2 and |y| <= half_height (axis = local +Y)
  Sphere,    ///< |p| <= radius
};

/// A Forcer volume (workbook 4.1): adds a force to everything inside it. The force is in
/// newtons, so light particles are pushed harder (a = F / m).
struct Forcer {
  ForcerKind kind = ForcerKind::Fan;     ///< what it does
  ForcerShape shape = ForcerShape::Box;  ///< where it acts
  Pose pose{};                             ///< placement of the volume (world)
  Vec3 half_extents{0.5, 0.5, 0.5};      ///< Box: half extents (m), each > 0
  double radius = 0.5;                   ///< Cylinder and Sphere: radius (m), > 0
  double half_height = 0.5;              ///< Cylinder: half height along local +Y (m), > 0
  Vec3 direction{0, 1, 0};               ///< Fan: push direction in the local frame (normalised)
  double strength = 1.0;                 ///< force magnitude (N), finite; Vortex: tangential
  double pull = 0.0;                     ///< Vortex: inward radial force (N), finite
  double softening = 0.1;                ///< Attractor: inside this distance (m, > 0) the force fades linearly to 0
  double pulse_period = 0.0;             ///< air cannon: period (s, >= 0); 0 means always on
  double pulse_duration = 0.0;           ///< air cannon: on-time at the start of each period (s), in [0, period]

  /// Throws Error naming `where` and the bad field.
  void validate(std::string_view where) const;
  /// True when the forcer is on at time t (s).
  bool active(double t) const;
  /// The force (N) on a point p (m) at time t (s): zero outside the volume or when off.
  Vec3 force_at(const Vec3& p, double t) const;
  /// Draws the volume outline and its push direction (when flags.forcers).
  void draw(DebugDraw& draw, Color c, const DrawFlags& flags = {}) const;
};

// ---------------------------------------------------------------------------------------
// forces

/// Uniform wind: a steady velocity plus deterministic gusts from seeded value noise
/// (no rand()): each axis gets gust * n_k(t / gust_period), where n_k is a smooth (C2)
/// interpolation of hashed lattice values in [-1, 1]. The same seed gives the same gusts.
struct Wind {
  Vec3 velocity{0, 0, 0};  ///< steady wind (m/s), finite
  double gust = 0;         ///< gust amplitude per axis (m/s), finite and >= 0
  double gust_period = 1;  ///< time between independent gust values (s), finite and > 0
  std::uint32_t seed = 1;  ///< noise seed

  /// The air velocity (m/s) at time t (s).
  Vec3 at(double t) const;
};

/// The forces on every particle: gravity, drag relative to the wind, and wind gusts.
/// Drag force: F = -(linear_drag + quadratic_drag |u|) u with u = v - wind(t), so with
/// linear drag alone a particle relaxes to the wind with time constant tau = m / b.
struct Forces {
  Vec3 gravity{0, -9.81, 0};  ///< gravitational acceleration (m/s^2), finite
  double linear_drag = 0;     ///< b (kg/s), finite and >= 0 (Stokes drag)
  double quadratic_drag = 0;  ///< c (kg/m), finite and >= 0 (c = rho Cd A / 2 for a blunt body)
  Wind wind{};                  ///< the air's velocity

  /// Throws Error naming `where` and the bad field.
  void validate(std::string_view where) const;
};

/// Collision settings shared by all surfaces.
struct CollisionSettings {
  /// Approach speeds (m/s) below this bounce with restitution 0, so resting particles
  /// settle instead of jittering (Box2D's restitution threshold). Negative means
  /// automatic: 2 |gravity| dt, the speed gravity adds in two steps. Finite.
  double restitution_threshold = -1;
};

// ---------------------------------------------------------------------------------------
// particles and emitters

/// Tag for particle handles.
struct ParticleTag {};
/// Generation-checked handle to a tracked particle (one created with ParticleSystem::create).
using ParticleId = Handle<ParticleTag>;
/// Tag for emitter handles.
struct EmitterTag {};
/// Generation-checked handle to an emitter.
using EmitterId = Handle<EmitterTag>;

/// Lifetime that means "never dies".
inline constexpr double kForever = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------
// memory limits

/// Bytes one particle may take in a ParticleSystem, the figure every memory check counts:
/// an upper bound over every method in steady state (the columns, 88 B: eight hot floats,
/// birth and death times, two colours, owner and source, the generic path's gather
/// arrays; a handle, 12 B; the integrator's scratch, at most 132 B for position Verlet's
/// double state; 232 B in all). A tracked particle of a system that records contacts
/// (ParticleSystem::set_record_contacts, on in a World) has a contact record besides,
/// by handle slot, outside this figure.
inline constexpr std::size_t kParticleBytes = 256;
/// The default memory budget of one ParticleSystem (ParticleSystemDef::memory_budget):
/// 4 GiB, room for 2^24 (16.8 million) particles of kParticleBytes.
inline constexpr std::size_t kParticleMemoryBudget = std::size_t{4} << 30;

/// Throws Error "<where>: <count> particles would take <memory> (<kParticleBytes> B each),
/// over the particle system's memory budget of <budget> (ParticleSystemDef.memory_budget)"
/// followed by `hint`, when count * kParticleBytes > budget. `count` is a double so that
/// absurd counts (an emitter rate of 1e300) are reported, not wrapped.
void require_particle_memory(double count, std::size_t budget, std::string_view where, std::string_view hint = {});

struct EmitterDef;
/// Throws Error, as require_particle_memory does, when the particles `def` keeps alive
/// (EmitterDef::max_live()) do not fit `budget`: named `max_alive_field` when the cap
/// sets the count, `rate_field` otherwise (with the rate and lifetime in the message).
void require_emitter_memory(const EmitterDef& def, std::size_t budget, std::string_view rate_field,
                            std::string_view max_alive_field);

/// Definition of one particle. Start from the defaults and change what you need.
/// The fastest a particle may be given (m/s), and the strongest wind: the drag squares the
/// speed relative to the wind in float, which overflows above sqrt(3.4e38) = 1.8e19 m/s, so
/// a velocity and the wind each stay within half of that.
inline constexpr double kMaxParticleSpeed = 9e18;

/// Throws Error "<where>: a speed of 1e+20 m/s is above the particles' limit of 9e+18 m/s
/// (...)" unless `speed` (m/s) is at most kMaxParticleSpeed.
void require_particle_speed(double speed, std::string_view where);

/// Positions, velocities and radii are stored as float and the mass as its float inverse,
/// so each must also fit a float (|x| <= 3.4e38, mass in [2.94e-39, 8.5e37] kg); speeds are
/// at most kMaxParticleSpeed.
struct ParticleDef {
  Vec3 position{0, 0, 0};  ///< initial position (m), finite as a float
  Vec3 velocity{0, 0, 0};  ///< initial velocity (m/s), |velocity| <= kMaxParticleSpeed
  double mass = 1.0;       ///< mass (kg), finite and > 0, 1 / mass a normal float
  double radius = 0.05;    ///< radius (m), finite and > 0 (as a float too); collisions keep the sphere outside surfaces
  double lifetime = kForever;  ///< seconds until it dies (> 0; kForever for immortal)
  Color color = colors::white;  ///< colour at birth
  Color end_color = colors::white;  ///< colour at the end of its life (mortal particles)

  /// Throws Error "<where>.mass: must be finite and > 0, got -1" and so on.
  void validate(std::string_view where) const;
};

/// Definition of an emitter: a point that emits particles into a cone.
struct EmitterDef {
  Pose pose{};                    ///< placement; emission is along the local `direction`
  Vec3 direction{0, 1, 0};      ///< cone axis in the local frame (normalised), non-zero
  double spread = 0.3;          ///< cone half-angle (rad), in [0, pi]
  double speed = 5.0;           ///< mean launch speed (m/s), finite and >= 0
  double speed_jitter = 0.1;    ///< speeds are uniform in speed * [1 - j, 1 + j]; j in [0, 1]
  double rate = 100.0;          ///< particles per second, finite and >= 0 (fractions carry over)
  double lifetime = 2.0;        ///< particle lifetime (s), finite and > 0
  double lifetime_jitter = 0.0; ///< lifetimes uniform in lifetime * [1 - j, 1 + j]; j in [0, 1)
  double mass = 0.001;          ///< particle mass (kg), finite and > 0
  double radius = 0.01;         ///< particle radius (m), finite and > 0
  Color start_color = colors::yellow;  ///< colour at birth
  Color end_color = Color::rgb(0.3f, 0.3f, 0.3f, 0.0f);  ///< colour at death (linear blend over life)
  std::size_t max_alive = 0;    ///< stop emitting while this many of its particles live; 0 = no cap
  std::uint64_t seed = 1;       ///< random stream for directions, speeds and lifetimes
  bool enabled = true;          ///< emits only when enabled

  /// Throws Error naming `where` and the bad field, e.g. "emitter.rate: must be finite
  /// and >= 0, got -5". The position, speed * (1 + speed_jitter), mass and radius must
  /// fit the particles' float state (see ParticleDef).
  void validate(std::string_view where) const;
  /// The most particles this emitter keeps alive at once: rate * lifetime * (1 +
  /// lifetime_jitter), rounded up, or max_alive when that is set and smaller. A
  /// ParticleSystem refuses an emitter (Error naming `rate` or `max_alive` and the
  /// memory) whose count does not fit its memory budget, at add_emitter and at each step.
  /// Emission costs time in proportion to the particles emitted: those due while the
  /// emitter is at max_alive are skipped by arithmetic, without drawing from its stream.
  double max_live() const;
};

/// Settings of a ParticleSystem.
struct ParticleSystemDef {
  /// Particles reserved up front; growth past it allocates once. At most
  /// memory_budget / kParticleBytes (2^24 by default): a larger value is refused before
  /// anything is allocated (Error naming the field and the memory it would take).
  std::size_t capacity = 1024;
  Method method = Method::SemiImplicitEuler;  ///< integrator (any of pba::Method)
  Forces forces{};                ///< gravity, drag and wind
  CollisionSettings collision{};  ///< restitution threshold
  /// Bytes the system may take (>= kParticleBytes), counted as kParticleBytes per
  /// particle: the reserved capacity, an emitter's max_live() and growth are refused
  /// beyond it (Error naming the field and the memory). Raise it on a larger machine.
  std::size_t memory_budget = kParticleMemoryBudget;
};

/// One contact of a tracked particle with a collider during a step, as the collision code
/// met it: at the time of impact inside the step, before the response changed anything.
struct ParticleContact {
  std::uint32_t collider = 0;     ///< index of the collider in the step's CollisionWorld
  Vec3f normal{0, 1, 0};          ///< unit contact normal, out of the surface toward the particle
  Vec3f point{0, 0, 0};           ///< the contact point on the surface (m): centre at impact - radius * normal
  float approach_speed = 0;       ///< normal speed toward the surface at impact, relative to it (m/s, >= 0)
};

/// The most contacts recorded per tracked particle and step (ParticleSystem::contacts());
/// a particle that meets more colliders in one step keeps the first ones tested.
inline constexpr std::size_t kMaxParticleContacts = 4;

/// Wall-clock seconds per phase of the last ParticleSystem::step (b2Profile style).
struct ParticleProfile {
  double emit = 0;       ///< spawning from emitters
  double integrate = 0;  ///< forces, forcers and the integrator (and, fused, collisions)
  double collide = 0;    ///< collisions when not fused into integration
  double recycle = 0;    ///< ageing and removing dead particles
  double total = 0;      ///< the whole step
};

namespace detail {

/// Particles per block of the fused kernel and of its broad phase (a few KB of columns,
/// so one block's scratch stays in L1).
inline constexpr std::size_t kParticleBlock = 256;

/// The contacts one tracked particle made in one step (by handle slot; contact recording).
/// `step` is the number of the step that wrote them (ParticleSystem::steps() after it):
/// records of older steps are stale, so nothing is cleared between steps.
struct ContactLog {
  long long step = -1;     ///< the step these contacts belong to
  std::uint32_t count = 0;  ///< contacts recorded, <= kMaxParticleContacts
  ParticleContact contacts[kMaxParticleContacts];  ///< in the order the colliders were tested
};

/// What the broad phase knows about one block of kParticleBlock particles at the start of
/// a step: a box around their positions, a bound on their speeds, their largest radius and
/// inverse mass. A step tests the box, grown by how far any of them can move in the step,
/// against every collider's swept bounds; a block far from all of them skips the collision
/// code (and the copy of the start-of-step state that the swept tests need), and the grown
/// box becomes its bounds for the next step. A block that is near is measured again and,
/// if still near, takes the exact path. Any change to a particle outside the fused kernel
/// (spawn, removal, teleport, another integrator) clears `valid`.
struct BlockBounds {
  double lo[3] = {0, 0, 0};  ///< no position in the block has a smaller x, y, z (m)
  double hi[3] = {0, 0, 0};  ///< nor a larger one (m)
  double maxabs = 0;         ///< largest |coordinate| of that box (m), for rounding margins
  double speed = 0;          ///< upper bound on every |v| in the block (m/s), >= 0
  double radius = 0;         ///< largest radius in the block (m)
  double inv_mass = 0;       ///< largest inverse mass in the block (1/kg)
  bool valid = false;        ///< false: nothing known, the block takes the exact path
  bool measured = false;     ///< the box and speed were measured (not grown by a sweep)
};

/// A collider's reach over one step, in double, for the fused kernel's conservative far
/// test (kernels.cpp); the system keeps one per collider as scratch.
struct Reach {
  ShapeType type;
  double n[3], d;         // plane: at the end of the step (the exact test uses only that)
  double n1;              // plane: |n_x| + |n_y| + |n_z|
  double lo[3], hi[3];    // sphere, box: box around the centre's path (start and end)
  double radius;          // sphere radius, or the circumradius: |half extents| (box), hh + R (capsule),
                          // FlatShape::reach (hull, mesh, compound)
  double spin;            // all but spheres and planes: ||R1 - R0|| (Frobenius), bounds the turn of its frame
  double path;            // |c1 - c0|
  double maxabs;          // largest |coordinate| of the centre's path
};
/// The hot float columns of a ParticleSystem (x, y, z, vx, vy, vz, inverse mass,
/// radius) in one 64-byte aligned allocation. Consecutive columns are staggered (by 320 B
/// modulo 4 KB, and by 32 KB more when they are large; see column_stride in particles.cpp):
/// seven streams that sit at the same address modulo the page and the memory interleave
/// compete for the same cache sets and DRAM banks, and on the development machine that
/// halved the bandwidth of the step from main memory. Move-only; grows geometrically (the
/// only allocation).
class HotColumns {
 public:
  static constexpr int kCount = 8;  ///< number of columns
  HotColumns() = default;
  HotColumns(const HotColumns&) = delete;
  HotColumns& operator=(const HotColumns&) = delete;
  HotColumns(HotColumns&& o) noexcept;
  HotColumns& operator=(HotColumns&& o) noexcept;
  ~HotColumns();
  /// Column c in [0, kCount): capacity() floats, the first size() of them live.
  float* operator[](int c) { return base_ + static_cast<std::size_t>(c) * stride_; }
  /// Column c, read-only.
  const float* operator[](int c) const { return base_ + static_cast<std::size_t>(c) * stride_; }
  /// Live rows.
  std::size_t size() const { return size_; }
  /// Rows allocated.
  std::size_t capacity() const { return capacity_; }
  /// Makes room for at least `rows` rows, keeping the live ones (allocates when it grows).
  void reserve(std::size_t rows);
  /// Appends one uninitialised row (doubling the capacity when full) and returns its index.
  std::size_t push();
  /// Drops the last row.
  void pop() { --size_; }
  /// Drops every row, keeping the capacity.
  void clear() { size_ = 0; }

 private:
  float* base_ = nullptr;
  std::size_t size_ = 0, capacity_ = 0, stride_ = 0;  // stride in floats
};

}  // namespace detail

/// Particles in structure-of-arrays layout, stepped together.
///
/// Semi-implicit Euler (the default) runs a fused, vectorised kernel: forces, forcers,
/// the integrator and the collisions in one pass over memory in blocks that stay in L1.
/// A per-block broad phase (detail::BlockBounds) lets blocks that no collider can reach
/// in the step skip the collision code; it never changes a result bit.
/// Every other method gathers positions and velocities into glm::vec3 arrays, calls
/// Integrator<glm::vec3> with the same force code, and collides afterwards; both paths
/// give bit-identical results for semi-implicit Euler. Implicit Euler is solved particle
/// by particle (the forces here do not couple particles, so the Jacobian is block
/// diagonal and each 3x3 Newton solve is exact); its dense-size limit therefore never
/// applies here. Position Verlet keeps velocity in x - x_prev, so it runs on a double
/// copy of the positions and velocities that persists between steps (a drift a h^2 below
/// half a float step of x is kept, not rounded away; the columns get the rounded state);
/// after any collision, spawn, removal or write its history is restarted from the
/// columns' x and v (second order).
///
/// Steps never allocate once the arrays have grown to the live count (reserve with
/// `capacity`); the one exception is implicit Euler's fallback at a discontinuous force
/// (the integrator reports the failed Newton solve by throwing, which allocates).
/// Not thread-safe.
class ParticleSystem {
 public:
  /// Creates an empty system (validates `def`, throws Error naming the bad field).
  explicit ParticleSystem(const ParticleSystemDef& def = {});
  ParticleSystem(const ParticleSystem&) = default;
  ParticleSystem& operator=(const ParticleSystem&) = default;
  ParticleSystem(ParticleSystem&&) noexcept = default;
  /// Moves `o` in; a self-move keeps the system as it was.
  ParticleSystem& operator=(ParticleSystem&& o) noexcept;

  // ---- settings ----

  /// The integration method.
  Method method() const { return integ_.method(); }
  /// Switches the integration method (takes effect at the next step).
  void set_method(Method m);
  /// Gravity, drag and wind; change fields freely between steps (validated at step()).
  Forces& forces() { return forces_; }
  /// Gravity, drag and wind.
  const Forces& forces() const { return forces_; }
  /// Collision settings.
  CollisionSettings& collision() { return collision_; }

  // ---- particles ----

  /// The most particles the memory budget allows: memory_budget / kParticleBytes. A
  /// create(), spawn() or emission past it throws Error naming the budget.
  std::size_t max_particles() const { return max_particles_; }
  /// The memory budget (bytes, ParticleSystemDef::memory_budget).
  std::size_t memory_budget() const { return memory_budget_; }
  /// Adds a tracked particle and returns its handle (validates `def`; the Error names
  /// `where` and the field). Tracked particles keep their handle while they live.
  ParticleId create(const ParticleDef& def, std::string_view where = "ParticleDef");
  /// Removes a tracked particle (throws Error for a stale handle).
  void destroy(ParticleId id);
  /// True when `id` names a live particle.
  bool valid(ParticleId id) const { return ids_.valid(id); }
  /// The array index of a tracked particle now (indices move when others die).
  std::size_t index_of(ParticleId id) const;
  /// Adds an anonymous particle (no handle) and returns its index (validates `def`).
  std::size_t spawn(const ParticleDef& def, std::string_view where = "ParticleDef");
  /// Removes every particle; keeps the capacity, emitters and settings.
  void clear();

  /// Live particles.
  std::size_t size() const { return hot_.size(); }
  /// Reserved capacity in particles.
  std::size_t capacity() const { return hot_.capacity(); }
  /// Position of particle i (m). The accessors by index throw pba::Error naming the call, i and
  /// size() unless i < size().
  Vec3 position(std::size_t i) const {
    check_index(i, "ParticleSystem::position");
    return {hot_[kX][i], hot_[kY][i], hot_[kZ][i]};
  }
  /// Velocity of particle i (m/s).
  Vec3 velocity(std::size_t i) const {
    check_index(i, "ParticleSystem::velocity");
    return {hot_[kVX][i], hot_[kVY][i], hot_[kVZ][i]};
  }
  /// Position of a tracked particle (throws Error for a stale handle).
  Vec3 position(ParticleId id) const { return position(index_of(id)); }
  /// Velocity of a tracked particle (throws Error for a stale handle).
  Vec3 velocity(ParticleId id) const { return velocity(index_of(id)); }
  /// Mass of particle i (kg).
  double mass(std::size_t i) const {
    check_index(i, "ParticleSystem::mass");
    return 1.0 / static_cast<double>(hot_[kInvMass][i]);
  }
  /// Radius of particle i (m).
  double radius(std::size_t i) const {
    check_index(i, "ParticleSystem::radius");
    return hot_[kRadius][i];
  }
  /// Age of particle i (s) at the current time().
  double age(std::size_t i) const {
    check_index(i, "ParticleSystem::age");
    return time_ - birth_[i];
  }
  /// Lifetime of particle i (s; infinity for immortal particles).
  double lifetime(std::size_t i) const {
    check_index(i, "ParticleSystem::lifetime");
    return death_[i] - birth_[i];
  }
  /// Simulated time (s) at the end of the last step (or the start time of the next).
  double time() const { return time_; }
  /// Colour of particle i now: the birth colour blended toward the end colour over its life.
  Color color(std::size_t i) const;
  /// Teleports particle i (validated; restarts position Verlet's history).
  void set_position(std::size_t i, const Vec3& p);
  /// Sets the velocity of particle i (validated; restarts position Verlet's history).
  void set_velocity(std::size_t i, const Vec3& v);

  /// The SoA columns, read-only (for rendering and CSV output).
  std::span<const float> xs() const { return column(kX); }
  std::span<const float> ys() const { return column(kY); }    ///< y positions (m)
  std::span<const float> zs() const { return column(kZ); }    ///< z positions (m)
  std::span<const float> vxs() const { return column(kVX); }  ///< x velocities (m/s)
  std::span<const float> vys() const { return column(kVY); }  ///< y velocities (m/s)
  std::span<const float> vzs() const { return column(kVZ); }  ///< z velocities (m/s)
  /// Copies positions into `out` (size() elements) as vec3, e.g. for a vertex buffer.
  void copy_positions(std::span<Vec3f> out) const;

  // ---- emitters ----

  /// Adds an emitter (validates `def`; the Error names `where` and the field).
  EmitterId add_emitter(const EmitterDef& def, std::string_view where = "EmitterDef");
  /// Removes an emitter (its particles live on).
  void remove_emitter(EmitterId id);
  /// The emitter's definition, to change rate, speed, colours... between steps
  /// (re-validated at the next step).
  EmitterDef& emitter(EmitterId id);
  /// Moves an emitter (the world does this from its entity's pose each step).
  void set_emitter_pose(EmitterId id, const Pose& pose);
  /// Particles an emitter has emitted since it was added.
  long long emitted(EmitterId id) const;
  /// Live emitters.
  std::size_t emitter_count() const { return emitters_.size(); }
  /// The emitter at slot `slot` (0 .. emitter_count() - 1; slots shift when one is removed).
  /// Throws pba::Error naming the slot and emitter_count() beyond them.
  EmitterId emitter_at(std::size_t slot) const;
  /// Where particle i came from: its emitter's slot + 1, or 0 for a particle created by itself.
  std::uint32_t source(std::size_t i) const {
    check_index(i, "ParticleSystem::source");
    return source_[i];
  }

  // ---- stepping ----

  /// Advances every particle from time t to t + dt (s, finite and > 0): emit, forces and
  /// integration, collisions with `colliders`, ageing and recycling. `forcers` push the
  /// particles inside them. Throws Error if the state becomes non-finite, naming the
  /// particle, the time and the step; the state is left as it was computed.
  void step(double t, double dt, const CollisionWorld& colliders, std::span<const Forcer> forcers);
  /// The same step with the colliders given as a span (validated each step, an Error
  /// names colliders[i]; they fill a CollisionWorld kept by the system, so this does not
  /// allocate in steady state either).
  void step(double t, double dt, std::span<const Collider> colliders, std::span<const Forcer> forcers);
  /// The same step with a braced list of colliders (`{}` for none).
  void step(double t, double dt, std::initializer_list<Collider> colliders, std::span<const Forcer> forcers) {
    step(t, dt, std::span<const Collider>(colliders.begin(), colliders.size()), forcers);
  }

  /// Steps taken.
  long long steps() const { return steps_; }
  /// Implicit Euler only: particles whose Newton solve failed (at a discontinuous force,
  /// such as a forcer's edge) and took a semi-implicit Euler step instead, since creation.
  long long newton_fallbacks() const { return newton_fallbacks_; }
  /// Collision responses in the last step.
  std::size_t contacts() const { return contacts_; }
  /// Switches contact recording on or off (off by default; a World turns it on for its
  /// particle entities' touch events). On, every tracked particle (one made by create())
  /// keeps the colliders it met in each step, read with contacts(ParticleId); anonymous
  /// (emitted or spawned) particles record nothing. The kernels write a record only at an
  /// impact, never allocate for it, and the physics (every bit) is the same either way.
  /// The records take sizeof(detail::ContactLog) (144 B) per tracked-particle handle slot,
  /// allocated with the handle; they are not counted in kParticleBytes.
  void set_record_contacts(bool on);
  /// True when contact recording is on.
  bool record_contacts() const { return record_contacts_; }
  /// The contacts tracked particle `id` made in the last step (recording on), at most
  /// kMaxParticleContacts, in the order the colliders were tested (triangle meshes last):
  /// one per collider whose surface its sphere met during the step (an impact, a resting
  /// or sliding contact, or a push out of a shape it started in). Empty when it met none,
  /// when recording is off, or before the first step. Throws Error for a stale handle.
  std::span<const ParticleContact> contacts(ParticleId id) const;
  /// Switches the fused kernel's per-block broad phase on (the default) or off. Off, every
  /// collider is tested against every particle; the results are bit-identical either way
  /// (the tests compare them; the benchmark measures the difference).
  void set_broad_phase(bool on) { broad_phase_ = on; }
  /// True when the broad phase is on.
  bool broad_phase() const { return broad_phase_; }
  /// Blocks of detail::kParticleBlock particles that ran the exact collision path in the
  /// last fused step (the others were skipped by the broad phase, or there were no
  /// colliders); in [0, ceil(size() / kParticleBlock)].
  std::size_t exact_blocks() const { return exact_blocks_; }
  /// Timings of the last step.
  const ParticleProfile& profile() const { return profile_; }
  /// 64-bit hash of positions and velocities (bit patterns), for determinism checks.
  std::uint64_t hash() const;
  /// Draws every particle as a point (or sphere when `spheres`), at most `max_points`,
  /// when flags.particles.
  void draw(DebugDraw& draw, const DrawFlags& flags, bool spheres = false, std::size_t max_points = 200000) const;
  /// The same with the default flags.
  void draw(DebugDraw& draw, bool spheres = false, std::size_t max_points = 200000) const {
    this->draw(draw, DrawFlags{}, spheres, max_points);
  }

  /// Internal: the acceleration of particles [begin, begin + n) at time t given AoS
  /// positions and velocities (the callback the integrator calls). Public for tests.
  void accelerations(double t, std::size_t begin, std::span<const Vec3f> x, std::span<const Vec3f> v,
                     std::span<Vec3f> a) const;

 private:
  // the accessors' check of a particle index: a cold throw out of line (an index out of range
  // read past the columns, undefined behaviour)
  void check_index(std::size_t i, const char* call) const {
    if (i >= size()) index_out_of_range(i, call);
  }
  [[noreturn]] void index_out_of_range(std::size_t i, const char* call) const;
  struct EmitterState {
    EmitterId id;
    EmitterDef def;
    double elapsed = 0;         // seconds since the rate last changed
    double rate = 0;            // the rate elapsed refers to
    long long emitted_phase = 0;  // particles emitted since the rate last changed
    long long emitted_total = 0;
    std::size_t alive = 0;      // live particles from this emitter
    std::uint64_t rng = 0;
  };
  std::size_t push_particle(const ParticleDef& def, std::uint32_t owner, std::uint32_t source);
  void remove_at(std::size_t i);
  void emit(double t, double dt);
  void step_fused(double t, double dt, const CollisionWorld& colliders, std::span<const Forcer> forcers,
                  float threshold);
  void step_generic(double t, double dt, const CollisionWorld& colliders, std::span<const Forcer> forcers,
                    float threshold);
  void step_verlet(double t, double dt);
  void recycle();
  void report_non_finite(double t) const;
  std::size_t emitter_index(EmitterId id, std::string_view where) const;

  // the hot columns, in this order
  enum : int { kX, kY, kZ, kVX, kVY, kVZ, kInvMass, kRadius };
  std::span<const float> column(int c) const { return {hot_[c], hot_.size()}; }
  // particle i changed outside the fused kernel: its block's bounds are stale
  void touch(std::size_t i) {
    const std::size_t b = i / detail::kParticleBlock;
    if (b < bounds_.size()) bounds_[b].valid = false;
  }
  void reserve_rows(std::size_t rows);
  void count_uniform(float inv_mass, float radius, int sign);

  Integrator<Vec3f> integ_;
  Integrator<Vec3f> integ_one_;  // implicit Euler, one particle at a time
  Integrator<Vec3> verlet_{Method::PositionVerlet};  // position Verlet on the double state
  Forces forces_;
  CollisionSettings collision_;
  // the particle columns: hot floats (x, y, z, vx, vy, vz, inverse mass, radius) ...
  detail::HotColumns hot_;
  std::vector<detail::BlockBounds> bounds_;  // one per block of hot_'s capacity
  std::vector<detail::Reach> reach_;         // the broad phase's scratch, one per collider
  CollisionWorld span_world_;                // the colliders of the span overload of step()
  // ... and cold ones
  std::vector<double> birth_, death_;  // birth and death times (s); death = inf for immortal
  std::vector<std::uint32_t> color0_, color1_;  // packed RGBA8 birth and death colours
  std::vector<std::uint32_t> owner_;   // tracked: handle index; kNone for anonymous
  std::vector<std::uint32_t> source_;  // emitter slot index + 1; 0 for none
  // tracked particles: handle slot -> array index
  HandlePool<ParticleTag> ids_;
  std::vector<std::uint32_t> slot_;
  // emitters, dense, and their handle slots -> dense index
  HandlePool<EmitterTag> emitter_ids_;
  std::vector<EmitterState> emitters_;
  std::vector<std::uint32_t> emitter_slot_;
  // scratch for the generic integrators (AoS), sized to the live count
  std::vector<Vec3f> gx_, gv_;
  // position verlet's double positions and velocities, valid while its history is, and
  // the float accelerations of its force callback
  std::vector<Vec3> verlet_x_, verlet_v_;
  std::vector<Vec3f> verlet_a_;
  std::size_t mortal_ = 0;  // particles with a finite lifetime
  double next_death_ = kForever;  // no particle dies before this time (s; a lower bound)
  // uniform inverse mass and radius: the values of the first particle of a non-empty
  // system, and how many live particles differ from them (0: the column need not be read)
  float inv_mass_ref_ = 0, radius_ref_ = 0;
  std::size_t inv_mass_odd_ = 0, radius_odd_ = 0;
  bool broad_phase_ = true;
  bool record_contacts_ = false;
  std::vector<detail::ContactLog> contact_logs_;  // by handle slot, while recording
  std::size_t exact_blocks_ = 0;
  double time_ = 0;         // simulated time of the state
  std::span<const Forcer> forcers_now_;  // the forcers of the step in progress
  bool history_dirty_ = true;
  std::size_t memory_budget_ = kParticleMemoryBudget;  // bytes (ParticleSystemDef::memory_budget)
  std::size_t max_particles_ = 0;                      // memory_budget_ / kParticleBytes
  long long steps_ = 0;
  long long newton_fallbacks_ = 0;
  std::size_t contacts_ = 0;
  ParticleProfile profile_;
};


}  // namespace pba
