// Tests for pba/core.h: validation messages, finite checks and state hashing.
#include <gtest/gtest.h>

#include "error_of.h"

#include <limits>
#include <vector>

#include "pba/core.h"

namespace {

using pba::test_support::error_of;

// Field paths join with dots, except a scene file's JSON pointer, which stays a pointer.
TEST(Validate, FieldPathsJoinDotsOrJsonPointers) {
  EXPECT_EQ(pba::field_path("def", "mass"), "def.mass");
  EXPECT_EQ(pba::field_path("def", "waypoints[3]"), "def.waypoints[3]");
  EXPECT_EQ(pba::field_path("/rigid_bodies/10/kinematic", "waypoints"), "/rigid_bodies/10/kinematic/waypoints");
  EXPECT_EQ(pba::field_path("/rigid_bodies/10/kinematic", "waypoints[3]"), "/rigid_bodies/10/kinematic/waypoints/3");
  EXPECT_EQ(pba::field_path("/colliders/0/shape", "half_extents.y"), "/colliders/0/shape/half_extents/y");
}

TEST(Validate, MessagesNameTheValueAndWhere) {
  EXPECT_EQ(error_of([] { pba::require_positive(-0.5, "settings.dt"); }),
            "settings.dt: must be finite and > 0, got -0.5");
  EXPECT_EQ(error_of([] { pba::require_positive(0.0, "settings.dt"); }),
            "settings.dt: must be finite and > 0, got 0");
  EXPECT_EQ(error_of([] { pba::require_finite(std::numeric_limits<double>::quiet_NaN(), "x"); }),
            "x: must be finite, got nan");
  EXPECT_EQ(error_of([] { pba::require_count(-3, 0, 100, "--substeps"); }),
            "--substeps: must be an integer in [0, 100], got -3");
  EXPECT_EQ(error_of([] { pba::require_positive(0.25, "ok"); }), "");
}

TEST(CheckFinite, ReportsFirstBadObjectWithTimeAndStep) {
  std::vector<pba::Vec3> x{{0, 0, 0}, {1, std::numeric_limits<double>::infinity(), 0}};
  std::vector<pba::Vec3> v{{0, 0, 0}, {0, 0, 0}};
  auto r = pba::check_finite<pba::Vec3>(x, v, "particle", 1.25, 75);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.index, 1u);
  EXPECT_EQ(r.message, "particle 1 became non-finite at t = 1.25 s (step 75): position (1, inf, 0)");
  x[1].y = 2;
  EXPECT_TRUE((pba::check_finite<pba::Vec3>(x, v, "particle", 1.25, 75).ok));
}

TEST(Hash, SensitiveToEveryBitAndStable) {
  std::vector<double> a{1.0, 2.0, 3.0};
  const auto h = pba::hash_span<double>(a);
  // FNV-1a is a fixed function of the bytes: the same array hashes the same
  EXPECT_EQ(h, pba::hash_span<double>(std::vector<double>{1.0, 2.0, 3.0}));
  // one ulp anywhere changes the hash
  a[1] = std::nextafter(2.0, 3.0);
  EXPECT_NE(h, pba::hash_span<double>(a));
  // the sign of zero is part of the state
  EXPECT_NE(pba::hash_span<double>(std::vector<double>{0.0}),
            pba::hash_span<double>(std::vector<double>{-0.0}));
  // FNV-1a of the empty input is its offset basis
  EXPECT_EQ(pba::hash_bytes(nullptr, 0), 0xcbf29ce484222325ULL);
}

// the float checks sit exactly at float's limits: FLT_MAX fits, the next double up rounds
// to a finite float until halfway to the next power, beyond which it is inf
TEST(Validation, FloatLimits) {
  using pba::test_support::error_of;
  const double fmax = std::numeric_limits<float>::max();
  EXPECT_EQ(error_of([&] { pba::require_float(fmax, "x"); }), "");
  EXPECT_EQ(error_of([&] { pba::require_float(-fmax, "x"); }), "");
  EXPECT_EQ(error_of([] { pba::require_float(1e39, "p.x"); }), "p.x: must fit a float (|v| <= 3.4028234663852886e+38), got 1e+39");
  EXPECT_NE(error_of([] { pba::require_float(pba::Vec3(0, -1e39, 0), "p"); }).find("got (0, -1e+39, 0)"), std::string::npos);
  // fits_float is require_float's test: a double up to half a float step (2^103) past FLT_MAX
  // rounds to FLT_MAX and fits; the halfway point rounds (to even) to infinity and does not
  const double half_step = std::ldexp(1.0, 103);
  for (const double v : {fmax, -fmax, fmax + half_step / 2, std::nextafter(fmax + half_step, 0.0), fmax + half_step,
                         -(fmax + half_step), 1e39, 0.0, 1e-300}) {
    EXPECT_EQ(pba::fits_float(v), std::isfinite(static_cast<float>(v))) << v;
    EXPECT_EQ(pba::fits_float(v), error_of([&] { pba::require_float(v, "x"); }).empty()) << v;
    EXPECT_EQ(pba::fits_float(pba::Vec3(0, v, 0)), error_of([&] { pba::require_float(pba::Vec3(0, v, 0), "x"); }).empty());
  }
  EXPECT_TRUE(pba::fits_float(std::nextafter(fmax + half_step, 0.0)));
  EXPECT_FALSE(pba::fits_float(fmax + half_step));
  // a non-finite value reads as require_finite's message: one call says both
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(pba::fits_float(std::nan("")));
  EXPECT_EQ(error_of([] { pba::require_float(std::nan(""), "p.x"); }), "p.x: must be finite, got nan");
  EXPECT_EQ(error_of([&] { pba::require_float(-inf, "p.x"); }), "p.x: must be finite, got -inf");
  EXPECT_EQ(error_of([&] { pba::require_float(pba::Vec3(1e39, inf, 0), "p"); }), "p: must be finite, got (1e+39, inf, 0)");
  // a mass stored as its float inverse: 1 / m must be a normal float
  EXPECT_EQ(error_of([] { pba::require_float_inverse(1.0, "m"); }), "");
  EXPECT_EQ(error_of([&] { pba::require_float_inverse(1.0 / std::numeric_limits<float>::min(), "m"); }), "");
  EXPECT_NE(error_of([] { pba::require_float_inverse(1e-39, "m"); }), "");   // 1e39 overflows
  EXPECT_NE(error_of([] { pba::require_float_inverse(1e38, "m"); }), "");    // 1e-38 is subnormal
  EXPECT_NE(error_of([] { pba::require_float_inverse(-1, "m"); }), "");
}

TEST(Format, Bytes) {
  EXPECT_EQ(pba::format_bytes(512), "512 B");
  EXPECT_EQ(pba::format_bytes(1024), "1 KiB");
  EXPECT_EQ(pba::format_bytes(6.8e9), "6.33 GiB");
  EXPECT_EQ(pba::format_bytes(double(std::size_t{64} << 30)), "64 GiB");
  EXPECT_EQ(pba::format_bytes(5.12e14), "466 TiB");
}

}  // namespace
