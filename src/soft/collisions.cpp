// Soft-body collisions: the collide module's point contact (collide/point_contact.h) at
// every particle, with a position-level response for XPBD and a velocity-level one for
// the mass-spring solver.
#include <algorithm>
#include <cmath>

#include "collide/point_contact.h"
#include "soft_impl.h"

namespace pba::detail {

namespace {

// The contact of particle position p with collider c at step fraction f, the surface
// grown by the thickness th: the outward normal, the depth and the surface velocity.
bool contact(const FlatShape<double>& c, const Vec3& p, double th, double f, Vec3& n, double& depth, Vec3& vs) {
  PointContact<double> q{};
  if (!point_contact(c, p.x, p.y, p.z, th, f, q)) return false;
  n = Vec3(q.nx, q.ny, q.nz);
  depth = q.depth;
  vs = Vec3(q.ux, q.uy, q.uz);
  return true;
}

}  // namespace

// Position-based contacts with Coulomb friction (Macklin, Mueller, Chentanez & Kim 2014,
// "Unified particle physics for real-time applications", section 6.1, eqs. 23-24): the
// particle is projected out along the normal by the depth d, then its tangential
// displacement over the substep relative to the surface, dx_t, is removed entirely when
// |dx_t| < mu s (static friction) and shortened by mu s otherwise (kinetic friction). s is
// the part of the push that stops the substep's approach (the normal impulse times h^2 / m):
// s = d for a particle that entered the thickness in this substep. The rest of the push, out
// of a thickness the particle began the substep inside, only corrects the position: x_prev
// moves with it, so it gives no speed and takes none (a particle moving out keeps its own
// speed), as the mass-spring contact does.
std::size_t collide_particles(SoftBody::Impl& s, double f, double h, double) {
  if (s.colliders.empty()) return 0;
  std::size_t contacts = 0;
  const double th = s.def.thickness;
  const std::size_t n = s.n;
  // the colliders in order, the triangle meshes last (two-sided, with no inside: a node
  // another surface pushed into one leaves it at the end)
  for (int pass = 0; pass < 2; ++pass)
  for (const FlatShape<double>& c : s.colliders) {
    if ((c.type == ShapeType::Mesh) != (pass == 1)) continue;
    // a float bound that rejects most particles cheaply: the plane's signed distance, or
    // the bounding sphere of the solid (enlarged by the thickness and a margin
    // for float rounding; the exact test follows in double)
    const double mu = std::max(s.def.friction, c.mu);
    const Vec3 c0(c.c0x, c.c0y, c.c0z), c1(c.c1x, c.c1y, c.c1z);
    const Vec3 center = c0 + (c1 - c0) * f;
    const float cx = static_cast<float>(center.x), cy = static_cast<float>(center.y), cz = static_cast<float>(center.z);
    const float nx = static_cast<float>(c.n1x), ny = static_cast<float>(c.n1y), nz = static_cast<float>(c.n1z);
    const Vec3 half(c.hx, c.hy, c.hz);
    const double reach = c.type == ShapeType::Sphere    ? c.radius
                         : c.type == ShapeType::Capsule ? c.hh + c.radius
                         : c.type == ShapeType::Box     ? glm::length(half)
                                                        : c.reach;  // hull, mesh, compound
    const float bound = static_cast<float>((reach + th) * (1 + 1e-5) + 1e-6);
    const float bound2 = bound * bound;
    // boxes: the local axes (the columns of R, rows of R^T) and the enlarged half
    // extents, in float
    const double* r = c.r1;
    const float r00 = static_cast<float>(r[0]), r01 = static_cast<float>(r[1]), r02 = static_cast<float>(r[2]);
    const float r10 = static_cast<float>(r[3]), r11 = static_cast<float>(r[4]), r12 = static_cast<float>(r[5]);
    const float r20 = static_cast<float>(r[6]), r21 = static_cast<float>(r[7]), r22 = static_cast<float>(r[8]);
    const float margin = static_cast<float>(th + 1e-5 * (1 + reach));
    const float hx = static_cast<float>(c.hx) + margin, hy = static_cast<float>(c.hy) + margin,
                hz = static_cast<float>(c.hz) + margin;
    const float plane_d = static_cast<float>(c.d0 + (c.d1 - c.d0) * f + th + 1e-6 * (1 + std::abs(c.d1)));
    for (std::size_t i = 0; i < n; ++i) {
      if (s.w[i] == 0.f) continue;
      if (c.type == ShapeType::Plane) {
        if (nx * s.x[i] + ny * s.y[i] + nz * s.z[i] >
            plane_d + 1e-5f * (std::abs(s.x[i]) + std::abs(s.y[i]) + std::abs(s.z[i])))
          continue;
      } else {
        const float dx = s.x[i] - cx, dy = s.y[i] - cy, dz = s.z[i] - cz;
        if (dx * dx + dy * dy + dz * dz > bound2) continue;
        if (c.type == ShapeType::Box &&
            (std::abs(r00 * dx + r01 * dy + r02 * dz) > hx || std::abs(r10 * dx + r11 * dy + r12 * dz) > hy ||
             std::abs(r20 * dx + r21 * dy + r22 * dz) > hz))
          continue;
      }
      Vec3 p(s.x[i], s.y[i], s.z[i]), nrm, vs;
      double depth;
      if (!contact(c, p, th, f, nrm, depth, vs)) continue;
      ++contacts;
      const Vec3 prev(s.px[i], s.py[i], s.pz[i]);
      // the substep's normal displacement relative to the surface before the push (< 0
      // approaching): the push's first -dn0 stops the approach (the normal impulse), the
      // rest, out, only corrects the position
      const double dn0 = glm::dot(p - prev, nrm) - glm::dot(vs, nrm) * h;
      const double out = depth + std::min(0.0, dn0);
      const double stop = depth - std::max(0.0, out);
      p += nrm * depth;
      if (mu > 0) {
        Vec3 dx = (p - prev) - vs * h;
        dx -= glm::dot(dx, nrm) * nrm;
        const double lt = glm::length(dx), lim = mu * stop;
        p -= lt <= lim ? dx : dx * (lim / lt);
      }
      // x_prev moves by the correction, so the velocity update (x - x_prev) / h sees none of it
      if (out > 0) {
        const Vec3 q = prev + nrm * out;
        s.px[i] = static_cast<float>(q.x), s.py[i] = static_cast<float>(q.y), s.pz[i] = static_cast<float>(q.z);
      }
      s.x[i] = static_cast<float>(p.x), s.y[i] = static_cast<float>(p.y), s.z[i] = static_cast<float>(p.z);
    }
  }
  return contacts;
}

// Velocity-level contacts for the mass-spring solver: project out, remove the approaching
// normal velocity relative to the surface (inelastic) and apply Coulomb friction to the
// tangential part: it loses at most mu times the normal velocity change.
std::size_t collide_velocities(SoftBody::Impl& s, std::span<Vec3> xs, std::span<Vec3> vs, double f) {
  if (s.colliders.empty()) return 0;
  std::size_t contacts = 0;
  const double th = s.def.thickness;
  // the colliders in order, the triangle meshes last (two-sided, with no inside: a node
  // another surface pushed into one leaves it at the end)
  for (int pass = 0; pass < 2; ++pass)
  for (const FlatShape<double>& c : s.colliders) {
    if ((c.type == ShapeType::Mesh) != (pass == 1)) continue;
    const double mu = std::max(s.def.friction, c.mu);
    for (std::size_t i = 0; i < xs.size(); ++i) {
      if (s.w[i] == 0.f) continue;
      Vec3 nrm, vsurf;
      double depth;
      if (!contact(c, xs[i], th, f, nrm, depth, vsurf)) continue;
      ++contacts;
      xs[i] += nrm * depth;
      // relative velocity: normal part removed if approaching, friction on the rest
      Vec3 vr = vs[i] - vsurf;
      const double vn = glm::dot(vr, nrm);
      if (vn < 0) {
        vr -= vn * nrm;
        const double lt = glm::length(vr), lim = mu * -vn;
        vr -= lt <= lim ? vr : vr * (lim / lt);
        vs[i] = vr + vsurf;
      }
    }
  }
  return contacts;
}

}  // namespace pba::detail
