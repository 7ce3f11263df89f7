// The fused semi-implicit Euler particle step: forces, forcers, integration, collisions
// and the finite check in one pass over memory, block by block, with a per-block broad
// phase that lets blocks no collider can reach skip the collision code.
#include <algorithm>
#include <cmath>

#include "core/clones.h"
#include "kernels.h"

namespace pba::detail {

namespace {

// lanes of the running minima and maxima: 8 independent accumulators per quantity keep
// the loops vectorised (one AVX2 register each) without reassociating a single operation
constexpr int kLanes = 8;

// Relative slack of every bound below. Each float operation rounds by at most 2^-24
// (6e-8) relative; the longest chain behind a bound has about 20 of them, so 1e-5 covers
// rounding with a factor of 8 to spare.
constexpr double kSlack = 1e-5;


// Kick then drift in place (v += a h; x += v h), the arithmetic of
// Integrator::step_semi_implicit_euler, with gravity and drag computed inline (Inline) or
// the accelerations read from scratch (when there are forcers): the path of a block that
// no collider can reach in the step, so nothing of the start of the step is kept.
// Returns true if something may have become NaN or infinite. A non-finite velocity makes
// the position non-finite too (x + v h with h >= 0), so the positions are summed: a sum
// with a NaN or an infinity in it is not finite. (A sum of huge finite positions can
// overflow too; the caller's full check then finds nothing and carries on.)
template <bool Inline>
PBA_INLINE bool kick_drift(int n, float* PBA_RESTRICT x, float* PBA_RESTRICT y, float* PBA_RESTRICT z,
                           float* PBA_RESTRICT vx, float* PBA_RESTRICT vy, float* PBA_RESTRICT vz,
                           const float* PBA_RESTRICT im, const ForceParams& f, const float* PBA_RESTRICT ax,
                           const float* PBA_RESTRICT ay, const float* PBA_RESTRICT az, float h) {
  float sum[kLanes] = {0, 0, 0, 0, 0, 0, 0, 0};
  auto particle = [&](int k, int j) __attribute__((always_inline)) {
    float a0, a1, a2;
    if constexpr (Inline) {
      gravity_drag(vx[k], vy[k], vz[k], im[k], f, a0, a1, a2);
    } else {
      a0 = ax[k];
      a1 = ay[k];
      a2 = az[k];
    }
    vx[k] += a0 * h;
    vy[k] += a1 * h;
    vz[k] += a2 * h;
    const float px = x[k] + vx[k] * h, py = y[k] + vy[k] * h, pz = z[k] + vz[k] * h;
    x[k] = px;
    y[k] = py;
    z[k] = pz;
    sum[j] += (px + py) + pz;
  };
  const int n8 = n & ~(kLanes - 1);
  for (int k0 = 0; k0 < n8; k0 += kLanes)
    for (int j = 0; j < kLanes; ++j) particle(k0 + j, j);
  for (int k = n8; k < n; ++k) particle(k, k - n8);
  float total = 0;
  for (int j = 0; j < kLanes; ++j) total += sum[j];
  return (total - total) != 0.0f;
}

// The exact path: keep the start of the step for the swept tests, kick and drift, check
// the new state, then every collider against the block. Returns the contacts; `bad` is
// set when something became non-finite; the tracked particles' contacts go to `sink`.
PBA_INLINE int exact_block(int n, float* PBA_RESTRICT x, float* PBA_RESTRICT y, float* PBA_RESTRICT z,
                           float* PBA_RESTRICT vx, float* PBA_RESTRICT vy, float* PBA_RESTRICT vz,
                           const float* PBA_RESTRICT ax, const float* PBA_RESTRICT ay,
                           const float* PBA_RESTRICT az, const float* PBA_RESTRICT radius, float h,
                           const ColliderParams* colliders, std::size_t n_colliders, float threshold, int& bad,
                           const ContactSink& sink) {
  alignas(64) float ox[kBlock], oy[kBlock], oz[kBlock], ovx[kBlock], ovy[kBlock], ovz[kBlock];
  int flag = 0;
  for (int k = 0; k < n; ++k) {
    ox[k] = x[k];
    oy[k] = y[k];
    oz[k] = z[k];
    ovx[k] = vx[k];
    ovy[k] = vy[k];
    ovz[k] = vz[k];
    vx[k] += ax[k] * h;
    vy[k] += ay[k] * h;
    vz[k] += az[k] * h;
    x[k] += vx[k] * h;
    y[k] += vy[k] * h;
    z[k] += vz[k] * h;
    flag |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
  }
  bad |= flag;
  // swept collisions against every surface; each checks the particles it changed
  return collide_block(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, colliders, n_colliders, threshold,
                       h, bad, sink);
}

// The block's bounds measured from its state: the box around the positions and a bound on
// |v| (covering the rounding of v . v and of the square root); with Full, the largest
// radius and inverse mass too (after the exact path; they change only with the particles).
template <bool Full>
PBA_INLINE void measure_block(int n, const float* PBA_RESTRICT x, const float* PBA_RESTRICT y,
                              const float* PBA_RESTRICT z, const float* PBA_RESTRICT vx,
                              const float* PBA_RESTRICT vy, const float* PBA_RESTRICT vz,
                              const float* PBA_RESTRICT im, const float* PBA_RESTRICT radius, BlockBounds& out) {
  // per-lane running extremes (8 independent accumulators keep the loop vectorised
  // without reassociating anything)
  float lo0[kLanes], lo1[kLanes], lo2[kLanes], hi0[kLanes], hi1[kLanes], hi2[kLanes];
  float v2[kLanes], rr[kLanes], mm[kLanes];
  for (int j = 0; j < kLanes; ++j) {
    lo0[j] = lo1[j] = lo2[j] = 3.4e38f;
    hi0[j] = hi1[j] = hi2[j] = -3.4e38f;
    v2[j] = rr[j] = mm[j] = 0.0f;
  }
  auto particle = [&](int k, int j) __attribute__((always_inline)) {
    lo0[j] = x[k] < lo0[j] ? x[k] : lo0[j];
    lo1[j] = y[k] < lo1[j] ? y[k] : lo1[j];
    lo2[j] = z[k] < lo2[j] ? z[k] : lo2[j];
    hi0[j] = x[k] > hi0[j] ? x[k] : hi0[j];
    hi1[j] = y[k] > hi1[j] ? y[k] : hi1[j];
    hi2[j] = z[k] > hi2[j] ? z[k] : hi2[j];
    const float s = vx[k] * vx[k] + vy[k] * vy[k] + vz[k] * vz[k];
    v2[j] = s > v2[j] ? s : v2[j];
    if constexpr (Full) {
      rr[j] = radius[k] > rr[j] ? radius[k] : rr[j];
      mm[j] = im[k] > mm[j] ? im[k] : mm[j];
    }
  };
  const int n8 = n & ~(kLanes - 1);
  for (int k0 = 0; k0 < n8; k0 += kLanes)
    for (int j = 0; j < kLanes; ++j) particle(k0 + j, j);
  for (int k = n8; k < n; ++k) particle(k, k - n8);
  // fold the lanes; v . v in float is at least (1 - 3 2^-24) of the exact value, so the
  // slack covers it and the square root
  float lo[3] = {lo0[0], lo1[0], lo2[0]}, hi[3] = {hi0[0], hi1[0], hi2[0]};
  float top = v2[0], r = rr[0], m = mm[0];
  for (int j = 1; j < kLanes; ++j) {
    lo[0] = std::min(lo[0], lo0[j]);
    lo[1] = std::min(lo[1], lo1[j]);
    lo[2] = std::min(lo[2], lo2[j]);
    hi[0] = std::max(hi[0], hi0[j]);
    hi[1] = std::max(hi[1], hi1[j]);
    hi[2] = std::max(hi[2], hi2[j]);
    top = std::max(top, v2[j]);
    r = std::max(r, rr[j]);
    m = std::max(m, mm[j]);
  }
  out.maxabs = 0;
  for (int i = 0; i < 3; ++i) {
    out.lo[i] = lo[i];
    out.hi[i] = hi[i];
    out.maxabs = std::max({out.maxabs, std::fabs(out.lo[i]), std::fabs(out.hi[i])});
  }
  out.speed = std::sqrt(static_cast<double>(top)) * (1 + kSlack);
  out.measured = true;
  if constexpr (Full) {
    out.radius = r;
    out.inv_mass = m;
  }
}

// ---------------------------------------------------------------------------------------
// the broad phase

Reach make_reach(const ColliderParams& c) {
  Reach r{};
  r.type = c.type;
  r.n[0] = c.n1x, r.n[1] = c.n1y, r.n[2] = c.n1z, r.d = c.d1;
  r.n1 = std::fabs(r.n[0]) + std::fabs(r.n[1]) + std::fabs(r.n[2]);
  const double c0[3] = {c.c0x, c.c0y, c.c0z}, c1[3] = {c.c1x, c.c1y, c.c1z};
  double path2 = 0;
  for (int i = 0; i < 3; ++i) {
    r.lo[i] = std::min(c0[i], c1[i]);
    r.hi[i] = std::max(c0[i], c1[i]);
    r.maxabs = std::max({r.maxabs, std::fabs(c0[i]), std::fabs(c1[i])});
    path2 += (c1[i] - c0[i]) * (c1[i] - c0[i]);
  }
  r.path = std::sqrt(path2);
  if (c.type == ShapeType::Sphere) r.radius = c.radius;
  if (c.type != ShapeType::Plane && c.type != ShapeType::Sphere) {
    // the circumradius about the frame origin: the box's corners, the capsule's end caps,
    // the farthest corner of a hull's, mesh's or compound's local bounds
    r.radius = c.type == ShapeType::Box ? std::sqrt(double(c.hx) * c.hx + double(c.hy) * c.hy + double(c.hz) * c.hz)
               : c.type == ShapeType::Capsule ? double(c.hh) + double(c.radius)
                                              : double(c.reach);
    double s2 = 0;
    for (int i = 0; i < 9; ++i) s2 += (double(c.r1[i]) - c.r0[i]) * (double(c.r1[i]) - c.r0[i]);
    r.spin = std::sqrt(s2);
  }
  return r;
}

/// The box that a block's particles stay in during a step, their largest radius, and a
/// bound on their speeds at its end: BlockBounds for the next step.
using Swept = BlockBounds;

// The far tests (a swept bounding volume against each collider's, Ericson 2005, 4.2 and
// 5.5): true only if no particle of the block can touch collider c during the step, so
// its exact test would find nothing. P, the swept box, holds every start and end
// position; the margin (kSlack relative to every magnitude involved) is far above the
// float rounding of the exact tests.
//   sphere: the exact test follows the segment from a start to an end position relative
//     to the moving centre, (1 - s) p0 + s p1 - ((1 - s) c0 + s c1): a point of P minus a
//     point of the centre's box C, so never closer than dist(P, C);
//   box: the exact test clips that segment, in the box frame (R0 at the start, R1 at the
//     end), over s in [-1e-3, 1] against the box grown by r, which lies inside the ball
//     of radius |h| + sqrt(3) r. In the frame, |l(s)| >= |(1 - s) a + s b| - ||R1 - R0|| |b|
//     with a = p0 - c0, b = p1 - c1, and |(1 - s) a + s b| >= dist(P, C) less 1e-3 of
//     the two boxes' diameters for the stretch before s = 0;
//   capsule: the same argument as the box, with the capsule grown by r inside the ball of
//     radius hh + R + r <= hh + R + sqrt(3) r about its origin (and s only in [0, 1]);
//   hull: the same as the box: its planes moved out by r are clipped by its local bounds
//     grown by r, inside the ball of radius reach + sqrt(3) r (reach: the bounds' farthest
//     corner); mesh: within r of a triangle, inside the ball of radius reach + r;
//   compound: each leaf as above in its own frame, a fixed placement in the compound's,
//     so inside the ball of radius reach + sqrt(3) r about the compound's origin.
#if defined(__GNUC__)
__attribute__((noinline))
#endif
bool far_from_solid(const Swept& p, const Reach& c) {
  // distance between the two boxes, the diameter and centre of P
  double gap2 = 0, diam2 = 0, mid2 = 0;
  for (int i = 0; i < 3; ++i) {
    const double g = std::max({0.0, p.lo[i] - c.hi[i], c.lo[i] - p.hi[i]});
    gap2 += g * g;
    diam2 += (p.hi[i] - p.lo[i]) * (p.hi[i] - p.lo[i]);
    const double m = 0.5 * (p.lo[i] + p.hi[i]) - c.hi[i];  // |centre of P - c1| <= this box's
    const double m2 = 0.5 * (p.lo[i] + p.hi[i]) - c.lo[i];
    mid2 += std::max(m * m, m2 * m2);
  }
  const double gap = std::sqrt(gap2), diam = std::sqrt(diam2);
  if (c.type == ShapeType::Sphere) {
    const double margin = kSlack * (p.maxabs + c.maxabs + c.radius + p.radius);
    return gap - c.radius - p.radius > margin;
  }
  const double b_max = std::sqrt(mid2) + 0.5 * diam;  // >= |p1 - c1| for p1 in P
  const double reach = c.radius + std::sqrt(3.0) * p.radius;
  const double margin = kSlack * (p.maxabs + c.maxabs + b_max + reach);
  return gap - 1e-3 * (diam + c.path) - c.spin * b_max - reach > margin;
}

// planes inline (the common ground), spheres and boxes out of line. A plane is a
// half-space whose exact test looks only at the end of the step: the corner of P deepest
// along the end normal must be above the end plane by more than the radius.
PBA_INLINE bool far_from(const Swept& p, const Reach& c) {
  if (c.type != ShapeType::Plane) return far_from_solid(p, c);
  double dist = -c.d - p.radius;
  for (int i = 0; i < 3; ++i) dist += c.n[i] * (c.n[i] >= 0 ? p.lo[i] : p.hi[i]);
  return dist > kSlack * (std::fabs(c.d) + p.radius + c.n1 * p.maxabs);
}

/// Bounds on the forces of one step, for how far a particle can move.
struct ForceBounds {
  double g;       // |gravity| (m/s^2)
  double b, c;    // linear and quadratic drag
  double wind;    // |wind| (m/s)
  double forcer;  // sum over the forcers of the largest force (N)
};

ForceBounds force_bounds(const ForceParams& f, const ForcerParams* forcers, std::size_t n_forcers) {
  ForceBounds fb{};
  fb.g = std::sqrt(double(f.gx) * f.gx + double(f.gy) * f.gy + double(f.gz) * f.gz);
  fb.wind = std::sqrt(double(f.wx) * f.wx + double(f.wy) * f.wy + double(f.wz) * f.wz);
  fb.b = f.b;
  fb.c = f.c;
  // a fan pushes with |F| = strength; a vortex with at most |strength| + |pull| (tangent
  // and pull are along orthogonal unit vectors); an attractor with at most |strength|
  for (std::size_t i = 0; i < n_forcers; ++i) {
    const ForcerParams& p = forcers[i];
    if (p.kind == ForcerKind::Fan)
      fb.forcer += std::sqrt(double(p.fx) * p.fx + double(p.fy) * p.fy + double(p.fz) * p.fz);
    else
      fb.forcer += std::fabs(double(p.strength)) + (p.kind == ForcerKind::Vortex ? std::fabs(double(p.pull)) : 0.0);
  }
  return fb;
}

// The largest acceleration (m/s^2) of a particle with inverse mass at most im whose speed
// relative to the air is at most u: |g - (1/m)(b + c|u|) u + F/m| <= |g| + im (b + c u) u + im F.
PBA_INLINE double max_accel(const ForceBounds& fb, double im, double u) {
  return fb.g + im * (fb.b + fb.c * u) * u + im * fb.forcer;
}

// The swept box of a block over a step of length h from its bounds at the start: every
// |v| <= speed now, so after the kick |v'| <= speed + h a_max, and each coordinate moves by
// at most h |v'| plus the rounding of x + v' h (relative to |x|). The box holds every
// start and end position.
PBA_INLINE Swept sweep(const BlockBounds& bb, const ForceBounds& fb, double h) {
  Swept s = bb;
  s.speed = (bb.speed + h * max_accel(fb, bb.inv_mass, bb.speed + fb.wind)) * (1 + kSlack);
  const double reach = h * s.speed * (1 + kSlack) + kSlack * bb.maxabs;
  for (int i = 0; i < 3; ++i) {
    s.lo[i] = bb.lo[i] - reach;
    s.hi[i] = bb.hi[i] + reach;
  }
  s.maxabs = bb.maxabs + reach;
  s.measured = false;
  return s;
}

// True when no collider can reach any particle of the block in this step.
PBA_INLINE bool far_from_all(const Swept& s, const Reach* reach, std::size_t n) {
  for (std::size_t c = 0; c < n; ++c)
    if (!far_from(s, reach[c])) return false;
  return true;
}

}  // namespace

// compiled for AVX2 and for the baseline, same bits: PBA_CLONES (core/clones.h)
PBA_CLONES
FusedResult fused_semi_implicit_euler(const FusedArgs& a) {
  FusedResult out;
  // a uniform inverse mass or radius: one L1 array of the value stands in for the column
  alignas(64) float im_value[kBlock], r_value[kBlock];
  std::fill(im_value, im_value + kBlock, a.inv_mass_value);
  std::fill(r_value, r_value + kBlock, a.radius_value);
  // the step's force bounds and the colliders' reach, for the broad phase
  const ForceBounds fb = force_bounds(a.forces, a.forcers, a.n_forcers);
  Reach* reach = a.reach;
  const bool use_bounds = a.broad_phase;
  if (use_bounds)
    for (std::size_t c = 0; c < a.n_colliders; ++c) reach[c] = make_reach(a.colliders[c]);
  alignas(64) float ax[kBlock], ay[kBlock], az[kBlock];
  for (std::size_t b = 0; b < a.n; b += kBlock) {
    const int n = static_cast<int>(std::min<std::size_t>(a.n - b, kBlock));
    float *x = a.x + b, *y = a.y + b, *z = a.z + b, *vx = a.vx + b, *vy = a.vy + b, *vz = a.vz + b;
    const float* im = a.inv_mass ? a.inv_mass + b : im_value;
    const float* radius = a.radius ? a.radius + b : r_value;
    BlockBounds& bb = a.bounds[b / kBlock];
    // the broad phase: is the block out of every collider's reach? If bounds grown over
    // earlier steps say no, measure the block now and ask again
    bool far = a.n_colliders == 0;
    Swept s;
    if (!far && use_bounds && bb.valid) {
      s = sweep(bb, fb, a.h);
      far = far_from_all(s, reach, a.n_colliders);
      if (!far && !bb.measured) {
        measure_block<false>(n, x, y, z, vx, vy, vz, im, radius, bb);
        s = sweep(bb, fb, a.h);
        far = far_from_all(s, reach, a.n_colliders);
      }
    }
    if (far) {
      // forces and integration alone
      bool bad;
      if (a.n_forcers == 0) {
        bad = kick_drift<true>(n, x, y, z, vx, vy, vz, im, a.forces, nullptr, nullptr, nullptr, a.h);
      } else {
        base_accel(n, vx, vy, vz, im, a.forces, ax, ay, az);
        for (std::size_t f = 0; f < a.n_forcers; ++f) forcer_accel(n, x, y, z, im, a.forcers[f], ax, ay, az);
        bad = kick_drift<false>(n, x, y, z, vx, vy, vz, im, a.forces, ax, ay, az, a.h);
      }
      // the swept box holds the end positions: the bounds of the next step (they only
      // grow until measure_block refreshes them)
      if (a.n_colliders == 0) {
        bb.valid = false;  // nothing to keep bounds for
      } else {
        bb = s;
        bb.valid = !bad;
      }
      if (bad) out.non_finite = true;
      continue;
    }
    // near a surface, or nothing known: the exact path. A block that touched a surface
    // will be near it next step too, so only one that did not is measured for the next
    // step's broad phase
    int bad = 0;
    base_accel(n, vx, vy, vz, im, a.forces, ax, ay, az);
    for (std::size_t f = 0; f < a.n_forcers; ++f) forcer_accel(n, x, y, z, im, a.forcers[f], ax, ay, az);
    const ContactSink sink{a.owner ? a.owner + b : nullptr, a.logs, a.step};
    const int hits = exact_block(n, x, y, z, vx, vy, vz, ax, ay, az, radius, a.h, a.colliders, a.n_colliders,
                                 a.threshold, bad, sink);
    out.contacts += static_cast<std::size_t>(hits);
    ++out.exact_blocks;
    bb.valid = false;
    if (use_bounds && hits == 0 && bad == 0) {
      measure_block<true>(n, x, y, z, vx, vy, vz, im, radius, bb);
      bb.valid = std::isfinite(bb.speed);
    }
    if (bad) out.non_finite = true;
  }
  return out;
}

}  // namespace pba::detail
