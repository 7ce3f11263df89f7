// The moving-boxes scene of the broad-phase lab, tests and benchmark.
#include "pba/collide/moving_boxes.h"

#include <algorithm>
#include <cmath>

namespace pba {

namespace {

// splitmix64 (Steele, Lea and Flood 2014): a small deterministic stream, the same on every
// platform (std::uniform_real_distribution is not)
std::uint64_t next_u64(std::uint64_t& s) {
  std::uint64_t z = (s += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}
double uniform(std::uint64_t& s, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(next_u64(s) >> 11) * 0x1.0p-53);
}

}  // namespace

MovingBoxes::MovingBoxes(const MovingBoxesDef& def) {
  // check the settings
  require_count(def.count, 1, 10000000, "MovingBoxesDef.count");
  side_ = def.side == 0 ? 1.6 * std::cbrt(static_cast<double>(def.count)) : def.side;
  if (def.side != 0) require_positive(def.side, "MovingBoxesDef.side");
  require_positive(def.min_half, "MovingBoxesDef.min_half");
  require_in_range(def.max_half, def.min_half, 0.5 * side_ * (1 - 1e-9), "MovingBoxesDef.max_half");
  require_non_negative(def.speed, "MovingBoxesDef.speed");
  require_in_range(def.fast_fraction, 0, 1, "MovingBoxesDef.fast_fraction");
  require_non_negative(def.fast_speed, "MovingBoxesDef.fast_speed");

  // sizes, then positions inside the walls, then velocities
  std::uint64_t s = def.seed;
  const auto n = static_cast<std::size_t>(def.count);
  center_.resize(n);
  half_.resize(n);
  velocity_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Vec3& h = half_[i];
    for (int k = 0; k < 3; ++k) h[k] = uniform(s, def.min_half, def.max_half);
    for (int k = 0; k < 3; ++k) center_[i][k] = uniform(s, h[k], side_ - h[k]);
    const double v = uniform(s, 0, 1) < def.fast_fraction ? def.fast_speed : def.speed;
    for (int k = 0; k < 3; ++k) velocity_[i][k] = uniform(s, -v, v);
  }
}

void MovingBoxes::step(double dt) {
  require_non_negative(dt, "MovingBoxes.step(dt)");
  for (std::size_t i = 0; i < center_.size(); ++i) {
    Vec3& c = center_[i];
    Vec3& v = velocity_[i];
    const Vec3& h = half_[i];
    c += v * dt;
    // reflect off the walls: mirror the overshoot back inside and reverse the velocity
    for (int k = 0; k < 3; ++k) {
      const double lo = h[k], hi = side_ - h[k];
      if (c[k] < lo) {
        c[k] = std::min(2 * lo - c[k], hi);
        v[k] = -v[k];
      } else if (c[k] > hi) {
        c[k] = std::max(2 * hi - c[k], lo);
        v[k] = -v[k];
      }
    }
  }
}

}  // namespace pba
