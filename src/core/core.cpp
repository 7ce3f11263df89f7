// Implementation of pba/core.h: formatting, validation and hashing.
#include "pba/core.h"

#include <charconv>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <limits>

namespace pba {

std::string format_value(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

namespace {
[[noreturn]] void fail(std::string_view where, std::string_view rule, double v) {
  throw Error(std::string(where) + ": " + std::string(rule) + ", got " + format_value(v));
}
}  // namespace

void require_finite(double v, std::string_view where) {
  if (!std::isfinite(v)) fail(where, "must be finite", v);
}

std::string format_vec3(const Vec3& v) {
  // appended piece by piece (GCC 12 warns falsely on chained operator+ of strings)
  std::string s = "(";
  s.append(format_value(v.x)).append(", ").append(format_value(v.y)).append(", ").append(format_value(v.z));
  return s.append(")");
}

std::string field_path(std::string_view where, std::string_view name) {
  std::string s;
  s.reserve(where.size() + name.size() + 2);
  s.append(where);
  if (!where.empty() && where.front() == '/') {
    // a JSON pointer (a scene file's path) goes on as one: "/a/b" + "c[2]" is "/a/b/c/2"
    for (const char c : name) {
      if (c == '[' || c == '.') s.append(1, '/');
      else if (c != ']') s.append(1, c);
    }
    if (name.empty() || name.front() != '[') s.insert(where.size(), 1, '/');
    return s;
  }
  s.append(1, '.').append(name);
  return s;
}

void require_finite(const Vec3& v, std::string_view where) {
  if (!is_finite(v)) throw Error(std::string(where) + ": must be finite, got " + format_vec3(v));
}

void require_unit_quat(const Quat& q, std::string_view where) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!std::isfinite(n) || std::abs(n - 1) > 1e-6)
    throw Error(std::string(where) + ": must be a finite unit quaternion, got (" + format_value(q.w) + ", " +
                format_value(q.x) + ", " + format_value(q.y) + ", " + format_value(q.z) + ")");
}

void require_positive(double v, std::string_view where) {
  if (!std::isfinite(v) || !(v > 0)) fail(where, "must be finite and > 0", v);
}

void require_non_negative(double v, std::string_view where) {
  if (!std::isfinite(v) || !(v >= 0)) fail(where, "must be finite and >= 0", v);
}

void require_in_range(double v, double lo, double hi, std::string_view where) {
  if (!std::isfinite(v) || v < lo || v > hi)
    fail(where, "must be in [" + format_value(lo) + ", " + format_value(hi) + "]", v);
}

void require_count(long long v, long long lo, long long hi, std::string_view where) {
  if (v < lo || v > hi)
    throw Error(std::string(where) + ": must be an integer in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "], got " + std::to_string(v));
}

void require_float(double v, std::string_view where) {
  if (fits_float(v)) return;
  require_finite(v, where);
  fail(where, "must fit a float (|v| <= " + format_value(std::numeric_limits<float>::max()) + ")", v);
}

void require_float(const Vec3& v, std::string_view where) {
  if (fits_float(v)) return;
  require_finite(v, where);
  throw Error(std::string(where) + ": must fit a float (|component| <= " +
              format_value(std::numeric_limits<float>::max()) + "), got " + format_vec3(v));
}

void require_float_sum(const Vec3& sum, std::string_view terms, std::string_view where) {
  if (fits_float(sum)) return;
  throw Error(std::string(where) + ": " + std::string(terms) + " = " + format_vec3(sum) +
              " does not fit a float (|component| <= " + format_value(std::numeric_limits<float>::max()) + ")");
}

void require_float_inverse(double v, std::string_view where) {
  // 1 / v rounded to float must be normal: neither infinite nor flushed toward zero
  const float inv = static_cast<float>(1.0 / v);
  if (!(v > 0 && std::isnormal(inv)))
    fail(where,
         "must be in [" + format_value(1.0 / std::numeric_limits<float>::max()) + ", " +
             format_value(1.0 / std::numeric_limits<float>::min()) + "] (its inverse is stored as a normal float)",
         v);
}

std::string format_bytes(double bytes) {
  // binary units, three significant digits
  static constexpr const char* kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  int u = 0;
  while (bytes >= 1024 && u + 1 < static_cast<int>(std::size(kUnits))) {
    bytes /= 1024;
    ++u;
  }
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g %s", bytes, kUnits[u]);
  return buf;
}

namespace {
template <class V>
std::string format_vec(const V& v) {
  if constexpr (std::is_arithmetic_v<V>) {
    return format_value(static_cast<double>(v));
  } else {
    std::string s = "(";
    for (int i = 0; i < V::length(); ++i) {
      if (i) s += ", ";
      s += format_value(static_cast<double>(v[i]));
    }
    return s + ")";
  }
}
}  // namespace

template <class V>
FiniteCheck check_finite(std::span<const V> x, std::span<const V> v, std::string_view kind, double t,
                         long long step) {
  FiniteCheck r;
  // scan both arrays; report the first object whose position or velocity is bad
  const std::size_t n = x.size() < v.size() ? v.size() : x.size();
  for (std::size_t i = 0; i < n; ++i) {
    const bool bad_x = i < x.size() && !is_finite(x[i]);
    const bool bad_v = i < v.size() && !is_finite(v[i]);
    if (!bad_x && !bad_v) continue;
    r.ok = false;
    r.index = i;
    r.message = std::string(kind) + " " + std::to_string(i) + " became non-finite at t = " +
                format_value(t) + " s (step " + std::to_string(step) + "): " +
                (bad_x ? "position " + format_vec(x[i]) : "velocity " + format_vec(v[i]));
    return r;
  }
  return r;
}

template FiniteCheck check_finite<double>(std::span<const double>, std::span<const double>,
                                          std::string_view, double, long long);
template FiniteCheck check_finite<Vec2>(std::span<const Vec2>, std::span<const Vec2>, std::string_view,
                                        double, long long);
template FiniteCheck check_finite<Vec3>(std::span<const Vec3>, std::span<const Vec3>, std::string_view,
                                        double, long long);
template FiniteCheck check_finite<Vec3f>(std::span<const Vec3f>, std::span<const Vec3f>,
                                         std::string_view, double, long long);

std::uint64_t hash_bytes(const void* data, std::size_t size, std::uint64_t seed) {
  // FNV-1a, 64-bit: simple, stable across platforms, fast enough for state hashes
  const auto* p = static_cast<const unsigned char*>(data);
  std::uint64_t h = seed;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 0x100000001b3ULL;
  }
  return h;
}

}  // namespace pba
