// Private: the particle kernels, written on plain float columns so the compiler
// vectorises them. Each works on one block of at most kBlock particles (a few KB, in L1).
// The fused semi-implicit Euler step and the generic integrator path call the same
// functions in the same order, so both give the same bits.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "pba/particles.h"

#if defined(__GNUC__)
#define PBA_INLINE inline __attribute__((always_inline))
#define PBA_RESTRICT __restrict__
#else
#define PBA_INLINE inline
#define PBA_RESTRICT
#endif

namespace pba::detail {

/// Particles per block: 256 x (3 accelerations + 6 start-of-step values) x 4 bytes = 9 KB
/// of scratch, in L1.
inline constexpr int kBlock = static_cast<int>(kParticleBlock);

/// Gravity, drag and the wind at one time, in float.
struct ForceParams {
  float gx, gy, gz;  // gravity (m/s^2)
  float b, c;        // linear (kg/s) and quadratic (kg/m) drag
  float wx, wy, wz;  // wind (m/s)
};

/// A forcer flattened for the kernel: centre, rotation columns, extents, world push.
struct ForcerParams {
  ForcerKind kind;
  ForcerShape shape;
  float cx, cy, cz;
  float r[9];               // rotation, column-major: column j = local axis j in world
  float hx, hy, hz;         // box half extents, or (radius, half_height, radius)
  float fx, fy, fz;         // fan: force in world (N)
  float ax, ay, az;         // vortex axis (world)
  float strength, pull, softening;
};

/// A collider flattened for the kernel over one step.
struct ColliderParams {
  ShapeType type;
  float e, mu;                       // restitution and friction
  float n0x, n0y, n0z, d0;           // plane at the start of the step
  float n1x, n1y, n1z, d1;           // plane at the end
  float c0x, c0y, c0z, c1x, c1y, c1z;  // sphere/box centre at start and end
  float radius;                      // sphere radius
  float hx, hy, hz;                  // box half extents
  float r0[9], r1[9];                // box rotation at start and end (column-major)
  float vx, vy, vz;                  // linear velocity of the frame origin
  float wx, wy, wz;                  // angular velocity
  bool is_static;                    // same pose at start and end, no velocity
};

// Gravity and drag on one particle: a = g - (1/m) (b + c |u|) u with u = v - wind
// (linear and quadratic drag). Returns |u| (m/s). Every path computes the force with this
// one function, in this order, so all of them give the same bits.
PBA_INLINE float gravity_drag(float vx, float vy, float vz, float inv_mass, const ForceParams& f, float& ax,
                              float& ay, float& az) {
  const float ux = vx - f.wx, uy = vy - f.wy, uz = vz - f.wz;
  const float speed = std::sqrt(ux * ux + uy * uy + uz * uz);
  const float kd = inv_mass * (f.b + f.c * speed);
  ax = f.gx - kd * ux;
  ay = f.gy - kd * uy;
  az = f.gz - kd * uz;
  return speed;
}

// gravity and drag for a block, into a
PBA_INLINE void base_accel(int n, const float* PBA_RESTRICT vx, const float* PBA_RESTRICT vy,
                           const float* PBA_RESTRICT vz, const float* PBA_RESTRICT inv_mass,
                           const ForceParams& f, float* PBA_RESTRICT ax, float* PBA_RESTRICT ay,
                           float* PBA_RESTRICT az) {
  for (int k = 0; k < n; ++k) gravity_drag(vx[k], vy[k], vz[k], inv_mass[k], f, ax[k], ay[k], az[k]);
}

// the force of one forcer on the particles of a block, added to a as F / m
template <ForcerKind K, ForcerShape S>
PBA_INLINE void forcer_accel_t(int n, const float* PBA_RESTRICT x, const float* PBA_RESTRICT y,
                               const float* PBA_RESTRICT z, const float* PBA_RESTRICT inv_mass,
                               const ForcerParams& p, float* PBA_RESTRICT ax, float* PBA_RESTRICT ay,
                               float* PBA_RESTRICT az) {
  const float* r = p.r;
  for (int k = 0; k < n; ++k) {
    // offset from the centre, in world and in the local frame (R^T d)
    const float dx = x[k] - p.cx, dy = y[k] - p.cy, dz = z[k] - p.cz;
    const float lx = r[0] * dx + r[1] * dy + r[2] * dz;
    const float ly = r[3] * dx + r[4] * dy + r[5] * dz;
    const float lz = r[6] * dx + r[7] * dy + r[8] * dz;
    // inside test for the shape
    bool inside;
    if constexpr (S == ForcerShape::Box)
      inside = (std::fabs(lx) <= p.hx) & (std::fabs(ly) <= p.hy) & (std::fabs(lz) <= p.hz);
    else if constexpr (S == ForcerShape::Cylinder)
      inside = (lx * lx + lz * lz <= p.hx * p.hx) & (std::fabs(ly) <= p.hy);
    else
      inside = lx * lx + ly * ly + lz * lz <= p.hx * p.hx;
    // the force for the kind
    float fx, fy, fz;
    if constexpr (K == ForcerKind::Fan) {
      fx = p.fx;
      fy = p.fy;
      fz = p.fz;
    } else if constexpr (K == ForcerKind::Vortex) {
      // radial part of d (perpendicular to the axis), tangent = axis x radial
      const float along = dx * p.ax + dy * p.ay + dz * p.az;
      const float rx = dx - along * p.ax, ry = dy - along * p.ay, rz = dz - along * p.az;
      const float rr = std::sqrt(rx * rx + ry * ry + rz * rz);
      const float inv = rr > 1e-6f ? 1.0f / rr : 0.0f;
      const float tx = p.ay * rz - p.az * ry, ty = p.az * rx - p.ax * rz, tz = p.ax * ry - p.ay * rx;
      fx = (p.strength * tx - p.pull * rx) * inv;
      fy = (p.strength * ty - p.pull * ry) * inv;
      fz = (p.strength * tz - p.pull * rz) * inv;
    } else {
      // toward the centre; magnitude fades linearly inside the softening radius
      const float dist = std::sqrt(dx * dx + dy * dy + dz * dz);
      const float s = -p.strength / (dist > p.softening ? dist : p.softening);
      fx = s * dx;
      fy = s * dy;
      fz = s * dz;
    }
    const float im = inside ? inv_mass[k] : 0.0f;
    ax[k] += im * fx;
    ay[k] += im * fy;
    az[k] += im * fz;
  }
}

// dispatch on kind and shape once per block, never per particle
PBA_INLINE void forcer_accel(int n, const float* x, const float* y, const float* z, const float* inv_mass,
                             const ForcerParams& p, float* ax, float* ay, float* az) {
#define PBA_FORCER_CASE(K, S)                                                        \
  if (p.kind == ForcerKind::K && p.shape == ForcerShape::S) {                        \
    forcer_accel_t<ForcerKind::K, ForcerShape::S>(n, x, y, z, inv_mass, p, ax, ay, az); \
    return;                                                                          \
  }
  PBA_FORCER_CASE(Fan, Box)
  PBA_FORCER_CASE(Fan, Cylinder)
  PBA_FORCER_CASE(Fan, Sphere)
  PBA_FORCER_CASE(Vortex, Box)
  PBA_FORCER_CASE(Vortex, Cylinder)
  PBA_FORCER_CASE(Vortex, Sphere)
  PBA_FORCER_CASE(Attractor, Box)
  PBA_FORCER_CASE(Attractor, Cylinder)
  PBA_FORCER_CASE(Attractor, Sphere)
#undef PBA_FORCER_CASE
}

// 1 if any of the six values is NaN or infinite (x - x is NaN exactly then)
PBA_INLINE int non_finite6(float a, float b, float c, float d, float e, float f) {
  return ((a - a) + (b - b) + (c - c) + (d - d) + (e - e) + (f - f)) != 0.0f;
}

// The response to one contact, shared by every shape and written with selects only, so
// the plane loop vectorises. The contact plane has unit normal n; s0 and s1 are the
// signed distances of the particle's surface from it at the start and the end of the
// step (s(p) = n.p - d1 - r at the end), `hit` says whether to respond at all.
//
// If the particle crossed the plane during the step (s0 >= 0 > s1), the step is split at
// the time of impact f = s0 / (s0 - s1): position and velocity are interpolated to the
// contact (velocity linearly from v0 to v1, the step's mean acceleration), the normal
// velocity relative to the surface (us) is reversed and scaled by e there (0 below the
// restitution threshold: resting contact), and the rest of the step, (1 - f) dt, is
// replayed from the contact with the same mean acceleration. This is exact for constant
// acceleration, so the rebound height does not depend on the integrator or on where in
// the step the impact fell. If it started inside, it is pushed out onto the plane.
// Either way, if the end point is still below the plane (a resting particle that gravity
// pushes down within the step), it is put on the plane and its normal velocity into the
// plane removed: the contact force, with no sinking and no jitter. Friction (Coulomb) then
// removes up to mu times the step's whole normal impulse (bounce plus contact force) from
// the final tangential velocity, never reversing it.
PBA_INLINE void respond(bool hit, float& x, float& y, float& z, float& vx, float& vy, float& vz, float ox, float oy,
                        float oz, float ovx, float ovy, float ovz, float nx, float ny, float nz, float s0, float s1,
                        float d1, float r, float usx, float usy, float usz, float e_surface, float mu,
                        float threshold, float h, float inv_h) {
  // every value is computed unconditionally and chosen by selects (no divisions or
  // square roots behind a condition), so the compiler can if-convert and vectorise
  // time of impact (1 when the particle started inside)
  const bool crossed = s0 >= 0.0f;
  const float den = s0 - s1;
  const float f_raw = s0 / (den > 0.0f ? den : 1.0f);
  const float f = (crossed & (den > 0.0f)) ? f_raw : 1.0f;
  // contact state: interpolated position (pushed out if it started inside) and velocity
  const float push_in = crossed ? 0.0f : (s1 < 0.0f ? -s1 : 0.0f);
  const float pcx = ox + f * (x - ox) + push_in * nx;
  const float pcy = oy + f * (y - oy) + push_in * ny;
  const float pcz = oz + f * (z - oz) + push_in * nz;
  const float vcx = ovx + f * (vx - ovx), vcy = ovy + f * (vy - ovy), vcz = ovz + f * (vz - ovz);
  // bounce: the normal velocity relative to the surface reversed and scaled by e
  const float vn = (vcx - usx) * nx + (vcy - usy) * ny + (vcz - usz) * nz;
  const bool approaching = vn < 0.0f;
  const float e = vn < -threshold ? e_surface : 0.0f;
  const float dvn = approaching ? -(1.0f + e) * vn : 0.0f;  // normal impulse per unit mass
  const float wx = vcx + dvn * nx, wy = vcy + dvn * ny, wz = vcz + dvn * nz;
  // replay the rest of the step from the contact with the mean acceleration
  const float rest = (1.0f - f) * h;
  const float ax = (vx - ovx) * inv_h, ay = (vy - ovy) * inv_h, az = (vz - ovz) * inv_h;
  const float half_rest2 = 0.5f * rest * rest;
  float px = pcx + wx * rest + ax * half_rest2;
  float py = pcy + wy * rest + ay * half_rest2;
  float pz = pcz + wz * rest + az * half_rest2;
  const float ex = wx + ax * rest, ey = wy + ay * rest, ez = wz + az * rest;
  // still below the plane at the end: onto it, and the contact force removes the normal
  // velocity into it
  const float se = nx * px + ny * py + nz * pz - d1 - r;
  const bool below = se < 0.0f;
  const float lift = below ? -se : 0.0f;
  px += lift * nx;
  py += lift * ny;
  pz += lift * nz;
  const float rx = ex - usx, ry = ey - usy, rz = ez - usz;
  const float vn2 = rx * nx + ry * ny + rz * nz;
  const bool stop = below & (vn2 < 0.0f);
  const float vn_end = stop ? 0.0f : vn2;
  const float impulse = dvn + (stop ? -vn2 : 0.0f);
  // Coulomb friction on the tangential velocity for the step's whole normal impulse
  const float tx = rx - vn2 * nx, ty = ry - vn2 * ny, tz = rz - vn2 * nz;
  const float vt = std::sqrt(tx * tx + ty * ty + tz * tz);
  const float mj = mu * impulse;
  const float ratio = mj / (vt > mj ? vt : 1.0f);
  const float scale = vt > mj ? 1.0f - ratio : 0.0f;
  // commit where there was a contact
  x = hit ? px : x;
  y = hit ? py : y;
  z = hit ? pz : z;
  vx = hit ? usx + tx * scale + vn_end * nx : vx;
  vy = hit ? usy + ty * scale + vn_end * ny : vy;
  vz = hit ? usz + tz * scale + vn_end * nz : vz;
}

// planes: branch-free so the loop vectorises. Particles below the plane at the end of
// the step collide; ones above it at the start crossed it during the step (a plane is a
// half-space, so nothing passes through it unseen, at any speed). A static plane (the
// usual ground) gets its own copy of the loop with the surface velocity folded to zero.
template <bool Static>
PBA_INLINE int collide_plane_t(int n, const float* PBA_RESTRICT ox, const float* PBA_RESTRICT oy,
                               const float* PBA_RESTRICT oz, const float* PBA_RESTRICT ovx,
                               const float* PBA_RESTRICT ovy, const float* PBA_RESTRICT ovz, float* PBA_RESTRICT x,
                               float* PBA_RESTRICT y, float* PBA_RESTRICT z, float* PBA_RESTRICT vx,
                               float* PBA_RESTRICT vy, float* PBA_RESTRICT vz, const float* PBA_RESTRICT radius,
                               const ColliderParams& c, float threshold, float h, int& bad) {
  const float nx = c.n1x, ny = c.n1y, nz = c.n1z, d1 = c.d1;
  const float n0x = Static ? nx : c.n0x, n0y = Static ? ny : c.n0y, n0z = Static ? nz : c.n0z;
  const float d0 = Static ? d1 : c.d0;
  const float usx = Static ? 0.0f : c.vx, usy = Static ? 0.0f : c.vy, usz = Static ? 0.0f : c.vz;
  const float inv_h = 1.0f / h;
  // a cheap vectorised pass first: which particles end behind the plane
  alignas(64) std::uint8_t hits[kBlock];
  int count = 0;
  for (int k = 0; k < n; ++k) {
    const bool hit = (nx * x[k] + ny * y[k] + nz * z[k] - d1 - radius[k]) < 0.0f;
    hits[k] = hit ? 1 : 0;
    count += hit ? 1 : 0;
  }
  if (count == 0) return 0;
  // few contacts (particles in flight): respond to those alone, one at a time; the
  // scalar and vector code compute the same IEEE operations, so the bits are the same
  if (count * 4 < n) {
    for (int k = 0; k < n; ++k) {
      if (!hits[k]) continue;
      const float r = radius[k];
      const float s0 = n0x * ox[k] + n0y * oy[k] + n0z * oz[k] - d0 - r;
      const float s1 = nx * x[k] + ny * y[k] + nz * z[k] - d1 - r;
      respond(true, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k], nx, ny, nz,
              s0, s1, d1, r, usx, usy, usz, c.e, c.mu, threshold, h, inv_h);
      bad |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
    }
    return count;
  }
  // many contacts (particles resting on the ground): everyone, vectorised
  int flag = 0;
  for (int k = 0; k < n; ++k) {
    // signed distances of the particle's surface from the plane, start and end
    const float r = radius[k];
    const float s0 = n0x * ox[k] + n0y * oy[k] + n0z * oz[k] - d0 - r;
    const float s1 = nx * x[k] + ny * y[k] + nz * z[k] - d1 - r;
    const bool hit = s1 < 0.0f;
    // respond on copies, then store unconditionally (keeps the loop free of branches)
    float px = x[k], py = y[k], pz = z[k], qx = vx[k], qy = vy[k], qz = vz[k];
    respond(hit, px, py, pz, qx, qy, qz, ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k], nx, ny, nz, s0, s1, d1, r,
            usx, usy, usz, c.e, c.mu, threshold, h, inv_h);
    x[k] = px;
    y[k] = py;
    z[k] = pz;
    vx[k] = qx;
    vy[k] = qy;
    vz[k] = qz;
    flag |= non_finite6(px, py, pz, qx, qy, qz);
  }
  bad |= flag;
  return count;
}

PBA_INLINE int collide_plane(int n, const float* ox, const float* oy, const float* oz, const float* ovx,
                             const float* ovy, const float* ovz, float* x, float* y, float* z, float* vx, float* vy,
                             float* vz, const float* radius, const ColliderParams& c, float threshold, float h,
                             int& bad) {
  if (c.is_static)
    return collide_plane_t<true>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad);
  return collide_plane_t<false>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad);
}

// p -> R^T (p - c) for a column-major rotation
PBA_INLINE void to_local(const float* r, float cx, float cy, float cz, float px, float py, float pz, float& lx,
                         float& ly, float& lz) {
  const float dx = px - cx, dy = py - cy, dz = pz - cz;
  lx = r[0] * dx + r[1] * dy + r[2] * dz;
  ly = r[3] * dx + r[4] * dy + r[5] * dz;
  lz = r[6] * dx + r[7] * dy + r[8] * dz;
}

// the surface velocity at a point: v + w x (p - c)
PBA_INLINE void surface_velocity(const ColliderParams& c, float px, float py, float pz, float& ux, float& uy,
                                 float& uz) {
  const float dx = px - c.c1x, dy = py - c.c1y, dz = pz - c.c1z;
  ux = c.vx + (c.wy * dz - c.wz * dy);
  uy = c.vy + (c.wz * dx - c.wx * dz);
  uz = c.vz + (c.wx * dy - c.wy * dx);
}

// spheres: the segment from the start to the end of the step, relative to the moving
// centre, against the sphere of radius R + r: the first root of |q0 + s d|^2 = (R + r)^2
// in [0, 1] (Ericson, "Real-Time Collision Detection", 2005, 5.3.2). A particle whose
// path enters the sphere is caught at any speed.
PBA_INLINE int collide_sphere(int n, const float* ox, const float* oy, const float* oz, const float* ovx,
                              const float* ovy, const float* ovz, float* x, float* y, float* z, float* vx, float* vy,
                              float* vz, const float* radius, const ColliderParams& c, float threshold, float h,
                              int& bad) {
  int count = 0;
  for (int k = 0; k < n; ++k) {
    const float R = c.radius + radius[k];
    // relative positions at the start and end
    const float q0x = ox[k] - c.c0x, q0y = oy[k] - c.c0y, q0z = oz[k] - c.c0z;
    const float q1x = x[k] - c.c1x, q1y = y[k] - c.c1y, q1z = z[k] - c.c1z;
    const float dx = q1x - q0x, dy = q1y - q0y, dz = q1z - q0z;
    const float c0 = q0x * q0x + q0y * q0y + q0z * q0z - R * R;
    const float c1 = q1x * q1x + q1y * q1y + q1z * q1z - R * R;
    // quick reject: outside at both ends and the segment's closest approach is outside
    const float a = dx * dx + dy * dy + dz * dz;
    const float b = q0x * dx + q0y * dy + q0z * dz;  // half of the linear coefficient
    if (c1 >= 0.0f && (c0 < 0.0f || b >= 0.0f || a <= 0.0f || b * b - a * c0 < 0.0f)) continue;
    float nx, ny, nz;
    bool crossed = false;
    if (c0 >= 0.0f) {
      // entering: first root of a s^2 + 2 b s + c0 = 0
      const float disc = b * b - a * c0;
      const float s = (-b - std::sqrt(disc > 0.0f ? disc : 0.0f)) / a;
      if (!(s <= 1.0f) && c1 >= 0.0f) continue;
      const float sc = s < 0.0f ? 0.0f : (s > 1.0f ? 1.0f : s);
      nx = q0x + sc * dx;
      ny = q0y + sc * dy;
      nz = q0z + sc * dz;
      crossed = true;
    } else {
      // started inside: push out along the end offset
      nx = q1x;
      ny = q1y;
      nz = q1z;
    }
    const float len = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (len > 1e-12f) {
      nx /= len;
      ny /= len;
      nz /= len;
    } else {
      nx = 0;
      ny = 1;
      nz = 0;
    }
    // the tangent plane at the contact point: distances at the start (start pose) and end
    const float s1 = nx * q1x + ny * q1y + nz * q1z - R;
    if (!(s1 < 0.0f)) continue;
    const float s0 = crossed ? nx * q0x + ny * q0y + nz * q0z - R : -1.0f;
    const float d1 = nx * c.c1x + ny * c.c1y + nz * c.c1z + c.radius;
    float ux, uy, uz;
    surface_velocity(c, c.c1x + nx * c.radius, c.c1y + ny * c.radius, c.c1z + nz * c.radius, ux, uy, uz);
    respond(true, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k], nx, ny, nz,
            s0 > 0.0f ? s0 : 0.0f, s1, d1, radius[k], ux, uy, uz, c.e, c.mu, threshold, h, 1.0f / h);
    bad |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
    ++count;
  }
  return count;
}

// boxes: in the box's frame (start pose for the start point, end pose for the end point)
// the segment is clipped against the box grown by the particle radius with the slab test
// (Ericson 2005, 5.3.3): the entry face gives the normal. The grown box has square edges
// where the exact Minkowski sum is rounded, so near edges and corners the contact is up to
// r (sqrt(3) - 1) early. A particle that starts inside is pushed out of the nearest face.
PBA_INLINE int collide_box(int n, const float* ox, const float* oy, const float* oz, const float* ovx,
                           const float* ovy, const float* ovz, float* x, float* y, float* z, float* vx, float* vy,
                           float* vz, const float* radius, const ColliderParams& c, float threshold, float step_h,
                           int& bad) {
  int count = 0;
  for (int k = 0; k < n; ++k) {
    const float r = radius[k];
    const float h[3] = {c.hx + r, c.hy + r, c.hz + r};
    const float dt = step_h;
    float l0[3], l1[3];
    to_local(c.r0, c.c0x, c.c0y, c.c0z, ox[k], oy[k], oz[k], l0[0], l0[1], l0[2]);
    to_local(c.r1, c.c1x, c.c1y, c.c1z, x[k], y[k], z[k], l1[0], l1[1], l1[2]);
    const bool in1 = std::fabs(l1[0]) < h[0] && std::fabs(l1[1]) < h[1] && std::fabs(l1[2]) < h[2];
    const bool in0 = std::fabs(l0[0]) < h[0] && std::fabs(l0[1]) < h[1] && std::fabs(l0[2]) < h[2];
    int axis = -1;
    float sign = 1.0f;
    bool crossed = false;
    if (!in0) {
      // slab test of the segment l0 -> l1: latest entry, earliest exit
      float t_enter = -3.4e38f, t_exit = 1.0f;
      int enter_axis = -1;
      float enter_sign = 1.0f;
      bool miss = false;
      for (int j = 0; j < 3 && !miss; ++j) {
        const float d = l1[j] - l0[j];
        if (std::fabs(d) < 1e-12f) {
          if (std::fabs(l0[j]) >= h[j]) miss = true;
          continue;
        }
        // moving toward +: enters through the -h face (normal -1), and vice versa
        float ta = (-h[j] - l0[j]) / d, tb = (h[j] - l0[j]) / d;
        float sg = -1.0f;
        if (ta > tb) {
          const float tmp = ta;
          ta = tb;
          tb = tmp;
          sg = 1.0f;
        }
        if (ta > t_enter) t_enter = ta, enter_axis = j, enter_sign = sg;
        if (tb < t_exit) t_exit = tb;
        if (t_enter > t_exit) miss = true;
      }
      if (miss || enter_axis < 0 || t_enter > 1.0f || t_enter < -1e-3f) continue;
      axis = enter_axis;
      sign = enter_sign;
      crossed = true;
    } else if (in1) {
      // started and ended inside: the face of least penetration at the end
      float best = 3.4e38f;
      for (int j = 0; j < 3; ++j) {
        const float pen = h[j] - std::fabs(l1[j]);
        if (pen < best) best = pen, axis = j, sign = l1[j] >= 0.0f ? 1.0f : -1.0f;
      }
    } else {
      continue;  // started inside, ended outside: already leaving
    }
    // contact plane: local face normal, signed distance of the end point past it
    const float s1 = sign * l1[axis] - h[axis];
    if (!(s1 < 0.0f)) continue;
    const float nx = c.r1[axis * 3 + 0] * sign, ny = c.r1[axis * 3 + 1] * sign, nz = c.r1[axis * 3 + 2] * sign;
    const float s0 = crossed ? sign * l0[axis] - h[axis] : -1.0f;
    const float hs[3] = {c.hx, c.hy, c.hz};
    const float d1 = nx * c.c1x + ny * c.c1y + nz * c.c1z + hs[axis];
    float ux, uy, uz;
    surface_velocity(c, x[k], y[k], z[k], ux, uy, uz);
    respond(true, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k], nx, ny, nz,
            s0 > 0.0f ? s0 : 0.0f, s1, d1, r, ux, uy, uz, c.e, c.mu, threshold, dt, 1.0f / dt);
    bad |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
    ++count;
  }
  return count;
}

// every collider against one block, in the order given
PBA_INLINE int collide_block(int n, const float* ox, const float* oy, const float* oz, const float* ovx,
                             const float* ovy, const float* ovz, float* x, float* y, float* z, float* vx, float* vy,
                             float* vz, const float* radius, const ColliderParams* colliders,
                             std::size_t n_colliders, float threshold, float h, int& bad) {
  int count = 0;
  for (std::size_t ci = 0; ci < n_colliders; ++ci) {
    const ColliderParams& c = colliders[ci];
    switch (c.type) {
      case ShapeType::Plane:
        count += collide_plane(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad);
        break;
      case ShapeType::Sphere:
        count += collide_sphere(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad);
        break;
      case ShapeType::Box:
        count += collide_box(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad);
        break;
    }
  }
  return count;
}

// 1 if any value of the block is NaN or infinite (x - x is NaN exactly then)
PBA_INLINE int any_non_finite(int n, const float* PBA_RESTRICT a, const float* PBA_RESTRICT b,
                              const float* PBA_RESTRICT c) {
  int bad = 0;
  for (int k = 0; k < n; ++k) bad |= ((a[k] - a[k]) + (b[k] - b[k]) + (c[k] - c[k])) != 0.0f;
  return bad;
}

/// Everything the fused kernel reads besides the columns.
struct FusedArgs {
  float* x;
  float* y;
  float* z;
  float* vx;
  float* vy;
  float* vz;
  const float* inv_mass;  // nullptr: every particle has inv_mass_value
  float inv_mass_value;
  const float* radius;    // nullptr: every particle has radius_value
  float radius_value;
  BlockBounds* bounds;    // one per block, read and updated (the broad phase)
  bool broad_phase;       // false: every block takes the exact collision path
  std::size_t n;
  float h;  // dt
  ForceParams forces;
  const ForcerParams* forcers;
  std::size_t n_forcers;
  const ColliderParams* colliders;
  std::size_t n_colliders;
  float threshold;
};

/// Result of the fused kernel.
struct FusedResult {
  std::size_t contacts = 0;      // collision responses
  std::size_t exact_blocks = 0;  // blocks that ran the exact collision path
  bool non_finite = false;       // some particle became NaN or infinite
};

/// The fused semi-implicit Euler step over all particles (kernels.cpp).
FusedResult fused_semi_implicit_euler(const FusedArgs& a);

}  // namespace pba::detail
