// The particle system: storage, validation, emitters, the generic integrator path,
// recycling. The fused kernel is in kernels.cpp; shapes and forcers in shapes.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>

#include "core/squarable.h"
#include "kernels.h"
#include "pba/particles.h"

namespace pba {

namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

[[noreturn]] void index_error(std::size_t i, std::size_t n, std::string_view where) {
  throw Error(std::string(where) + ": particle index " + std::to_string(i) + " out of range (" + std::to_string(n) +
              " particles)");
}

void require_index(std::size_t i, std::size_t n, std::string_view where) {
  if (i >= n) index_error(i, n, where);
}



std::uint32_t pack(Color c) {
  // RGBA8, clamped
  auto q = [](float f) {
    const float g = f < 0 ? 0 : (f > 1 ? 1 : f);
    return static_cast<std::uint32_t>(std::lround(g * 255.0f));
  };
  return q(c.r) << 24 | q(c.g) << 16 | q(c.b) << 8 | q(c.a);
}

Color unpack(std::uint32_t p) {
  return {((p >> 24) & 0xff) / 255.0f, ((p >> 16) & 0xff) / 255.0f, ((p >> 8) & 0xff) / 255.0f,
          (p & 0xff) / 255.0f};
}

// splitmix64 (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
// OOPSLA 2014): a tiny deterministic stream per emitter, no global state
std::uint64_t next_u64(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
double uniform01(std::uint64_t& s) { return static_cast<double>(next_u64(s) >> 11) * 0x1.0p-53; }

detail::ForceParams force_params(const Forces& f, double t) {
  const Vec3 w = f.wind.at(t);
  return {static_cast<float>(f.gravity.x), static_cast<float>(f.gravity.y), static_cast<float>(f.gravity.z),
          static_cast<float>(f.linear_drag), static_cast<float>(f.quadratic_drag), static_cast<float>(w.x),
          static_cast<float>(w.y), static_cast<float>(w.z)};
}

void rotation_columns(const Quat& q, float* r) {
  const Mat3 m = glm::mat3_cast(glm::normalize(q));
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r[c * 3 + k] = static_cast<float>(m[c][k]);
}

// flatten forcers that are on at time t (at most kMaxForcers)
constexpr std::size_t kMaxForcers = 64;

std::size_t forcer_params(std::span<const Forcer> forcers, double t, detail::ForcerParams* out) {
  std::size_t n = 0;
  for (const Forcer& f : forcers) {
    if (!f.active(t)) continue;
    detail::ForcerParams& p = out[n++];
    p.kind = f.kind;
    p.shape = f.shape;
    p.cx = static_cast<float>(f.pose.position.x);
    p.cy = static_cast<float>(f.pose.position.y);
    p.cz = static_cast<float>(f.pose.position.z);
    rotation_columns(f.pose.rotation, p.r);
    if (f.shape == ForcerShape::Box) {
      p.hx = static_cast<float>(f.half_extents.x);
      p.hy = static_cast<float>(f.half_extents.y);
      p.hz = static_cast<float>(f.half_extents.z);
    } else {
      p.hx = static_cast<float>(f.radius);
      p.hy = static_cast<float>(f.half_height);
      p.hz = static_cast<float>(f.radius);
    }
    const Quat q = glm::normalize(f.pose.rotation);
    const Vec3 push = q * glm::normalize(f.direction) * f.strength;
    const Vec3 axis = q * Vec3(0, 1, 0);
    p.fx = static_cast<float>(push.x);
    p.fy = static_cast<float>(push.y);
    p.fz = static_cast<float>(push.z);
    p.ax = static_cast<float>(axis.x);
    p.ay = static_cast<float>(axis.y);
    p.az = static_cast<float>(axis.z);
    p.strength = static_cast<float>(f.strength);
    p.pull = static_cast<float>(f.pull);
    p.softening = static_cast<float>(f.softening);
  }
  return n;
}

}  // namespace


// ---------------------------------------------------------------------------------------
// the hot columns

namespace detail {

namespace {

constexpr std::align_val_t kColumnAlign{64};
// Bytes added between columns beyond their length rounded up to 4 KB. 320 B puts the
// columns' rows in different L1 sets (no 4 KB aliasing between a store to x[i] and a
// load of vx[i]). Large columns get 32 KB more: with columns at the same address modulo
// 32 KB the fused step from main memory ran at about half the bandwidth (measured on the
// development VM with the read-modify-write pattern of the kernel: 19 GB/s against 40;
// docs/benchmarks.md), the signature of every stream hitting the same DRAM banks.
constexpr std::size_t kColumnStagger = 320;
constexpr std::size_t kLargeColumnStagger = 32768 + 320;
constexpr std::size_t kLargeColumn = 256 * 1024;  // bytes

std::size_t column_stride(std::size_t rows) {
  // bytes per column rounded up to a page, plus the stagger, in floats
  const std::size_t bytes = (rows * sizeof(float) + 4095) / 4096 * 4096;
  return (bytes + (bytes >= kLargeColumn ? kLargeColumnStagger : kColumnStagger)) / sizeof(float);
}

float* allocate_columns(std::size_t stride) {
  return static_cast<float*>(::operator new(stride * sizeof(float) * HotColumns::kCount, kColumnAlign));
}

}  // namespace

HotColumns::HotColumns(HotColumns&& o) noexcept
    : base_(o.base_), size_(o.size_), capacity_(o.capacity_), stride_(o.stride_) {
  o.base_ = nullptr;
  o.size_ = o.capacity_ = o.stride_ = 0;
}

HotColumns& HotColumns::operator=(HotColumns&& o) noexcept {
  std::swap(base_, o.base_);
  std::swap(size_, o.size_);
  std::swap(capacity_, o.capacity_);
  std::swap(stride_, o.stride_);
  return *this;
}

HotColumns::~HotColumns() {
  if (base_ != nullptr) ::operator delete(base_, kColumnAlign);
}

void HotColumns::reserve(std::size_t rows) {
  if (rows <= capacity_ && base_ != nullptr) return;
  // a new block, the live rows copied column by column
  const std::size_t stride = column_stride(rows);
  float* base = allocate_columns(stride);
  if (base_ != nullptr) {
    for (int c = 0; c < kCount; ++c) std::memcpy(base + c * stride, (*this)[c], size_ * sizeof(float));
    ::operator delete(base_, kColumnAlign);
  }
  base_ = base;
  stride_ = stride;
  capacity_ = rows;
}

std::size_t HotColumns::push() {
  if (size_ == capacity_ || base_ == nullptr) reserve(std::max<std::size_t>(16, 2 * capacity_));
  return size_++;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------
// definitions

void require_particle_memory(double count, std::size_t budget, std::string_view where, std::string_view hint) {
  const double bytes = count * static_cast<double>(kParticleBytes);
  if (!(bytes > static_cast<double>(budget))) return;
  // counts print exactly while a double holds them exactly
  const double whole = std::ceil(count);
  std::string msg(where);
  msg.append(": ")
      .append(whole < 0x1p53 ? std::to_string(static_cast<long long>(whole)) : format_value(whole))
      .append(" particles would take ")
      .append(format_bytes(bytes))
      .append(" (")
      .append(std::to_string(kParticleBytes))
      .append(" B each), over the particle system's memory budget of ")
      .append(format_bytes(static_cast<double>(budget)))
      .append(" (ParticleSystemDef.memory_budget)");
  throw Error(msg.append(hint));
}

namespace {

// the float state's rules for one particle's values (checked only when the double
// checks pass, so every message names the first rule broken)
void require_float_particle(const Vec3& position, double mass, double radius, std::string_view where) {
  if (!fits_float(position)) require_float(position, field_path(where, "position"));
  if (!std::isnormal(static_cast<float>(1.0 / mass))) require_float_inverse(mass, field_path(where, "mass"));
  if (!fits_float(radius)) require_float(radius, field_path(where, "radius"));
}

}  // namespace

// a speed (m/s) at most kMaxParticleSpeed: the drag squares |v - wind| in float
void require_particle_speed(double speed, std::string_view where) {
  if (speed <= kMaxParticleSpeed) return;
  throw Error(std::string(where) + ": a speed of " + format_value(speed) + " m/s is above the particles' limit of " +
              format_value(kMaxParticleSpeed) + " m/s (the drag squares the speed relative to the wind in float, " +
              "which overflows above 1.8e19 m/s)");
}

void ParticleDef::validate(std::string_view where) const {
  if (!is_finite(position)) require_finite(position, field_path(where, "position"));
  if (!is_finite(velocity)) require_finite(velocity, field_path(where, "velocity"));
  if (!(std::isfinite(mass) && (mass) > 0)) require_positive(mass, field_path(where, "mass"));
  if (!(std::isfinite(radius) && (radius) > 0)) require_positive(radius, field_path(where, "radius"));
  if (!(lifetime > 0))
    throw Error(field_path(where, "lifetime") + ": must be > 0 (infinity for immortal), got " + format_value(lifetime));
  require_float_particle(position, mass, radius, where);
  if (!fits_float(velocity)) require_float(velocity, field_path(where, "velocity"));
  if (glm::length(velocity) > kMaxParticleSpeed)
    require_particle_speed(glm::length(velocity), field_path(where, "velocity"));
}

void EmitterDef::validate(std::string_view where) const {
  if (!is_finite(pose.position)) require_finite(pose.position, field_path(where, "position"));
  // the emission cone turns with the pose: a zero quaternion (normalised to the identity)
  // or a non-finite one (non-finite particles, named by particle) is refused by name
  if (!detail::is_unit_quat(pose.rotation))
    require_unit_quat(pose.rotation, field_path(where, "rotation"));
  if (!is_finite(direction)) require_finite(direction, field_path(where, "direction"));
  if (glm::length(direction) == 0) throw Error(field_path(where, "direction") + ": must be non-zero, got (0, 0, 0)");
  if (!((spread) >= (0) && (spread) <= (kPi))) require_in_range(spread, 0, kPi, field_path(where, "spread"));
  if (!(std::isfinite(speed) && (speed) >= 0)) require_non_negative(speed, field_path(where, "speed"));
  if (!((speed_jitter) >= (0) && (speed_jitter) <= (1)))
    require_in_range(speed_jitter, 0, 1, field_path(where, "speed_jitter"));
  if (!(std::isfinite(rate) && (rate) >= 0)) require_non_negative(rate, field_path(where, "rate"));
  if (!(std::isfinite(lifetime) && (lifetime) > 0)) require_positive(lifetime, field_path(where, "lifetime"));
  if (!((lifetime_jitter) >= (0) && (lifetime_jitter) <= (0.999)))
    require_in_range(lifetime_jitter, 0, 0.999, field_path(where, "lifetime_jitter"));
  if (!(std::isfinite(mass) && (mass) > 0)) require_positive(mass, field_path(where, "mass"));
  if (!(std::isfinite(radius) && (radius) > 0)) require_positive(radius, field_path(where, "radius"));
  // the particles' float state, the fastest launch included
  require_float_particle(pose.position, mass, radius, where);
  const double fastest = speed * (1 + speed_jitter);
  if (!(fastest <= kMaxParticleSpeed))
    throw Error(field_path(where, "speed") + ": the fastest launch, speed * (1 + speed_jitter) = " +
                format_value(fastest) + " m/s, is above the particles' limit of " + format_value(kMaxParticleSpeed) +
                " m/s (the drag squares the speed in float), got speed " + format_value(speed));
}

double EmitterDef::max_live() const {
  // the steady state of a constant rate, or the cap when it is lower
  const double by_rate = std::ceil(rate * lifetime * (1 + lifetime_jitter));
  return max_alive > 0 ? std::min(by_rate, static_cast<double>(max_alive)) : by_rate;
}

void Forces::validate(std::string_view where) const {
  if (!is_finite(gravity)) require_finite(gravity, field_path(where, "gravity"));
  if (!(std::isfinite(linear_drag) && (linear_drag) >= 0))
    require_non_negative(linear_drag, field_path(where, "linear_drag"));
  if (!(std::isfinite(quadratic_drag) && (quadratic_drag) >= 0))
    require_non_negative(quadratic_drag, field_path(where, "quadratic_drag"));
  if (!is_finite(wind.velocity)) require_finite(wind.velocity, field_path(where, "wind.velocity"));
  if (!(std::isfinite(wind.gust) && (wind.gust) >= 0)) require_non_negative(wind.gust, field_path(where, "wind.gust"));
  if (!(std::isfinite(wind.gust_period) && (wind.gust_period) > 0))
    require_positive(wind.gust_period, field_path(where, "wind.gust_period"));
  // the kernels read these as floats
  if (!fits_float(gravity)) require_float(gravity, field_path(where, "gravity"));
  if (!fits_float(linear_drag)) require_float(linear_drag, field_path(where, "linear_drag"));
  if (!fits_float(quadratic_drag))
    require_float(quadratic_drag, field_path(where, "quadratic_drag"));
  const Vec3 strongest = glm::abs(wind.velocity) + Vec3(wind.gust);
  // (both inputs are finite here: a sum past 1.8e308 overflowed to inf, which is no fault of theirs)
  if (!fits_float(strongest))
    require_float_sum(strongest,
                      "|wind.velocity| " + format_vec3(glm::abs(wind.velocity)) + " + wind.gust " +
                          format_value(wind.gust),
                      where);
  // (the path is built only on failure: this runs every step, which allocates nothing)
  if (glm::length(strongest) > kMaxParticleSpeed)
    require_particle_speed(glm::length(strongest), field_path(where, "wind.velocity + wind.gust"));
}

// value noise: hashed lattice values in [-1, 1], quintic (C2) interpolation
// (Perlin, "Improving noise", SIGGRAPH 2002, the 6t^5 - 15t^4 + 10t^3 fade)
Vec3 Wind::at(double t) const {
  if (gust == 0) return velocity;
  const double u = t / gust_period;
  const double cell = std::floor(u);
  const double f = u - cell;
  const double s = f * f * f * (f * (f * 6 - 15) + 10);
  const auto k = static_cast<long long>(cell);
  auto lattice = [&](long long i, std::uint64_t channel) {
    std::uint64_t st = (static_cast<std::uint64_t>(seed) << 32) ^ (channel * 0x632be59bd9b4e019ULL) ^
                       static_cast<std::uint64_t>(i) * 0x9e3779b97f4a7c15ULL;
    return uniform01(st) * 2 - 1;
  };
  Vec3 g;
  for (int c = 0; c < 3; ++c) {
    const double a = lattice(k, static_cast<std::uint64_t>(c) + 1),
                 b = lattice(k + 1, static_cast<std::uint64_t>(c) + 1);
    g[c] = a + (b - a) * s;
  }
  return velocity + gust * g;
}

// ---------------------------------------------------------------------------------------
// the system

// a self-move keeps the system (see World's: a vector moved into itself gives up its elements,
// and the step then read the broad phase's blocks of particles that were no longer there)
ParticleSystem& ParticleSystem::operator=(ParticleSystem&& o) noexcept {
  if (this != &o) std::destroy_at(this), std::construct_at(this, std::move(o));
  return *this;
}

ParticleSystem::ParticleSystem(const ParticleSystemDef& def)
    : integ_(def.method), integ_one_(Method::ImplicitEuler), forces_(def.forces), collision_(def.collision) {
  // validate, then reserve every column
  forces_.validate("ParticleSystemDef.forces");
  require_finite(collision_.restitution_threshold, "ParticleSystemDef.collision.restitution_threshold");
  if (def.memory_budget < kParticleBytes)
    throw Error("ParticleSystemDef.memory_budget: must be at least " + std::to_string(kParticleBytes) +
                " B (one particle), got " + std::to_string(def.memory_budget));
  memory_budget_ = def.memory_budget;
  max_particles_ = memory_budget_ / kParticleBytes;
  // the reserve must fit the budget: refused before anything is allocated
  require_particle_memory(static_cast<double>(def.capacity), memory_budget_, "ParticleSystemDef.capacity");
  reserve_rows(std::min(std::max<std::size_t>(def.capacity, 16), max_particles_));
}

void ParticleSystem::reserve_rows(std::size_t rows) {
  // every column and the broad phase's per-block bounds, together (allocates)
  hot_.reserve(rows);
  const std::size_t cap = hot_.capacity();
  bounds_.resize((cap + detail::kParticleBlock - 1) / detail::kParticleBlock);
  for (auto* col : {&birth_, &death_}) col->reserve(cap);
  for (auto* col : {&color0_, &color1_, &owner_, &source_}) col->reserve(cap);
  gx_.reserve(cap);
  gv_.reserve(cap);
}

// Counts the particles whose inverse mass or radius differs from the system's reference
// values (those of the first particle of a non-empty system); sign is +1 when a particle
// is added, -1 when it is removed. When a count is zero the kernel need not read that
// column: every particle has the reference value.
void ParticleSystem::count_uniform(float inv_mass, float radius, int sign) {
  if (sign > 0 && hot_.size() == 0) {
    inv_mass_ref_ = inv_mass;
    radius_ref_ = radius;
    inv_mass_odd_ = radius_odd_ = 0;
  }
  if (inv_mass != inv_mass_ref_) inv_mass_odd_ += static_cast<std::size_t>(sign);
  if (radius != radius_ref_) radius_odd_ += static_cast<std::size_t>(sign);
}

void ParticleSystem::set_method(Method m) {
  // a value outside the enum is refused naming this call (the integrator's "pba::Method:
  // invalid value 99" did not say which call passed it)
  try {
    integ_.set_method(m);
  } catch (const Error& err) {
    throw Error(std::string("ParticleSystem::set_method(m): ") + err.what());
  }
  history_dirty_ = true;
}

std::size_t ParticleSystem::push_particle(const ParticleDef& d, std::uint32_t owner, std::uint32_t source) {
  // append to every column (allocates only past the reserved capacity)
  const float inv_mass = static_cast<float>(1.0 / d.mass), radius = static_cast<float>(d.radius);
  if (hot_.size() == hot_.capacity()) {
    // grow geometrically up to the budget, and no further
    if (hot_.size() >= max_particles_)
      require_particle_memory(static_cast<double>(hot_.size()) + 1, memory_budget_,
                              "ParticleSystem: adding a particle");
    reserve_rows(std::min(2 * hot_.capacity(), max_particles_));
  }
  count_uniform(inv_mass, radius, +1);
  const std::size_t i = hot_.push();
  hot_[kX][i] = static_cast<float>(d.position.x);
  hot_[kY][i] = static_cast<float>(d.position.y);
  hot_[kZ][i] = static_cast<float>(d.position.z);
  hot_[kVX][i] = static_cast<float>(d.velocity.x);
  hot_[kVY][i] = static_cast<float>(d.velocity.y);
  hot_[kVZ][i] = static_cast<float>(d.velocity.z);
  hot_[kInvMass][i] = inv_mass;
  hot_[kRadius][i] = radius;
  touch(i);
  birth_.push_back(time_);
  death_.push_back(time_ + d.lifetime);
  color0_.push_back(pack(d.color));
  color1_.push_back(pack(d.end_color));
  owner_.push_back(owner);
  source_.push_back(source);
  if (std::isfinite(d.lifetime)) {
    ++mortal_;
    next_death_ = std::min(next_death_, time_ + d.lifetime);
  }
  history_dirty_ = true;
  return i;
}

ParticleId ParticleSystem::create(const ParticleDef& def, std::string_view where) {
  def.validate(where);
  const ParticleId id = ids_.create();
  if (slot_.size() <= id.index) slot_.resize(id.index + 1, kNone);
  if (record_contacts_ && contact_logs_.size() < slot_.size()) contact_logs_.resize(slot_.size());
  if (record_contacts_) contact_logs_[id.index] = {};  // a reused slot forgets the last owner's
  slot_[id.index] = static_cast<std::uint32_t>(push_particle(def, id.index, 0));
  return id;
}

std::size_t ParticleSystem::spawn(const ParticleDef& def, std::string_view where) {
  def.validate(where);
  return push_particle(def, kNone, 0);
}

std::size_t ParticleSystem::index_of(ParticleId id) const {
  ids_.require(id, "ParticleSystem: particle");
  return slot_[id.index];
}

void ParticleSystem::set_record_contacts(bool on) {
  // a log per handle slot (stale ones are told apart by their step number)
  if (on && !record_contacts_) contact_logs_.assign(slot_.size(), {});
  record_contacts_ = on;
}

std::span<const ParticleContact> ParticleSystem::contacts(ParticleId id) const {
  ids_.require(id, "ParticleSystem::contacts: particle");
  if (!record_contacts_ || id.index >= contact_logs_.size()) return {};
  const detail::ContactLog& log = contact_logs_[id.index];
  if (log.step != steps_) return {};
  return {log.contacts, log.count};
}

void ParticleSystem::destroy(ParticleId id) {
  const std::size_t i = index_of(id);
  remove_at(i);
}

void ParticleSystem::remove_at(std::size_t i) {
  // release the handle and the emitter's count of the particle being removed
  if (owner_[i] != kNone) {
    const std::uint32_t slot = owner_[i];
    ids_.destroy(ParticleId{slot, ids_.generation(slot)}, "ParticleSystem::remove");
    slot_[slot] = kNone;
  }
  if (source_[i] != 0) {
    const std::uint32_t es = source_[i] - 1;
    if (es < emitter_slot_.size() && emitter_slot_[es] != kNone) --emitters_[emitter_slot_[es]].alive;
  }
  if (std::isfinite(death_[i])) --mortal_;
  count_uniform(hot_[kInvMass][i], hot_[kRadius][i], -1);
  // swap the last particle into i (deterministic: depends only on the order of removals)
  const std::size_t last = hot_.size() - 1;
  touch(i);
  touch(last);
  if (i != last) {
    for (int c = 0; c < detail::HotColumns::kCount; ++c) hot_[c][i] = hot_[c][last];
    birth_[i] = birth_[last], death_[i] = death_[last];
    color0_[i] = color0_[last], color1_[i] = color1_[last];
    owner_[i] = owner_[last], source_[i] = source_[last];
    if (owner_[i] != kNone) slot_[owner_[i]] = static_cast<std::uint32_t>(i);
  }
  hot_.pop();
  birth_.pop_back();
  death_.pop_back();
  for (auto* col : {&color0_, &color1_, &owner_, &source_}) col->pop_back();
  history_dirty_ = true;
}

void ParticleSystem::clear() {
  // release every handle, then empty the columns (capacity kept)
  for (std::size_t i = 0; i < owner_.size(); ++i)
    if (owner_[i] != kNone) {
      ids_.destroy(ParticleId{owner_[i], ids_.generation(owner_[i])}, "ParticleSystem::clear");
      slot_[owner_[i]] = kNone;
    }
  hot_.clear();
  for (auto& b : bounds_) b.valid = false;
  inv_mass_odd_ = radius_odd_ = 0;
  next_death_ = kForever;
  birth_.clear();
  death_.clear();
  for (auto* col : {&color0_, &color1_, &owner_, &source_}) col->clear();
  for (auto& e : emitters_) e.alive = 0;
  mortal_ = 0;
  history_dirty_ = true;
}

void ParticleSystem::index_out_of_range(std::size_t i, const char* call) const { index_error(i, size(), call); }

EmitterId ParticleSystem::emitter_at(std::size_t slot) const {
  if (slot >= emitters_.size())
    throw Error("ParticleSystem::emitter_at: emitter slot " + std::to_string(slot) + " out of range (" +
                std::to_string(emitters_.size()) + " emitters)");
  return emitters_[slot].id;
}

Color ParticleSystem::color(std::size_t i) const {
  check_index(i, "ParticleSystem::color");
  // blend birth to death colour by the fraction of life lived
  const Color a = unpack(color0_[i]);
  if (!std::isfinite(death_[i])) return a;
  const Color b = unpack(color1_[i]);
  const double life = death_[i] - birth_[i];
  const float f = static_cast<float>(std::clamp((time_ - birth_[i]) / life, 0.0, 1.0));
  return {a.r + (b.r - a.r) * f, a.g + (b.g - a.g) * f, a.b + (b.b - a.b) * f, a.a + (b.a - a.a) * f};
}

void ParticleSystem::set_position(std::size_t i, const Vec3& p) {
  require_float(p, "ParticleSystem::set_position");
  require_index(i, size(), "ParticleSystem::set_position");
  hot_[kX][i] = static_cast<float>(p.x);
  hot_[kY][i] = static_cast<float>(p.y);
  hot_[kZ][i] = static_cast<float>(p.z);
  touch(i);
  history_dirty_ = true;
}

void ParticleSystem::set_velocity(std::size_t i, const Vec3& v) {
  require_float(v, "ParticleSystem::set_velocity");
  require_particle_speed(glm::length(v), "ParticleSystem::set_velocity");
  require_index(i, size(), "ParticleSystem::set_velocity");
  hot_[kVX][i] = static_cast<float>(v.x);
  hot_[kVY][i] = static_cast<float>(v.y);
  hot_[kVZ][i] = static_cast<float>(v.z);
  touch(i);
  history_dirty_ = true;
}

void ParticleSystem::copy_positions(std::span<Vec3f> out) const {
  const std::size_t n = std::min(out.size(), size());
  for (std::size_t i = 0; i < n; ++i) out[i] = Vec3f(hot_[kX][i], hot_[kY][i], hot_[kZ][i]);
}

// ---------------------------------------------------------------------------------------
// emitters

std::size_t ParticleSystem::emitter_index(EmitterId id, std::string_view where) const {
  emitter_ids_.require(id, where);
  return emitter_slot_[id.index];
}

void require_emitter_memory(const EmitterDef& def, std::size_t budget, std::string_view rate_field,
                            std::string_view max_alive_field) {
  // name the field that sets the count
  const double live = def.max_live();
  if (live * static_cast<double>(kParticleBytes) <= static_cast<double>(budget)) return;
  if (def.max_alive > 0 && live == static_cast<double>(def.max_alive))
    require_particle_memory(live, budget, max_alive_field, "; lower max_alive");
  require_particle_memory(live, budget, rate_field,
                          "; it emits " + format_value(def.rate) + " particles/s that live up to " +
                              format_value(def.lifetime * (1 + def.lifetime_jitter)) +
                              " s: lower the rate or the lifetime, or set max_alive");
}

EmitterId ParticleSystem::add_emitter(const EmitterDef& def, std::string_view where) {
  def.validate(where);
  require_emitter_memory(def, memory_budget_, field_path(where, "rate"), field_path(where, "max_alive"));
  const EmitterId id = emitter_ids_.create();
  if (emitter_slot_.size() <= id.index) emitter_slot_.resize(id.index + 1, kNone);
  emitter_slot_[id.index] = static_cast<std::uint32_t>(emitters_.size());
  EmitterState s;
  s.id = id;
  s.def = def;
  s.rate = def.rate;
  s.rng = def.seed;
  emitters_.push_back(s);
  return id;
}

void ParticleSystem::remove_emitter(EmitterId id) {
  const std::size_t i = emitter_index(id, "ParticleSystem::remove_emitter");
  // its particles become sourceless
  for (auto& s : source_)
    if (s == id.index + 1) s = 0;
  emitter_ids_.destroy(id, "ParticleSystem::remove_emitter");
  emitter_slot_[id.index] = kNone;
  // swap-remove from the dense array
  if (i + 1 != emitters_.size()) {
    emitters_[i] = emitters_.back();
    emitter_slot_[emitters_[i].id.index] = static_cast<std::uint32_t>(i);
  }
  emitters_.pop_back();
}

EmitterDef& ParticleSystem::emitter(EmitterId id) {
  return emitters_[emitter_index(id, "ParticleSystem::emitter")].def;
}

void ParticleSystem::set_emitter_pose(EmitterId id, const Pose& pose) {
  emitters_[emitter_index(id, "ParticleSystem::set_emitter_pose")].def.pose = pose;
}

long long ParticleSystem::emitted(EmitterId id) const {
  return emitters_[emitter_index(id, "ParticleSystem::emitted")].emitted_total;
}

// Emission over (t, t + dt]: the i-th particle since the rate was last set is due at
// i / rate seconds, so after T seconds exactly floor(rate T) have been emitted (up to a
// relative 1e-9 of round-off), with no drift from summing fractions. Each particle is
// born at its due time and advanced ballistically to t + dt. Particles due while the
// emitter is at max_alive are skipped, as a count: the cost is that of the particles
// emitted, whatever the rate.
void ParticleSystem::emit(double t, double dt) {
  for (EmitterState& e : emitters_) {
    e.def.validate("emitter");
    require_emitter_memory(e.def, memory_budget_, "emitter.rate", "emitter.max_alive");
    // a new rate or a paused emitter restarts the schedule
    if (e.def.rate != e.rate || !e.def.enabled) {
      e.rate = e.def.rate;
      e.elapsed = 0;
      e.emitted_phase = 0;
      if (!e.def.enabled) continue;
    }
    e.elapsed += dt;
    const double due_real = e.rate * e.elapsed;
    if (!(due_real < 0x1p62))
      throw Error("emitter.rate: " + format_value(e.rate) + " particles/s over " + format_value(e.elapsed) +
                  " s is more particles than an emitter can count (2^62)");
    const auto due = static_cast<long long>(std::floor(due_real + 1e-9 * std::max(1.0, due_real)));
    // the last particle emitted: the cap leaves room for the first ones due (those after
    // them would be skipped one by one, drawing nothing from the stream)
    long long last = due;
    if (e.def.max_alive) {
      const std::size_t room = e.alive >= e.def.max_alive ? 0 : e.def.max_alive - e.alive;
      last = std::min(due, e.emitted_phase + static_cast<long long>(std::min<std::size_t>(room, 1ULL << 62)));
    } else if (static_cast<double>(due - e.emitted_phase) > static_cast<double>(max_particles_ - size())) {
      // uncapped: a step longer than the lifetimes can still bring more than fit
      require_particle_memory(static_cast<double>(size()) + static_cast<double>(due - e.emitted_phase),
                              memory_budget_, "emitter.rate",
                              "; " + format_value(e.rate) + " particles/s are due over a step of " +
                                  format_value(dt) + " s");
    }
    const Quat q = glm::normalize(e.def.pose.rotation);
    const Vec3 axis = q * glm::normalize(e.def.direction);
    // an orthonormal basis around the cone axis
    const Vec3 helper = std::abs(axis.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    const Vec3 u = glm::normalize(glm::cross(axis, helper));
    const Vec3 w = glm::cross(axis, u);
    const double cos_spread = std::cos(e.def.spread);
    for (long long i = e.emitted_phase + 1; i <= last; ++i) {
      // the particle's due time and how long it has lived by t + dt
      const double t_due = static_cast<double>(i) / e.rate;
      const double lived = std::clamp(e.elapsed - t_due, 0.0, dt);
      // direction uniform over the spherical cap, speed and lifetime jittered
      const double cz = 1 - uniform01(e.rng) * (1 - cos_spread);
      const double sz = std::sqrt(std::max(0.0, 1 - cz * cz));
      const double phi = 2 * kPi * uniform01(e.rng);
      const Vec3 dir = axis * cz + (u * std::cos(phi) + w * std::sin(phi)) * sz;
      const double speed = e.def.speed * (1 + e.def.speed_jitter * (2 * uniform01(e.rng) - 1));
      const double life = e.def.lifetime * (1 + e.def.lifetime_jitter * (2 * uniform01(e.rng) - 1));
      ParticleDef d;
      d.velocity = dir * speed + forces_.gravity * lived;
      d.position = e.def.pose.position + dir * speed * lived + forces_.gravity * (0.5 * lived * lived);
      d.mass = e.def.mass;
      d.radius = e.def.radius;
      d.lifetime = life;
      d.color = e.def.start_color;
      d.end_color = e.def.end_color;
      const std::size_t idx = push_particle(d, kNone, e.id.index + 1);
      birth_[idx] = t + dt - lived;
      death_[idx] = birth_[idx] + life;
      next_death_ = std::min(next_death_, death_[idx]);
      ++e.alive;
      ++e.emitted_total;
    }
    e.emitted_phase = due;
    // past 2^40 particles (only at absurd rates or after years) the schedule restarts
    // from the last due time, so that due_real keeps its integer precision
    if (e.emitted_phase >= (1LL << 40)) {
      e.elapsed -= static_cast<double>(e.emitted_phase) / e.rate;
      e.emitted_phase = 0;
    }
  }
}

// ---------------------------------------------------------------------------------------
// stepping

void ParticleSystem::accelerations(double t, std::size_t begin, std::span<const Vec3f> x,
                                   std::span<const Vec3f> v, std::span<Vec3f> a) const {
  // the forcers on at t, flattened once per call
  detail::ForcerParams fp[kMaxForcers];
  const std::size_t nf = forcer_params(forcers_now_, t, fp);
  const detail::ForceParams f = force_params(forces_, t);
  // block by block: de-interleave, the kernels' force code, interleave
  alignas(64) float bx[detail::kBlock], by[detail::kBlock], bz[detail::kBlock];
  alignas(64) float bvx[detail::kBlock], bvy[detail::kBlock], bvz[detail::kBlock];
  alignas(64) float ax[detail::kBlock], ay[detail::kBlock], az[detail::kBlock];
  for (std::size_t b = 0; b < x.size(); b += detail::kBlock) {
    const int n = static_cast<int>(std::min<std::size_t>(detail::kBlock, x.size() - b));
    for (int k = 0; k < n; ++k) {
      bx[k] = x[b + k].x, by[k] = x[b + k].y, bz[k] = x[b + k].z;
      bvx[k] = v[b + k].x, bvy[k] = v[b + k].y, bvz[k] = v[b + k].z;
    }
    const float* im = hot_[kInvMass] + begin + b;
    detail::base_accel(n, bvx, bvy, bvz, im, f, ax, ay, az);
    for (std::size_t j = 0; j < nf; ++j) detail::forcer_accel(n, bx, by, bz, im, fp[j], ax, ay, az);
    for (int k = 0; k < n; ++k) a[b + k] = Vec3f(ax[k], ay[k], az[k]);
  }
}

void ParticleSystem::step(double t, double dt, std::span<const Collider> colliders,
                          std::span<const Forcer> forcers) {
  span_world_.assign(colliders, "ParticleSystem::step colliders");
  step(t, dt, span_world_, forcers);
}

void ParticleSystem::step(double t, double dt, const CollisionWorld& colliders, std::span<const Forcer> forcers) {
  Stopwatch total;
  // validate the step and the settings once
  require_positive(dt, "ParticleSystem::step(dt)");
  require_finite(t, "ParticleSystem::step(t)");
  // the step in float, as every method's kernel uses it: normal, with a finite square (1e-50
  // rounded to 0 and made a silent no-op step; the implicit Euler's Integrator refused it
  // inside the Newton fallback, which swallowed it)
  if (!detail::squarable<float>(dt))
    detail::throw_not_squarable<float>(dt, "ParticleSystem::step(dt)", "s",
                                       detail::kParticleStepWhy);
  forces_.validate("ParticleSystem.forces");
  if (forcers.size() > kMaxForcers)
    throw Error("ParticleSystem::step: at most " + std::to_string(kMaxForcers) + " forcers, got " +
                std::to_string(forcers.size()));
  // the forcers and the collision settings, which the caller may change between steps (a
  // non-finite one would turn into a non-finite particle, named by the particle, or into a
  // threshold that never applies); named by index, without allocating when they are valid
  for (std::size_t i = 0; i < forcers.size(); ++i) {
    char where[48];
    std::snprintf(where, sizeof where, "ParticleSystem::step forcers[%zu]", i);
    forcers[i].validate(where);
  }
  require_finite(collision_.restitution_threshold, "ParticleSystem.collision.restitution_threshold");
  time_ = t;
  forcers_now_ = forcers;
  const double g = glm::length(forces_.gravity);
  const float threshold = static_cast<float>(
      collision_.restitution_threshold >= 0 ? collision_.restitution_threshold : 2 * g * dt);
  profile_ = {};
  contacts_ = 0;
  // forces, integration and collisions (the phases are timed off one stopwatch: four
  // clock reads per step)
  if (integ_.method() == Method::SemiImplicitEuler)
    step_fused(t, dt, colliders, forcers, threshold);
  else
    step_generic(t, dt, colliders, forcers, threshold);
  const double integrated = total.seconds();
  profile_.integrate = integrated - profile_.collide;
  time_ = t + dt;
  ++steps_;
  // ageing and recycling, then emission of the particles due in this step
  recycle();
  const double recycled = total.seconds();
  profile_.recycle = recycled - integrated;
  emit(t, dt);
  profile_.total = total.seconds();
  profile_.emit = profile_.total - recycled;
  forcers_now_ = {};
}

void ParticleSystem::step_fused(double t, double dt, const CollisionWorld& colliders,
                                std::span<const Forcer> forcers, float threshold) {
  // flatten the forcers for the kernel (a stack array, no allocation); the colliders come
  // flat from the collision world, with the broad phase's scratch beside them (it grows
  // only when the count of colliders does)
  detail::ForcerParams fp[kMaxForcers];
  const std::size_t nf = forcer_params(forcers, t, fp);
  if (reach_.size() < colliders.size()) reach_.resize(colliders.size());
  // a column whose values are all equal is not read (the kernel uses the value)
  detail::FusedArgs a{};
  a.x = hot_[kX], a.y = hot_[kY], a.z = hot_[kZ];
  a.vx = hot_[kVX], a.vy = hot_[kVY], a.vz = hot_[kVZ];
  a.inv_mass = inv_mass_odd_ == 0 ? nullptr : hot_[kInvMass];
  a.inv_mass_value = inv_mass_ref_;
  a.radius = radius_odd_ == 0 ? nullptr : hot_[kRadius];
  a.radius_value = radius_ref_;
  a.bounds = bounds_.data();
  a.broad_phase = broad_phase_;
  a.n = size();
  a.h = static_cast<float>(dt);
  a.forces = force_params(forces_, t);
  a.forcers = fp;
  a.n_forcers = nf;
  a.colliders = colliders.flat_float().data();
  a.n_colliders = colliders.size();
  a.reach = reach_.data();
  a.threshold = threshold;
  // contact recording, when on and some particle has a handle to record for
  if (record_contacts_ && ids_.size() > 0) {
    a.owner = owner_.data();
    a.logs = contact_logs_.data();
    a.step = steps_ + 1;
  }
  const detail::FusedResult r = detail::fused_semi_implicit_euler(a);
  contacts_ = r.contacts;
  exact_blocks_ = r.exact_blocks;
  if (r.non_finite) report_non_finite(t + dt);
}

void ParticleSystem::step_generic(double t, double dt, const CollisionWorld& colliders,
                                  std::span<const Forcer> /*forcers*/, float threshold) {
  const std::size_t n = size();
  // the broad phase's bounds are not kept up to date here
  for (auto& b : bounds_) b.valid = false;
  exact_blocks_ = 0;
  if (n == 0) return;
  float *x = hot_[kX], *y = hot_[kY], *z = hot_[kZ], *vx = hot_[kVX], *vy = hot_[kVY], *vz = hot_[kVZ];
  // gather into AoS vec3 (resizing allocates only when the count grows past capacity)
  gx_.resize(n);
  gv_.resize(n);
  if (integ_.method() != Method::PositionVerlet) {
    for (std::size_t i = 0; i < n; ++i) {
      gx_[i] = Vec3f(x[i], y[i], z[i]);
      gv_[i] = Vec3f(vx[i], vy[i], vz[i]);
    }
  }
  // integrate: position verlet on its double state, implicit Euler one particle at a
  // time, the others all at once
  if (integ_.method() == Method::PositionVerlet) {
    step_verlet(t, dt);
  } else if (integ_.method() == Method::ImplicitEuler) {
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3f x0 = gx_[i], v0 = gv_[i];
      auto accel = [this, i](double tt, std::span<const Vec3f> x, std::span<const Vec3f> v, std::span<Vec3f> a) {
        accelerations(tt, i, x, v, a);
      };
      try {
        integ_one_.step(t, dt, std::span<Vec3f>(&gx_[i], 1), std::span<Vec3f>(&gv_[i], 1), accel);
      } catch (const NewtonFailure&) {
        // Newton fails where the force is discontinuous (a forcer volume's edge): that
        // particle takes a semi-implicit Euler step instead, and is counted
        gx_[i] = x0;
        gv_[i] = v0;
        Vec3f a;
        accel(t, std::span<const Vec3f>(&x0, 1), std::span<const Vec3f>(&v0, 1), std::span<Vec3f>(&a, 1));
        gv_[i] = v0 + a * static_cast<float>(dt);
        gx_[i] = x0 + gv_[i] * static_cast<float>(dt);
        ++newton_fallbacks_;
      }
    }
  } else {
    integ_.step(t, dt, std::span<Vec3f>(gx_), std::span<Vec3f>(gv_),
                [this](double tt, std::span<const Vec3f> x, std::span<const Vec3f> v, std::span<Vec3f> a) {
                  accelerations(tt, 0, x, v, a);
                });
  }
  // collide block by block: old positions from the columns, new ones from the integrator
  Stopwatch sw;
  const detail::ColliderParams* cp = colliders.flat_float().data();
  const bool record = record_contacts_ && ids_.size() > 0;
  alignas(64) float bx[detail::kBlock], by[detail::kBlock], bz[detail::kBlock];
  alignas(64) float bvx[detail::kBlock], bvy[detail::kBlock], bvz[detail::kBlock];
  int bad = 0;
  for (std::size_t b = 0; b < n; b += detail::kBlock) {
    const int m = static_cast<int>(std::min<std::size_t>(detail::kBlock, n - b));
    for (int k = 0; k < m; ++k) {
      bx[k] = gx_[b + k].x, by[k] = gx_[b + k].y, bz[k] = gx_[b + k].z;
      bvx[k] = gv_[b + k].x, bvy[k] = gv_[b + k].y, bvz[k] = gv_[b + k].z;
    }
    const detail::ContactSink sink{record ? owner_.data() + b : nullptr, contact_logs_.data(), steps_ + 1};
    contacts_ += static_cast<std::size_t>(detail::collide_block(m, x + b, y + b, z + b, vx + b, vy + b, vz + b, bx, by,
                                                                bz, bvx, bvy, bvz, hot_[kRadius] + b, cp,
                                                                colliders.size(), threshold, static_cast<float>(dt),
                                                                bad, sink));
    bad |= detail::any_non_finite(m, bx, by, bz) | detail::any_non_finite(m, bvx, bvy, bvz);
    for (int k = 0; k < m; ++k) {
      x[b + k] = bx[k], y[b + k] = by[k], z[b + k] = bz[k];
      vx[b + k] = bvx[k], vy[b + k] = bvy[k], vz[b + k] = bvz[k];
    }
  }
  // position verlet's velocity lives in its history: restart it after any contact
  if (contacts_) history_dirty_ = true;
  profile_.collide = sw.seconds();
  if (bad) report_non_finite(t + dt);
}

// Position Verlet keeps its velocity in x - x_prev, so a drift a h^2 under half a float
// step of x, rounded away every step, is velocity lost (from y = 2.02 at h = 1e-4 s a
// particle hung in the air). The recurrence therefore runs on double positions and
// velocities (verlet_x_, verlet_v_) that persist between steps: they carry what the
// float columns cannot hold (the residual x - float(x)), as the XPBD solver's velocity
// column does (src/soft/xpbd.cpp, predict). The columns get the rounded state after each
// step; the double state is reloaded from them whenever the history restarts (a contact,
// a spawn or removal, a write, a change of method: history_dirty_). The forces read the
// rounded state, as on every other path. On round-off in long integrations and the
// compensated forms that avoid it: Hairer, Lubich & Wanner, "Geometric Numerical
// Integration" (2nd ed. 2006), section VIII.5.
void ParticleSystem::step_verlet(double t, double dt) {
  const std::size_t n = size();
  // (re)load the double state from the columns when the history restarts
  if (history_dirty_ || verlet_x_.size() != n) {
    verlet_x_.resize(n);
    verlet_v_.resize(n);
    const float *x = hot_[kX], *y = hot_[kY], *z = hot_[kZ], *vx = hot_[kVX], *vy = hot_[kVY], *vz = hot_[kVZ];
    for (std::size_t i = 0; i < n; ++i) {
      verlet_x_[i] = Vec3(x[i], y[i], z[i]);
      verlet_v_[i] = Vec3(vx[i], vy[i], vz[i]);
    }
    verlet_.reset_history();
    history_dirty_ = false;
  }
  // the recurrence in double; the forces see the state rounded to float
  verlet_a_.resize(n);
  verlet_.step(t, dt, std::span<Vec3>(verlet_x_), std::span<Vec3>(verlet_v_),
               [this](double tt, std::span<const Vec3> xs, std::span<const Vec3> vs, std::span<Vec3> a) {
                 for (std::size_t i = 0; i < xs.size(); ++i) {
                   gx_[i] = Vec3f(xs[i]);
                   gv_[i] = Vec3f(vs[i]);
                 }
                 accelerations(tt, 0, gx_, gv_, verlet_a_);
                 for (std::size_t i = 0; i < xs.size(); ++i) a[i] = Vec3(verlet_a_[i]);
               });
  // the new state, rounded, for the collisions and the columns
  for (std::size_t i = 0; i < n; ++i) {
    gx_[i] = Vec3f(verlet_x_[i]);
    gv_[i] = Vec3f(verlet_v_[i]);
  }
}

// remove particles whose death time has passed (swap-remove; deterministic order). No
// scan while the earliest death is still ahead: the scan would remove nothing.
void ParticleSystem::recycle() {
  if (mortal_ == 0 || next_death_ > time_ + 1e-12) return;
  double next = kForever;
  for (std::size_t i = 0; i < size();) {
    if (death_[i] <= time_ + 1e-12) {
      remove_at(i);
    } else {
      next = std::min(next, death_[i]);
      ++i;
    }
  }
  next_death_ = next;
}

void ParticleSystem::report_non_finite(double t) const {
  // the kernel's check may be a false alarm (a sum of huge positions overflowing): look
  // first, without allocating
  bool all_finite = true;
  for (int c : {kX, kY, kZ, kVX, kVY, kVZ})
    for (float v : column(c)) all_finite &= std::isfinite(v);
  if (all_finite) return;
  // format through core's check_finite (allocates: this is the error path)
  std::vector<Vec3f> px(size()), pv(size());
  for (std::size_t i = 0; i < size(); ++i) {
    px[i] = position(i);
    pv[i] = velocity(i);
  }
  const FiniteCheck c = check_finite<Vec3f>(px, pv, "particle", t, steps_ + 1);
  if (!c.ok) throw Error(c.message);
}

std::uint64_t ParticleSystem::hash() const {
  std::uint64_t h = hash_span<float>(column(kX));
  for (int c : {kY, kZ, kVX, kVY, kVZ}) h = hash_span<float>(column(c), h);
  return h;
}

void ParticleSystem::draw(DebugDraw& draw, const DrawFlags& flags, bool spheres, std::size_t max_points) const {
  if (!flags.particles) return;
  const std::size_t n = std::min(max_points, size());
  for (std::size_t i = 0; i < n; ++i) {
    if (spheres)
      draw.sphere(position(i), hot_[kRadius][i], color(i));
    else
      draw.point(position(i), 4.0f, color(i));
  }
}

}  // namespace pba
