// pba core: math aliases, errors, validation helpers, state hashing and timing.
//
// Every other pba header includes this one. It never includes graphics.
#pragma once

#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace pba {

/// Double-precision 3-vector: positions in metres, velocities in m/s, accelerations in m/s^2.
using Vec3 = glm::dvec3;
/// Double-precision 2-vector.
using Vec2 = glm::dvec2;
/// Double-precision 3x3 matrix (rotations, inertia tensors).
using Mat3 = glm::dmat3;
/// Double-precision 4x4 matrix (rigid transforms).
using Mat4 = glm::dmat4;
/// Double-precision unit quaternion (orientations).
using Quat = glm::dquat;
/// Single-precision 3-vector, for bulk data such as large particle arrays.
using Vec3f = glm::vec3;

/// pi, the one definition every module uses.
inline constexpr double kPi = 3.141592653589793238462643383279502884;

/// A rigid placement: position (m) and unit rotation. A pose maps a point p of its local
/// frame to the world point position + rotation * p.
struct Pose {
  Vec3 position{0, 0, 0};     ///< world position (m), finite
  Quat rotation{1, 0, 0, 0};  ///< world rotation, unit quaternion (w, x, y, z)
};

/// The pose of a frame placed at `local` within `parent`: parent * local (renormalised).
inline Pose compose(const Pose& parent, const Pose& local) {
  return {parent.position + parent.rotation * local.position, glm::normalize(parent.rotation * local.rotation)};
}
/// The inverse placement: inverse(p) * p is the identity.
inline Pose inverse(const Pose& p) {
  const Quat qi = glm::conjugate(p.rotation);
  return {qi * -p.position, qi};
}
/// The world point of the local point `local` (m).
inline Vec3 apply(const Pose& p, const Vec3& local) { return p.position + p.rotation * local; }
/// The local point of the world point `world` (m): apply(inverse(p), world).
inline Vec3 apply_inverse(const Pose& p, const Vec3& world) {
  return glm::conjugate(p.rotation) * (world - p.position);
}

/// The one exception type pba throws for bad input and diverged simulations.
/// Its message names the bad value and where it came from, for example
/// "StepperSettings.fixed_dt (--dt): must be finite and > 0, got -0.01".
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Formats a double for error messages: shortest round-trip form, "nan", "inf", "-inf".
std::string format_value(double v);

/// Formats a vector for error messages as "(x, y, z)" with format_value's numbers.
std::string format_vec3(const Vec3& v);
/// Joins a field path for error messages: field_path("def", "mass") is "def.mass"; a JSON
/// pointer (a scene file's path) stays one: field_path("/bodies/0", "points[2]") is
/// "/bodies/0/points/2".
std::string field_path(std::string_view where, std::string_view name);

/// Throws Error "<where>: must be finite, got <v>" unless v is finite.
void require_finite(double v, std::string_view where);
/// Throws Error "<where>: must be finite, got (x, y, z)" unless every component is finite.
void require_finite(const Vec3& v, std::string_view where);
/// Throws Error unless q is finite with norm within 1e-6 of 1.
void require_unit_quat(const Quat& q, std::string_view where);
/// Throws Error unless v is finite and strictly positive.
void require_positive(double v, std::string_view where);
/// Throws Error unless v is finite and >= 0.
void require_non_negative(double v, std::string_view where);
/// Throws Error unless lo <= v <= hi (both inclusive) and v is finite.
void require_in_range(double v, double lo, double hi, std::string_view where);
/// Throws Error unless lo <= v <= hi for an integer count.
void require_count(long long v, long long lo, long long hi, std::string_view where);

/// True when v is finite as a float: |v| <= 3.4028235e+38 to the float's rounding (a value
/// up to half a float step beyond rounds to the largest float and fits); false for NaN and
/// infinity. The one test of "fits a float" in the library: require_float throws exactly when
/// it is false.
inline bool fits_float(double v) { return std::isfinite(static_cast<float>(v)); }
/// fits_float for every component of v.
inline bool fits_float(const Vec3& v) { return fits_float(v.x) && fits_float(v.y) && fits_float(v.z); }
/// Throws Error unless fits_float(v), for values stored as float: a non-finite v reads as
/// require_finite's "<where>: must be finite, got nan", a finite one beyond the range as
/// "<where>: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+39".
void require_float(double v, std::string_view where);
/// Throws Error unless fits_float(v), naming `where` and v as "(x, y, z)": "must be finite"
/// when a component is NaN or infinite, else "must fit a float".
void require_float(const Vec3& v, std::string_view where);
/// Throws Error unless fits_float(sum), for a value stored as float that the caller computed
/// from finite inputs, which `terms` names with their values ("the entity's position
/// (1e+308, 0, 0) + pose.position (1e+308, 0, 0)"): "<where>: <terms> = (inf, 0, 0) does not fit
/// a float (|component| <= 3.4028234663852886e+38)". A sum that overflowed a double reads so
/// too, where require_float's "must be finite" blamed the value, not its finite inputs.
void require_float_sum(const Vec3& sum, std::string_view terms, std::string_view where);
/// Throws Error unless v > 0 and 1 / v is a normal float (v in about [2.9e-39, 8.5e37]):
/// for a mass stored as its float inverse.
void require_float_inverse(double v, std::string_view where);
/// Formats a byte count for error messages: "512 B", "6.4 GiB", "466 TiB" (3 significant digits).
std::string format_bytes(double bytes);

/// True when every component of v is finite.
template <class V>
bool is_finite(const V& v) {
  if constexpr (std::is_arithmetic_v<V>) {
    return std::isfinite(v);
  } else {
    for (int i = 0; i < V::length(); ++i)
      if (!std::isfinite(v[i])) return false;
    return true;
  }
}

/// Where a simulation's state first became non-finite: the object's index and
/// kind, the simulated time (s) and step. `ok` is true when everything is finite.
struct FiniteCheck {
  bool ok = true;           ///< true when every checked value is finite
  std::size_t index = 0;    ///< index of the first non-finite object
  std::string message;      ///< human-readable report, empty when ok
};

/// Scans positions and velocities of `kind` objects (e.g. "particle") for NaN or
/// infinity. On failure the message reads
/// "particle 3 became non-finite at t = 1.25 s (step 75): position (nan, 0, 1)".
template <class V>
FiniteCheck check_finite(std::span<const V> x, std::span<const V> v, std::string_view kind, double t,
                         long long step);

/// 64-bit FNV-1a over raw bytes, for state hashes in tests and benchmarks.
/// Hashes bit patterns, so +0.0 and -0.0 differ, as determinism requires.
std::uint64_t hash_bytes(const void* data, std::size_t size,
                         std::uint64_t seed = 0xcbf29ce484222325ULL);

/// Hash of a contiguous array of trivially-copyable values (vectors, doubles).
template <class T>
std::uint64_t hash_span(std::span<const T> values, std::uint64_t seed = 0xcbf29ce484222325ULL) {
  return hash_bytes(values.data(), values.size_bytes(), seed);
}

/// Monotonic wall-clock stopwatch for profiling; seconds as double.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  /// Restarts timing from now.
  void reset() { start_ = std::chrono::steady_clock::now(); }
  /// Seconds elapsed since construction or the last reset().
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace pba
