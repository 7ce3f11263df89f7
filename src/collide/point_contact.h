// Private: the one point-versus-shape contact of the collide module, for every client.
//
// A point (a particle's centre, a soft-body node) against a collider's flat form
// (detail::FlatShape, pba/collide/collision_world.h), in two forms over the same shapes:
//
//   swept_*      the segment from the point's start (against the start pose) to its end
//                (against the end pose), the shape grown by the point's radius: the
//                contact plane where the point first meets it, with the signed
//                distances at both ends of the step (the particles' continuous
//                collision: nothing passes through at any speed);
//   point_contact  where the point is now, the shape at pose fraction f of the step and
//                grown by a thickness: the outward normal and the depth (the soft
//                bodies' position- and velocity-level contacts).
//
// Every function is an inline template over the scalar (float in the vectorised
// particle kernel, double for soft bodies), scalar per point and written so that GCC
// if-converts and vectorises the loops that call it; each keeps the exact order of
// operations the particle and soft-body code had when each kept its own copy, so the
// results are the same bits. Plane, sphere, box and capsule inline; convex hulls,
// triangle meshes and compounds out of line, in double (point_contact_shapes.cpp): the
// generic path, which the float kernel reaches by the same dispatch on the shape type.
#pragma once

#include <cmath>

#include "pba/collide/collision_world.h"

#if defined(__GNUC__)
#define PBA_CONTACT_INLINE inline __attribute__((always_inline))
#else
#define PBA_CONTACT_INLINE inline
#endif

namespace pba::detail {

/// Where a moving point meets a surface: the unit normal of the contact plane, the
/// signed distances of the point's surface from it at the start (s0 >= 0) and the end
/// (s1 < 0) of the step, the plane's offset at the end (n . x = d1 + r on it) and the
/// surface velocity at the contact.
template <class T>
struct SweptContact {
  T nx, ny, nz;  ///< unit normal (world)
  T s0, s1;      ///< signed distances at the start and the end of the step (m)
  T d1;          ///< plane offset at the end of the step (m)
  T ux, uy, uz;  ///< surface velocity at the contact (m/s)
};

/// Signed distance of a sphere of radius r at p from the plane n . x = d: n . p - d - r.
template <class T>
PBA_CONTACT_INLINE T plane_gap(T nx, T ny, T nz, T d, T px, T py, T pz, T r) {
  return nx * px + ny * py + nz * pz - d - r;
}

/// p -> R^T (p - c) for a column-major rotation r.
template <class T>
PBA_CONTACT_INLINE void to_local(const T* r, T cx, T cy, T cz, T px, T py, T pz, T& lx, T& ly, T& lz) {
  const T dx = px - cx, dy = py - cy, dz = pz - cz;
  lx = r[0] * dx + r[1] * dy + r[2] * dz;
  ly = r[3] * dx + r[4] * dy + r[5] * dz;
  lz = r[6] * dx + r[7] * dy + r[8] * dz;
}

/// The surface velocity at a point p of a frame whose origin is at c: v + w x (p - c).
template <class T>
PBA_CONTACT_INLINE void surface_velocity(const FlatShape<T>& c, T cx, T cy, T cz, T px, T py, T pz, T& ux, T& uy,
                                         T& uz) {
  const T dx = px - cx, dy = py - cy, dz = pz - cz;
  ux = c.vx + (c.wy * dz - c.wz * dy);
  uy = c.vy + (c.wz * dx - c.wx * dz);
  uz = c.vz + (c.wx * dy - c.wy * dx);
}

/// Spheres, swept: the segment from the start to the end of the step, relative to the
/// moving centre, against the sphere of radius R + r: the first root of
/// |q0 + s d|^2 = (R + r)^2 in [0, 1] (Ericson, "Real-Time Collision Detection", 2005,
/// 5.3.2); a point that starts inside is pushed out along its end offset. Returns false
/// when the point does not end inside.
template <class T>
PBA_CONTACT_INLINE bool swept_sphere(const FlatShape<T>& c, T ox, T oy, T oz, T x, T y, T z, T r,
                                     SweptContact<T>& out) {
  const T R = c.radius + r;
  // relative positions at the start and end
  const T q0x = ox - c.c0x, q0y = oy - c.c0y, q0z = oz - c.c0z;
  const T q1x = x - c.c1x, q1y = y - c.c1y, q1z = z - c.c1z;
  const T dx = q1x - q0x, dy = q1y - q0y, dz = q1z - q0z;
  const T c0 = q0x * q0x + q0y * q0y + q0z * q0z - R * R;
  const T c1 = q1x * q1x + q1y * q1y + q1z * q1z - R * R;
  // quick reject: outside at both ends and the segment's closest approach is outside
  const T a = dx * dx + dy * dy + dz * dz;
  const T b = q0x * dx + q0y * dy + q0z * dz;  // half of the linear coefficient
  if (c1 >= T(0) && (c0 < T(0) || b >= T(0) || a <= T(0) || b * b - a * c0 < T(0))) return false;
  T nx, ny, nz;
  bool crossed = false;
  if (c0 >= T(0)) {
    // entering: first root of a s^2 + 2 b s + c0 = 0
    const T disc = b * b - a * c0;
    const T s = (-b - std::sqrt(disc > T(0) ? disc : T(0))) / a;
    if (!(s <= T(1)) && c1 >= T(0)) return false;
    const T sc = s < T(0) ? T(0) : (s > T(1) ? T(1) : s);
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
  const T len = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (len > T(1e-12f)) {
    nx /= len;
    ny /= len;
    nz /= len;
  } else {
    nx = 0;
    ny = 1;
    nz = 0;
  }
  // the tangent plane at the contact point: distances at the start (start pose) and end
  const T s1 = nx * q1x + ny * q1y + nz * q1z - R;
  if (!(s1 < T(0))) return false;
  const T s0 = crossed ? nx * q0x + ny * q0y + nz * q0z - R : T(-1);
  out.nx = nx, out.ny = ny, out.nz = nz;
  out.s0 = s0 > T(0) ? s0 : T(0);
  out.s1 = s1;
  out.d1 = nx * c.c1x + ny * c.c1y + nz * c.c1z + c.radius;
  surface_velocity(c, c.c1x, c.c1y, c.c1z, c.c1x + nx * c.radius, c.c1y + ny * c.radius, c.c1z + nz * c.radius,
                   out.ux, out.uy, out.uz);
  return true;
}

/// Boxes, swept: in the box's frame (start pose for the start point, end pose for the
/// end point) the segment is clipped against the box grown by the point's radius with the
/// slab test (Ericson 2005, 5.3.3): the entry face gives the normal. The grown box has
/// square edges where the exact Minkowski sum is rounded, so near edges and corners the
/// contact is up to r (sqrt(3) - 1) early. A point that starts and ends inside is pushed
/// out of the face of least penetration. Returns false when there is no contact.
template <class T>
PBA_CONTACT_INLINE bool swept_box(const FlatShape<T>& c, T ox, T oy, T oz, T x, T y, T z, T r,
                                  SweptContact<T>& out) {
  const T h[3] = {c.hx + r, c.hy + r, c.hz + r};
  T l0[3], l1[3];
  to_local(c.r0, c.c0x, c.c0y, c.c0z, ox, oy, oz, l0[0], l0[1], l0[2]);
  to_local(c.r1, c.c1x, c.c1y, c.c1z, x, y, z, l1[0], l1[1], l1[2]);
  const bool in1 = std::fabs(l1[0]) < h[0] && std::fabs(l1[1]) < h[1] && std::fabs(l1[2]) < h[2];
  const bool in0 = std::fabs(l0[0]) < h[0] && std::fabs(l0[1]) < h[1] && std::fabs(l0[2]) < h[2];
  int axis = -1;
  T sign = T(1);
  bool crossed = false;
  if (!in0) {
    // slab test of the segment l0 -> l1: latest entry, earliest exit
    T t_enter = T(-3.4e38f), t_exit = T(1);
    int enter_axis = -1;
    T enter_sign = T(1);
    bool miss = false;
    for (int j = 0; j < 3 && !miss; ++j) {
      const T d = l1[j] - l0[j];
      if (std::fabs(d) < T(1e-12f)) {
        if (std::fabs(l0[j]) >= h[j]) miss = true;
        continue;
      }
      // moving toward +: enters through the -h face (normal -1), and vice versa
      T ta = (-h[j] - l0[j]) / d, tb = (h[j] - l0[j]) / d;
      T sg = T(-1);
      if (ta > tb) {
        const T tmp = ta;
        ta = tb;
        tb = tmp;
        sg = T(1);
      }
      if (ta > t_enter) t_enter = ta, enter_axis = j, enter_sign = sg;
      if (tb < t_exit) t_exit = tb;
      if (t_enter > t_exit) miss = true;
    }
    if (miss || enter_axis < 0 || t_enter > T(1) || t_enter < T(-1e-3f)) return false;
    axis = enter_axis;
    sign = enter_sign;
    crossed = true;
  } else if (in1) {
    // started and ended inside: the face of least penetration at the end
    T best = T(3.4e38f);
    for (int j = 0; j < 3; ++j) {
      const T pen = h[j] - std::fabs(l1[j]);
      if (pen < best) best = pen, axis = j, sign = l1[j] >= T(0) ? T(1) : T(-1);
    }
  } else {
    return false;  // started inside, ended outside: already leaving
  }
  // contact plane: local face normal, signed distance of the end point past it
  const T s1 = sign * l1[axis] - h[axis];
  if (!(s1 < T(0))) return false;
  const T nx = c.r1[axis * 3 + 0] * sign, ny = c.r1[axis * 3 + 1] * sign, nz = c.r1[axis * 3 + 2] * sign;
  const T s0 = crossed ? sign * l0[axis] - h[axis] : T(-1);
  const T hs[3] = {c.hx, c.hy, c.hz};
  out.nx = nx, out.ny = ny, out.nz = nz;
  out.s0 = s0 > T(0) ? s0 : T(0);
  out.s1 = s1;
  out.d1 = nx * c.c1x + ny * c.c1y + nz * c.c1z + hs[axis];
  surface_velocity(c, c.c1x, c.c1y, c.c1z, x, y, z, out.ux, out.uy, out.uz);
  return true;
}

/// The earliest s in [0, 1] at which q0 + s d enters the ball of radius R about c (the
/// first root of |q0 - c + s d|^2 = R^2), or 2 when it does not; q0 outside the ball.
template <class T>
PBA_CONTACT_INLINE T ball_entry(const T* q0, const T* d, T cy, T R) {
  const T px = q0[0], py = q0[1] - cy, pz = q0[2];
  const T a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const T b = px * d[0] + py * d[1] + pz * d[2];
  const T c = px * px + py * py + pz * pz - R * R;
  const T disc = b * b - a * c;
  if (!(a > T(0)) || b >= T(0) || disc < T(0)) return T(2);
  const T s = (-b - std::sqrt(disc)) / a;
  return s >= T(0) && s <= T(1) ? s : T(2);
}

/// Capsules, swept: in the capsule's frame (start pose for the start point, end pose for
/// the end point; its core the segment y in [-hh, hh] on the local Y axis) the segment
/// from l0 to l1 against the capsule grown by the point's radius, in closed form: the
/// first entry into the union of the side cylinder (the root of x^2 + z^2 = R^2 with y
/// on the core) and the two end balls (Ericson 2005, 5.3.7 and 5.3.2). The contact
/// normal points from the nearest core point to the point where the path enters; a point
/// that starts inside is pushed out from the core along its end offset.
template <class T>
PBA_CONTACT_INLINE bool swept_capsule(const FlatShape<T>& c, T ox, T oy, T oz, T x, T y, T z, T r,
                                      SweptContact<T>& out) {
  const T R = c.radius + r, hh = c.hh;
  T l0[3], l1[3];
  to_local(c.r0, c.c0x, c.c0y, c.c0z, ox, oy, oz, l0[0], l0[1], l0[2]);
  to_local(c.r1, c.c1x, c.c1y, c.c1z, x, y, z, l1[0], l1[1], l1[2]);
  // squared distances from the core at both ends
  auto core_dist2 = [hh](const T* l) {
    const T cy = l[1] < -hh ? -hh : (l[1] > hh ? hh : l[1]);
    const T dy = l[1] - cy;
    return l[0] * l[0] + dy * dy + l[2] * l[2];
  };
  const T e0 = core_dist2(l0) - R * R, e1 = core_dist2(l1) - R * R;
  const T d[3] = {l1[0] - l0[0], l1[1] - l0[1], l1[2] - l0[2]};
  T p[3];  // where the contact is, in the local frame
  bool crossed = false;
  if (e0 >= T(0)) {
    // entering: the earliest entry into the side or either end ball
    T s = T(2);
    const T a = d[0] * d[0] + d[2] * d[2];
    const T b = l0[0] * d[0] + l0[2] * d[2];
    const T cc = l0[0] * l0[0] + l0[2] * l0[2] - R * R;
    const T disc = b * b - a * cc;
    if (a > T(0) && b < T(0) && disc >= T(0)) {
      const T sc = (-b - std::sqrt(disc)) / a;
      const T yc = l0[1] + sc * d[1];
      if (sc >= T(0) && sc <= T(1) && yc >= -hh && yc <= hh) s = sc;
    }
    const T s_lo = ball_entry(l0, d, -hh, R), s_hi = ball_entry(l0, d, hh, R);
    s = s_lo < s ? s_lo : s;
    s = s_hi < s ? s_hi : s;
    if (s > T(1)) {
      // the path never enters; a point that ends inside (rounding at a grazing entry)
      // is pushed out from where it ended
      if (!(e1 < T(0))) return false;
      p[0] = l1[0], p[1] = l1[1], p[2] = l1[2];
    } else {
      p[0] = l0[0] + s * d[0], p[1] = l0[1] + s * d[1], p[2] = l0[2] + s * d[2];
      crossed = true;
    }
  } else {
    // started inside: push out along the end offset
    if (!(e1 < T(0))) return false;  // already leaving
    p[0] = l1[0], p[1] = l1[1], p[2] = l1[2];
  }
  // the normal from the nearest core point, in the local frame
  const T cy = p[1] < -hh ? -hh : (p[1] > hh ? hh : p[1]);
  T nl[3] = {p[0], p[1] - cy, p[2]};
  const T len = std::sqrt(nl[0] * nl[0] + nl[1] * nl[1] + nl[2] * nl[2]);
  if (len > T(1e-12f)) {
    nl[0] /= len, nl[1] /= len, nl[2] /= len;
  } else {
    nl[0] = T(1), nl[1] = T(0), nl[2] = T(0);
  }
  // the tangent plane there: signed distances at the start (start pose) and the end
  const T s1 = nl[0] * l1[0] + nl[1] * (l1[1] - cy) + nl[2] * l1[2] - R;
  if (!(s1 < T(0))) return false;
  const T s0 = crossed ? nl[0] * l0[0] + nl[1] * (l0[1] - cy) + nl[2] * l0[2] - R : T(-1);
  // to world at the end pose: n = R1 nl, the core point c1 + R1 (0, cy, 0)
  const T* m = c.r1;
  out.nx = m[0] * nl[0] + m[3] * nl[1] + m[6] * nl[2];
  out.ny = m[1] * nl[0] + m[4] * nl[1] + m[7] * nl[2];
  out.nz = m[2] * nl[0] + m[5] * nl[1] + m[8] * nl[2];
  const T qx = c.c1x + m[3] * cy, qy = c.c1y + m[4] * cy, qz = c.c1z + m[5] * cy;
  out.s0 = s0 > T(0) ? s0 : T(0);
  out.s1 = s1;
  out.d1 = out.nx * qx + out.ny * qy + out.nz * qz + c.radius;
  surface_velocity(c, c.c1x, c.c1y, c.c1z, qx + out.nx * c.radius, qy + out.ny * c.radius, qz + out.nz * c.radius,
                   out.ux, out.uy, out.uz);
  return true;
}

/// Where a point is in contact with a surface now: the outward unit normal, the depth
/// (> 0) and the surface velocity at the point.
template <class T>
struct PointContact {
  T nx, ny, nz;  ///< outward unit normal (world)
  T depth;       ///< how far to move along the normal to reach the thickened surface (m)
  T ux, uy, uz;  ///< surface velocity at the point (m/s)
};

/// Hulls, meshes and compounds, swept, in double (point_contact_shapes.cpp): the contact
/// plane where the path from p0 (start pose) to p1 (end pose) of a point of radius r first
/// meets the shape, as the swept_* functions above. `source`, `parts` and `n_parts` are
/// the flat form's links, set by the CollisionWorld (FlatShape::source, parts).
bool swept_generic_d(ShapeType type, const Collider* source, const FlatShape<double>* parts, std::uint32_t n_parts,
                     const Vec3& p0, const Vec3& p1, double r, SweptContact<double>& out);
/// Hulls, meshes and compounds, now (point_contact_shapes.cpp): as point_contact below.
bool point_contact_generic_d(ShapeType type, const Collider* source, const FlatShape<double>* parts,
                             std::uint32_t n_parts, const Vec3& p, double th, double f, PointContact<double>& out);

/// The swept contact of a hull, mesh or compound in T: computed in double, rounded once.
template <class T>
inline bool swept_generic(const FlatShape<T>& c, T ox, T oy, T oz, T x, T y, T z, T r, SweptContact<T>& out) {
  SweptContact<double> q;
  if (!swept_generic_d(c.type, c.source, c.parts, c.n_parts, Vec3(ox, oy, oz), Vec3(x, y, z), r, q)) return false;
  out.nx = T(q.nx), out.ny = T(q.ny), out.nz = T(q.nz);
  out.s0 = T(q.s0), out.s1 = T(q.s1), out.d1 = T(q.d1);
  out.ux = T(q.ux), out.uy = T(q.uy), out.uz = T(q.uz);
  return true;
}

/// The contact of a point p with a collider at step fraction f in [0, 1] (the frame's
/// origin and a plane's offset interpolated linearly between the start and the end of
/// the step, its rotation and normal taken at the end), the surface grown by the
/// thickness th >= 0: a plane's signed distance, a sphere's radial offset, a box's
/// closest point (outside) or nearest face (inside), a capsule's offset from the nearest
/// point of its core segment; hulls, meshes and compounds on the generic path (a hull's
/// exact closest point or deepest face, a mesh's nearest triangle without ghost normals,
/// a compound's deepest child). Returns false when the point is farther than th from the
/// surface.
template <class T>
PBA_CONTACT_INLINE bool point_contact(const FlatShape<T>& c, T px, T py, T pz, T th, T f, PointContact<T>& out) {
  const T cx = c.c0x + (c.c1x - c.c0x) * f, cy = c.c0y + (c.c1y - c.c0y) * f, cz = c.c0z + (c.c1z - c.c0z) * f;
  switch (c.type) {
    case ShapeType::Plane: {
      const T d = c.d0 + (c.d1 - c.d0) * f;
      const T phi = c.n1x * px + c.n1y * py + c.n1z * pz - d - th;
      if (phi >= T(0)) return false;
      out.nx = c.n1x, out.ny = c.n1y, out.nz = c.n1z;
      out.depth = -phi;
      break;
    }
    case ShapeType::Sphere: {
      const T rx = px - cx, ry = py - cy, rz = pz - cz;
      const T r2 = rx * rx + ry * ry + rz * rz, R = c.radius + th;
      if (r2 >= R * R) return false;
      const T len = std::sqrt(r2);
      if (len > T(0)) {
        out.nx = rx / len, out.ny = ry / len, out.nz = rz / len;
      } else {
        out.nx = T(0), out.ny = T(1), out.nz = T(0);
      }
      out.depth = R - len;
      break;
    }
    case ShapeType::Box: {
      // local coordinates, the closest point on the box
      const T* m = c.r1;
      T q[3];
      to_local(m, cx, cy, cz, px, py, pz, q[0], q[1], q[2]);
      const T half[3] = {c.hx, c.hy, c.hz};
      T dq[3];
      for (int i = 0; i < 3; ++i) {
        const T lo = q[i] < -half[i] ? -half[i] : q[i];
        dq[i] = q[i] - (half[i] < lo ? half[i] : lo);
      }
      const T d2 = dq[0] * dq[0] + dq[1] * dq[1] + dq[2] * dq[2];
      if (d2 >= th * th) return false;
      T u[3];
      if (d2 > T(0)) {
        // outside, within the thickness: push along the offset from the surface
        const T d = std::sqrt(d2);
        for (int i = 0; i < 3; ++i) u[i] = dq[i] / d;
        out.depth = th - d;
      } else {
        // inside: out through the nearest face
        const T gap[3] = {half[0] - std::fabs(q[0]), half[1] - std::fabs(q[1]), half[2] - std::fabs(q[2])};
        int axis = 0;
        if (gap[1] < gap[axis]) axis = 1;
        if (gap[2] < gap[axis]) axis = 2;
        u[0] = u[1] = u[2] = T(0);
        u[axis] = q[axis] < T(0) ? T(-1) : T(1);
        out.depth = gap[axis] + th;
      }
      // back to world: R u
      out.nx = m[0] * u[0] + m[3] * u[1] + m[6] * u[2];
      out.ny = m[1] * u[0] + m[4] * u[1] + m[7] * u[2];
      out.nz = m[2] * u[0] + m[5] * u[1] + m[8] * u[2];
      break;
    }
    case ShapeType::Capsule: {
      // local coordinates, the nearest point of the core segment
      const T* m = c.r1;
      T q[3];
      to_local(m, cx, cy, cz, px, py, pz, q[0], q[1], q[2]);
      const T ay = q[1] < -c.hh ? -c.hh : (q[1] > c.hh ? c.hh : q[1]);
      T u[3] = {q[0], q[1] - ay, q[2]};
      const T d2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], R = c.radius + th;
      if (d2 >= R * R) return false;
      const T d = std::sqrt(d2);
      if (d > T(0)) {
        u[0] /= d, u[1] /= d, u[2] /= d;
      } else {
        u[0] = T(1), u[1] = T(0), u[2] = T(0);  // on the axis: out along local x
      }
      out.depth = R - d;
      out.nx = m[0] * u[0] + m[3] * u[1] + m[6] * u[2];
      out.ny = m[1] * u[0] + m[4] * u[1] + m[7] * u[2];
      out.nz = m[2] * u[0] + m[5] * u[1] + m[8] * u[2];
      break;
    }
    case ShapeType::Hull:
    case ShapeType::Mesh:
    case ShapeType::Compound: {
      // the generic path, in double
      PointContact<double> q;
      if (!point_contact_generic_d(c.type, c.source, c.parts, c.n_parts, Vec3(px, py, pz), th, f, q)) return false;
      out.nx = T(q.nx), out.ny = T(q.ny), out.nz = T(q.nz), out.depth = T(q.depth);
      out.ux = T(q.ux), out.uy = T(q.uy), out.uz = T(q.uz);
      return true;
    }
  }
  surface_velocity(c, cx, cy, cz, px, py, pz, out.ux, out.uy, out.uz);
  return true;
}

}  // namespace pba::detail
