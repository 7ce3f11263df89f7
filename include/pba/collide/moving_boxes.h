// pba collide, a broad-phase scene: boxes flying about inside a closed container, bouncing
// off its walls. One scene for the broad-phase lab sample, the tests and the benchmark
// (the Box2D way: the sample, the test and the benchmark build the same world).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pba/collide/shape.h"
#include "pba/core.h"

namespace pba {

/// Settings of a MovingBoxes scene. Lengths in metres, speeds in m/s.
struct MovingBoxesDef {
  int count = 1000;            ///< boxes, in [1, 10^7]
  double side = 0;             ///< container edge (m); 0 picks 1.6 cbrt(count), as Bullet's collision benchmark
                               ///< does; else finite > 0
  double min_half = 0.2;       ///< smallest half extent (m), finite, > 0
  double max_half = 0.5;       ///< largest half extent (m), finite, >= min_half and < side / 2
  double speed = 1.0;          ///< largest speed of a slow box per axis (m/s), finite, >= 0
  double fast_fraction = 0.1;  ///< share of fast boxes, in [0, 1]
  double fast_speed = 20.0;    ///< largest speed of a fast box per axis (m/s), finite, >= 0
  std::uint64_t seed = 1;      ///< random stream (splitmix64), any value
};

/// Axis-aligned boxes of random sizes and velocities in the container [0, side]^3, moving
/// in straight lines and reflecting off the walls. Deterministic: the same def gives the
/// same boxes bit for bit. step() never allocates.
class MovingBoxes {
 public:
  /// Places the boxes uniformly at random inside the container (throws Error naming the
  /// bad field of `def`).
  explicit MovingBoxes(const MovingBoxesDef& def);
  /// Advances every box by `dt` seconds (finite, >= 0), reflecting it off the walls.
  void step(double dt);
  /// The box of body i (m).
  Aabb box(std::size_t i) const { return {center_[i] - half_[i], center_[i] + half_[i]}; }
  /// Number of boxes.
  std::size_t size() const { return center_.size(); }
  /// Container edge (m).
  double side() const { return side_; }
  /// Centres (m).
  std::span<const Vec3> centers() const { return center_; }
  /// Half extents (m).
  std::span<const Vec3> half_extents() const { return half_; }
  /// Velocities (m/s).
  std::span<const Vec3> velocities() const { return velocity_; }

 private:
  std::vector<Vec3> center_, half_, velocity_;
  double side_ = 0;
};

}  // namespace pba
