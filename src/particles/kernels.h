// Private: the particle kernels, written on plain float columns so the compiler
// vectorises them. Each works on one block of at most kBlock particles (a few KB, in L1).
// The fused semi-implicit Euler step and the generic integrator path call the same
// functions in the same order, so both give the same bits.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "collide/point_contact.h"
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

// True when q is a unit quaternion within require_unit_quat's 1e-6 (false for a non-finite
// one): the validators of definitions checked at every step test this first and build the
// field path of the message only when it fails, so a valid step does not allocate.
inline bool is_unit_quat(const Quat& q) {
  return std::abs(std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z) - 1) <= 1e-6;
}

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

/// A collider flattened for the kernel over one tick: the collide module's flat form in
/// float, computed once per tick by the CollisionWorld.
using ColliderParams = FlatShape<float>;


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

// The contact state of a step that met a plane (s0, s1: signed distances at the start and
// end of the step): the time of impact f = s0 / (s0 - s1) (1 when the particle started
// inside), and position and velocity interpolated to it (a particle that started inside is
// pushed out onto the plane). respond() acts on it, record_contact_inline() records it.
// Branch-free (the division is taken unconditionally and selected), so loops vectorise.
struct ImpactState {
  float f, px, py, pz, vx, vy, vz;
};
PBA_INLINE ImpactState impact_state(float x, float y, float z, float vx, float vy, float vz, float ox, float oy,
                                    float oz, float ovx, float ovy, float ovz, float nx, float ny, float nz, float s0,
                                    float s1) {
  const bool crossed = s0 >= 0.0f;
  const float den = s0 - s1;
  const float f_raw = s0 / (den > 0.0f ? den : 1.0f);
  const float f = (crossed & (den > 0.0f)) ? f_raw : 1.0f;
  const float push_in = crossed ? 0.0f : (s1 < 0.0f ? -s1 : 0.0f);
  return {f,
          ox + f * (x - ox) + push_in * nx,
          oy + f * (y - oy) + push_in * ny,
          oz + f * (z - oz) + push_in * nz,
          ovx + f * (vx - ovx),
          ovy + f * (vy - ovy),
          ovz + f * (vz - ovz)};
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
  const ImpactState c = impact_state(x, y, z, vx, vy, vz, ox, oy, oz, ovx, ovy, ovz, nx, ny, nz, s0, s1);
  const float f = c.f, pcx = c.px, pcy = c.py, pcz = c.pz, vcx = c.vx, vcy = c.vy, vcz = c.vz;
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

/// Where the kernels record contacts (ParticleSystem::set_record_contacts): the handle slot
/// of each particle of the block (kNoSlot for an anonymous one) and the logs by slot. With
/// `owner` null, recording is off and a kernel only tests that pointer, once per contact or
/// per block.
struct ContactSink {
  const std::uint32_t* owner = nullptr;  // per particle of the block (offset to the block)
  ContactLog* logs = nullptr;            // by handle slot
  long long step = 0;                    // the number of the step being taken
};
/// The slot of a particle without a handle.
inline constexpr std::uint32_t kNoSlot = 0xffffffffu;

// Records that particle k met collider ci, with the time of impact and the contact state
// that respond() computes from the same values (before it changes them): the normal, the
// contact point on the surface and the normal speed toward it there.
PBA_INLINE void record_contact_inline(const ContactSink& sink, int k, std::uint32_t ci, float x, float y, float z,
                                      float vx, float vy, float vz, float ox, float oy, float oz, float ovx, float ovy,
                                      float ovz, float nx, float ny, float nz, float s0, float s1, float r, float usx,
                                      float usy, float usz) {
  const std::uint32_t slot = sink.owner[k];
  if (slot == kNoSlot) return;
  ContactLog& log = sink.logs[slot];
  if (log.step != sink.step) log.step = sink.step, log.count = 0;
  if (log.count == kMaxParticleContacts) return;
  // respond()'s contact state
  const ImpactState at = impact_state(x, y, z, vx, vy, vz, ox, oy, oz, ovx, ovy, ovz, nx, ny, nz, s0, s1);
  const float vn = (at.vx - usx) * nx + (at.vy - usy) * ny + (at.vz - usz) * nz;
  ParticleContact& c = log.contacts[log.count++];
  c.collider = ci;
  c.normal = Vec3f(nx, ny, nz);
  c.point = Vec3f(at.px - r * nx, at.py - r * ny, at.pz - r * nz);
  c.approach_speed = vn < 0.0f ? -vn : 0.0f;
}

// The same out of line, for the loops that respond one particle at a time: it runs only at
// a contact of a tracked particle, and keeps those loops as small as without recording.
#if defined(__GNUC__)
__attribute__((noinline))
#endif
inline void record_contact(const ContactSink& sink, int k, std::uint32_t ci, float x, float y, float z, float vx,
                           float vy, float vz, float ox, float oy, float oz, float ovx, float ovy, float ovz, float nx,
                           float ny, float nz, float s0, float s1, float r, float usx, float usy, float usz) {
  record_contact_inline(sink, k, ci, x, y, z, vx, vy, vz, ox, oy, oz, ovx, ovy, ovz, nx, ny, nz, s0, s1, r, usx, usy,
                        usz);
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
                               const ColliderParams& c, float threshold, float h, int& bad, const ContactSink& sink,
                               std::uint32_t ci) {
  const float nx = c.n1x, ny = c.n1y, nz = c.n1z, d1 = c.d1;
  const float n0x = Static ? nx : c.n0x, n0y = Static ? ny : c.n0y, n0z = Static ? nz : c.n0z;
  const float d0 = Static ? d1 : c.d0;
  const float usx = Static ? 0.0f : c.vx, usy = Static ? 0.0f : c.vy, usz = Static ? 0.0f : c.vz;
  const float inv_h = 1.0f / h;
  // a cheap vectorised pass first: which particles end behind the plane
  alignas(64) std::uint8_t hits[kBlock];
  int count = 0;
  for (int k = 0; k < n; ++k) {
    const bool hit = plane_gap(nx, ny, nz, d1, x[k], y[k], z[k], radius[k]) < 0.0f;
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
      const float s0 = plane_gap(n0x, n0y, n0z, d0, ox[k], oy[k], oz[k], r);
      const float s1 = plane_gap(nx, ny, nz, d1, x[k], y[k], z[k], r);
      if (sink.owner)
        record_contact(sink, k, ci, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k],
                       nx, ny, nz, s0, s1, r, usx, usy, usz);
      respond(true, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k], nx, ny, nz,
              s0, s1, d1, r, usx, usy, usz, c.e, c.mu, threshold, h, inv_h);
      bad |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
    }
    return count;
  }
  // many contacts (particles resting on the ground): the tracked ones' records first (the
  // loop below overwrites what they are made from), then everyone, vectorised
  if (sink.owner)
    for (int k = 0; k < n; ++k) {
      if (!hits[k]) continue;
      const float r = radius[k];
      const float s0 = plane_gap(n0x, n0y, n0z, d0, ox[k], oy[k], oz[k], r);
      const float s1 = plane_gap(nx, ny, nz, d1, x[k], y[k], z[k], r);
      record_contact_inline(sink, k, ci, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k],
                            ovz[k], nx, ny, nz, s0, s1, r, usx, usy, usz);
    }
  int flag = 0;
  for (int k = 0; k < n; ++k) {
    // signed distances of the particle's surface from the plane, start and end
    const float r = radius[k];
    const float s0 = plane_gap(n0x, n0y, n0z, d0, ox[k], oy[k], oz[k], r);
    const float s1 = plane_gap(nx, ny, nz, d1, x[k], y[k], z[k], r);
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
                             int& bad, const ContactSink& sink, std::uint32_t ci) {
  if (c.is_static)
    return collide_plane_t<true>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad,
                                 sink, ci);
  return collide_plane_t<false>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad, sink,
                                ci);
}

// spheres, boxes, capsules, hulls, meshes and compounds: the collide module's swept point
// contact (collide/point_contact.h) finds the contact plane of each particle's path, then
// the shared response handles it. A particle whose path enters the shape is caught at
// any speed.
template <bool (*Contact)(const ColliderParams&, float, float, float, float, float, float, float,
                          SweptContact<float>&)>
PBA_INLINE int collide_swept(int n, const float* ox, const float* oy, const float* oz, const float* ovx,
                             const float* ovy, const float* ovz, float* x, float* y, float* z, float* vx, float* vy,
                             float* vz, const float* radius, const ColliderParams& c, float threshold, float h,
                             int& bad, const ContactSink& sink, std::uint32_t ci) {
  int count = 0;
  for (int k = 0; k < n; ++k) {
    SweptContact<float> q;
    if (!Contact(c, ox[k], oy[k], oz[k], x[k], y[k], z[k], radius[k], q)) continue;
    if (sink.owner)
      record_contact(sink, k, ci, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k],
                     q.nx, q.ny, q.nz, q.s0, q.s1, radius[k], q.ux, q.uy, q.uz);
    respond(true, x[k], y[k], z[k], vx[k], vy[k], vz[k], ox[k], oy[k], oz[k], ovx[k], ovy[k], ovz[k], q.nx, q.ny, q.nz,
            q.s0, q.s1, q.d1, radius[k], q.ux, q.uy, q.uz, c.e, c.mu, threshold, h, 1.0f / h);
    bad |= non_finite6(x[k], y[k], z[k], vx[k], vy[k], vz[k]);
    ++count;
  }
  return count;
}

// every collider against one block, in the order given, the triangle meshes last. A mesh
// is a two-sided surface with no inside: a particle that another surface pushed into it
// (wedged between the two) is pushed out of it at the end of each step, so the other
// surface's response, which replays the step from its start, cannot walk it through the
// mesh step by step
PBA_INLINE int collide_block(int n, const float* ox, const float* oy, const float* oz, const float* ovx,
                             const float* ovy, const float* ovz, float* x, float* y, float* z, float* vx, float* vy,
                             float* vz, const float* radius, const ColliderParams* colliders,
                             std::size_t n_colliders, float threshold, float h, int& bad,
                             const ContactSink& sink = {}) {
  int count = 0;
  bool meshes = false;
  for (std::size_t ci = 0; ci < n_colliders; ++ci) {
    const ColliderParams& c = colliders[ci];
    const auto ci32 = static_cast<std::uint32_t>(ci);
    if (c.type == ShapeType::Mesh) {
      meshes = true;
      continue;
    }
    switch (c.type) {
      case ShapeType::Plane:
        count += collide_plane(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c, threshold, h, bad, sink,
                               ci32);
        break;
      case ShapeType::Sphere:
        count += collide_swept<swept_sphere<float>>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c,
                                                    threshold, h, bad, sink, ci32);
        break;
      case ShapeType::Box:
        count += collide_swept<swept_box<float>>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c,
                                                 threshold, h, bad, sink, ci32);
        break;
      case ShapeType::Capsule:
        count += collide_swept<swept_capsule<float>>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c,
                                                     threshold, h, bad, sink, ci32);
        break;
      case ShapeType::Hull:
      case ShapeType::Mesh:
      case ShapeType::Compound:
        // the generic path: out of line, in double (collide/point_contact_shapes.cpp)
        count += collide_swept<swept_generic<float>>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius, c,
                                                     threshold, h, bad, sink, ci32);
        break;
    }
  }
  for (std::size_t ci = 0; meshes && ci < n_colliders; ++ci)
    if (colliders[ci].type == ShapeType::Mesh)
      count += collide_swept<swept_generic<float>>(n, ox, oy, oz, ovx, ovy, ovz, x, y, z, vx, vy, vz, radius,
                                                   colliders[ci], threshold, h, bad, sink,
                                                   static_cast<std::uint32_t>(ci));
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
  Reach* reach;  // scratch for the broad phase: n_colliders of them (any count)
  float threshold;
  // contact recording: the handle slot per particle (nullptr: off), the logs by slot and
  // the number of the step being taken
  const std::uint32_t* owner = nullptr;
  ContactLog* logs = nullptr;
  long long step = 0;
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
