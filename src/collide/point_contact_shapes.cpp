// The point contact's generic path: a point (a particle, a soft-body node) against convex
// hulls, triangle meshes and compounds, in double, swept (the particles) and now (the soft
// bodies). The closed forms for planes, spheres, boxes and capsules stay inline in
// point_contact.h; a compound's sphere, box and capsule children use them too.
#include <cmath>
#include <limits>

#include "hull_face.h"
#include "point_contact.h"
#include "query_internal.h"

namespace pba::detail {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// the frame's velocity at the point x: v + w x (x - origin)
void frame_velocity(const Collider& c, const Vec3& origin, const Vec3& x, double& ux, double& uy, double& uz) {
  const Vec3 u = c.velocity + glm::cross(c.angular_velocity, x - origin);
  ux = u.x, uy = u.y, uz = u.z;
}

// the contact plane m . x = m . q + r of a local normal m through the local point q, in
// the world at the end pose, with the local signed distances g0, g1 (start, end) of the
// path from it; g0 < 0 marks a point that did not cross (it started inside)
void set_swept(const Collider& c, const Vec3& m, const Vec3& q, double g0, double g1, const Vec3& p1,
               SweptContact<double>& out) {
  const Vec3 n = c.end.rotation * m;
  out.nx = n.x, out.ny = n.y, out.nz = n.z;
  out.s0 = g0 >= 0 ? g0 : -1.0;
  out.s1 = g1;
  out.d1 = glm::dot(n, c.end.position) + glm::dot(m, q);
  frame_velocity(c, c.end.position, p1, out.ux, out.uy, out.uz);
}

// Hulls, swept: the segment l0 -> l1 in the hull's frame (start pose for l0, end pose for
// l1) clipped against the hull's face planes moved out by r, and against its local bounds
// moved out by r, so the grown hull never reaches past its bounds grown by r however
// sharp its corners (Cyrus & Beck 1978; Ericson 2005, 5.3.8). The entry plane gives the
// normal; like the box (swept_box) the grown hull has flat faces where the exact
// Minkowski sum is rounded, so near edges and corners the contact comes early by at most
// r (sqrt(3) - 1). A point that starts and ends inside leaves by the plane of least
// penetration at the end.
bool hull_swept(const Collider& c, const Vec3& p0, const Vec3& p1, double r, SweptContact<double>& out) {
  const ConvexHull& h = *c.shape.hull;
  const auto faces = h.faces();
  const Aabb b = h.bounds();
  const Vec3 l0 = apply_inverse(c.begin, p0), l1 = apply_inverse(c.end, p1);
  const std::size_t nf = faces.size(), np = nf + 6;
  // plane k: its outward normal and offset (faces, then +x, -x, +y, -y, +z, -z of the bounds)
  auto plane = [&](std::size_t k, Vec3& n, double& d) {
    if (k < nf) {
      n = faces[k].normal, d = faces[k].offset;
      return;
    }
    const int axis = static_cast<int>(k - nf) / 2;
    const bool neg = (k - nf) % 2 == 1;
    n = Vec3(0.0);
    n[axis] = neg ? -1 : 1;
    d = neg ? -b.lo[axis] : b.hi[axis];
  };
  // inside the grown hull at the start and at the end
  bool in0 = true, in1 = true;
  for (std::size_t k = 0; k < np && (in0 || in1); ++k) {
    Vec3 n;
    double d;
    plane(k, n, d);
    in0 = in0 && glm::dot(n, l0) - d - r < 0;
    in1 = in1 && glm::dot(n, l1) - d - r < 0;
  }
  std::size_t best = np;
  bool crossed = false;
  if (!in0) {
    // Cyrus-Beck: the latest entry and the earliest exit over the planes
    const Vec3 dl = l1 - l0;
    double t_enter = -kInf, t_exit = 1;
    for (std::size_t k = 0; k < np; ++k) {
      Vec3 n;
      double d;
      plane(k, n, d);
      const double s = glm::dot(n, l0) - d - r, den = glm::dot(n, dl);
      if (std::abs(den) < 1e-300) {
        if (s >= 0) return false;  // parallel, outside this plane
        continue;
      }
      const double t = -s / den;
      if (den < 0) {
        if (t > t_enter) t_enter = t, best = k;
      } else if (t < t_exit) {
        t_exit = t;
      }
      if (t_enter > t_exit) return false;
    }
    if (best == np || t_enter > 1 || t_enter < -1e-3) return false;
    crossed = true;
  } else if (in1) {
    // started and ended inside: the plane of least penetration at the end
    double top = -kInf;
    for (std::size_t k = 0; k < np; ++k) {
      Vec3 n;
      double d;
      plane(k, n, d);
      const double s = glm::dot(n, l1) - d - r;
      if (s > top) top = s, best = k;
    }
  } else {
    return false;  // started inside, ended outside: already leaving
  }
  // the contact plane, and the path's distances from it
  Vec3 n;
  double d;
  plane(best, n, d);
  const double s1 = glm::dot(n, l1) - d - r;
  if (!(s1 < 0)) return false;
  const double s0 = crossed ? std::max(glm::dot(n, l0) - d - r, 0.0) : -1.0;
  set_swept(c, n, n * d, s0, s1, p1, out);
  return true;
}

// Ericson 2005, "Real-Time Collision Detection" 5.1.5: the closest point of triangle abc
// to p by its Voronoi regions, with the region as edge bits (ab = 1, bc = 2, ca = 4, the
// TriangleMesh::edge_flags bits): a vertex has its two edges, the face 0
Vec3 closest_feature(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, std::uint8_t& region) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  region = 1 | 4;
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  region = 1 | 2;
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  region = 1;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  region = 2 | 4;
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  region = 4;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  region = 2;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  region = 0;
  const double den = 1 / (va + vb + vc);
  return a + ab * (vb * den) + ac * (vc * den);
}

// The nearest feature of one triangle to q within `reach`, seen from the side of the
// plane that `side` is on: the contact normal m and the gap (q's distance along m from
// the feature, which is < reach). Inside the face, and on an edge or corner that the mesh
// marks flat or concave, the normal is the face's (no ghost normals on internal edges);
// on a convex or boundary edge or corner it points from the feature to q. False when q
// is not within reach of the triangle.
bool triangle_near(const TriangleMesh& mesh, std::uint32_t t, const Vec3& q, double side, double reach, Vec3& m,
                   Vec3& foot, double& gap) {
  const auto v = mesh.vertices();
  const auto& tri = mesh.triangles()[t];
  const Vec3 &a = v[tri[0]], &b = v[tri[1]], &c = v[tri[2]];
  std::uint8_t region;
  const Vec3 cp = closest_feature(q, a, b, c, region);
  const Vec3 off = q - cp;
  const double dist2 = glm::dot(off, off);
  if (!(dist2 < reach * reach)) return false;
  if (region == 0 || (mesh.edge_flags()[t] & region) == 0 || !(dist2 > 0)) {
    m = side * mesh.normal(t);
    foot = a;
    gap = glm::dot(m, q - a);
  } else {
    const double dist = std::sqrt(dist2);
    m = off / dist;
    foot = cp;
    gap = dist;
  }
  return true;
}

// true when the point x of the triangle's plane lies in triangle t (edges included, with
// a rounding slack of 1e-12 of the squared edge lengths)
bool in_triangle(const TriangleMesh& mesh, std::uint32_t t, const Vec3& x) {
  const auto v = mesh.vertices();
  const auto& tri = mesh.triangles()[t];
  const Vec3 n = mesh.normal(t);
  for (int e = 0; e < 3; ++e) {
    const Vec3 &a = v[tri[e]], &b = v[tri[(e + 1) % 3]];
    const Vec3 ab = b - a;
    if (glm::dot(glm::cross(ab, x - a), n) < -1e-12 * glm::dot(ab, ab)) return false;
  }
  return true;
}

// Meshes, swept: in the mesh's frame, every triangle near the path (the BVH query with
// the path's bounds grown by r) is tried on the side of its plane where the path starts.
// First, a particle that starts within r of a triangle (touching it already, or pushed
// into it by another collider) leaves the deepest of those, so a particle wedged between
// the mesh and another shape cannot be walked through the mesh step by step. Else a path
// that crosses a triangle's plane moved out by r with its foot inside the triangle, or
// whose centre crosses the triangle itself, hits that face (the earliest over the
// triangles: nothing passes through a triangle at any speed; Ericson 2005, 5.3.6 for the
// ray and triangle). Else the end point's nearest feature within r gives the contact (the
// deepest). Inside a face, and on edges that the mesh marks flat or concave, the normal
// is the face's (no ghost normals on internal edges; TriangleMesh::edge_flags). Ties go
// to the lower triangle index.
bool mesh_swept(const Collider& c, const Vec3& p0, const Vec3& p1, double r, SweptContact<double>& out) {
  const TriangleMesh& mesh = *c.shape.mesh;
  const Vec3 l0 = apply_inverse(c.begin, p0), l1 = apply_inverse(c.end, p1), dl = l1 - l0;
  const Aabb box = Aabb{glm::min(l0, l1), glm::max(l0, l1)}.grown(r * (1 + 1e-9) + 1e-12);
  const auto v = mesh.vertices();
  // the deepest end contact of those touched at the start (0) and of the others (1), and
  // the earliest face hit
  struct Near {
    double gap = kInf;
    std::uint32_t tri = 0;
    Vec3 m{0.0}, foot{0.0};
  } near[2];
  double t_hit = kInf, t_g0 = 0, t_g1 = 0;
  std::uint32_t t_tri = 0;
  Vec3 t_m(0.0), t_foot(0.0);
  mesh.query(box, [&](std::uint32_t t) {
    // the side the path comes from (on the plane: the side it moves away from)
    const Vec3 n = mesh.normal(t), a = v[mesh.triangles()[t][0]];
    const double h0 = glm::dot(n, l0 - a), h1 = glm::dot(n, l1 - a);
    const double side = h0 > 0 ? 1.0 : (h0 < 0 ? -1.0 : (h1 <= 0 ? 1.0 : -1.0));
    const double g0 = side * h0, g1 = side * h1;
    if (g1 >= r) return;  // ends clear of the triangle on its side
    const Vec3 m = side * n;
    // the face, crossed during the step
    if (g0 >= r) {
      const double tr = (g0 - r) / (g0 - g1);
      bool face = in_triangle(mesh, t, l0 + tr * dl - r * m);
      if (!face && g1 < 0) face = in_triangle(mesh, t, l0 + (g0 / (g0 - g1)) * dl);
      if (face) {
        if (tr < t_hit || (tr == t_hit && t < t_tri)) t_hit = tr, t_tri = t, t_m = m, t_foot = a, t_g0 = g0, t_g1 = g1;
        return;
      }
    }
    // the end point's nearest feature of this triangle
    Vec3 gm, foot;
    double gap;
    if (!triangle_near(mesh, t, l1, side, r, gm, foot, gap)) return;
    Near& k = near[g0 < r ? 0 : 1];
    if (gap < k.gap || (gap == k.gap && t < k.tri)) k.gap = gap, k.tri = t, k.m = gm, k.foot = foot;
  });
  if (near[0].gap < r) {
    set_swept(c, near[0].m, near[0].foot, -1.0, near[0].gap - r, p1, out);
    return true;
  }
  if (t_hit <= 1) {
    set_swept(c, t_m, t_foot, t_g0 - r, t_g1 - r, p1, out);
    return true;
  }
  if (!(near[1].gap < r)) return false;
  set_swept(c, near[1].m, near[1].foot, -1.0, near[1].gap - r, p1, out);
  return true;
}

// a compound's leaf (sphere, box, capsule: the closed forms; hull: above), swept
bool leaf_swept(const FlatShape<double>& f, const Vec3& p0, const Vec3& p1, double r, SweptContact<double>& out) {
  switch (f.type) {
    case ShapeType::Sphere: return swept_sphere(f, p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, r, out);
    case ShapeType::Box: return swept_box(f, p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, r, out);
    case ShapeType::Capsule: return swept_capsule(f, p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, r, out);
    case ShapeType::Hull: return hull_swept(*f.source, p0, p1, r, out);
    default: return false;  // compounds hold no planes or meshes; nested ones are flattened
  }
}

// Compounds, swept: every leaf at its own begin and end poses; the earliest crossing
// wins, and a point that started inside some leaf takes the deepest of those first (it is
// pushed out before anything else happens)
bool compound_swept(const FlatShape<double>* parts, std::uint32_t n, const Vec3& p0, const Vec3& p1, double r,
                    SweptContact<double>& out) {
  double best = kInf;
  for (std::uint32_t i = 0; i < n; ++i) {
    SweptContact<double> q;
    if (!leaf_swept(parts[i], p0, p1, r, q)) continue;
    const double key = q.s0 < 0 ? -1 + q.s1 : q.s0 / std::max(q.s0 - q.s1, 1e-300);
    if (key < best) best = key, out = q;
  }
  return best < kInf;
}

// the pose at step fraction f: the origin interpolated, the rotation at the end (as
// point_contact does for the closed forms)
Pose pose_at(const Collider& c, double f) {
  return Pose{c.begin.position + (c.end.position - c.begin.position) * f, c.end.rotation};
}

void set_point(const Collider& c, const Pose& p, const Vec3& n, double depth, const Vec3& x,
               PointContact<double>& out) {
  out.nx = n.x, out.ny = n.y, out.nz = n.z;
  out.depth = depth;
  frame_velocity(c, p.position, x, out.ux, out.uy, out.uz);
}

// Hulls, now: the exact signed distance, the contact when it is under the thickness. The
// most separating face plane first: at or beyond the thickness, no contact (the distance
// is at least that); inside, that face; outside with the foot of the point inside that
// face, the foot is the closest point of the convex hull. Only the rest (near an edge or a
// corner) takes point_distance's search over the faces.
bool hull_contact(const Collider& c, const Vec3& x, double th, double f, PointContact<double>& out) {
  const ConvexHull& h = *c.shape.hull;
  const auto faces = h.faces();
  const Pose p = pose_at(c, f);
  const Vec3 q = apply_inverse(p, x);
  std::size_t best = 0;
  double sep = -kInf;
  for (std::size_t k = 0; k < faces.size(); ++k) {
    const double s = glm::dot(faces[k].normal, q) - faces[k].offset;
    if (s > sep) sep = s, best = k;
  }
  if (!(sep < th)) return false;
  // inside, or the foot on that face inside its loop
  const Vec3 n = faces[best].normal;
  if (sep <= 0 || on_hull_face(h, static_cast<std::uint32_t>(best), q - sep * n)) {
    set_point(c, p, p.rotation * n, th - sep, x, out);
    return true;
  }
  const PointDistance d = query::point_distance_unchecked(c.shape, p, x);
  if (!(d.distance < th)) return false;
  set_point(c, p, d.normal, th - d.distance, x, out);
  return true;
}

// Meshes, now: the nearest triangle feature within the thickness, each seen from the
// side the point is on (two-sided), with the face normal on internal edges
bool mesh_contact(const Collider& c, const Vec3& x, double th, double f, PointContact<double>& out) {
  const TriangleMesh& mesh = *c.shape.mesh;
  const Pose p = pose_at(c, f);
  const Vec3 q = apply_inverse(p, x);
  const Aabb box = Aabb{q, q}.grown(th * (1 + 1e-9) + 1e-12);
  const auto v = mesh.vertices();
  double best = kInf;
  std::uint32_t best_t = 0;
  Vec3 best_m(0.0);
  mesh.query(box, [&](std::uint32_t t) {
    const double h = glm::dot(mesh.normal(t), q - v[mesh.triangles()[t][0]]);
    Vec3 m, foot;
    double gap;
    if (!triangle_near(mesh, t, q, h >= 0 ? 1.0 : -1.0, th, m, foot, gap)) return;
    if (gap < best || (gap == best && t < best_t)) best = gap, best_t = t, best_m = m;
  });
  if (!(best < th)) return false;
  set_point(c, p, p.rotation * best_m, th - best, x, out);
  return true;
}

// Compounds, now: the deepest leaf contact
bool compound_contact(const FlatShape<double>* parts, std::uint32_t n, const Vec3& x, double th, double f,
                      PointContact<double>& out) {
  double best = -kInf;
  for (std::uint32_t i = 0; i < n; ++i) {
    const FlatShape<double>& leaf = parts[i];
    PointContact<double> q{};  // (set whenever hit is; zeroed so the compiler sees it set)
    const bool hit = leaf.type == ShapeType::Hull ? hull_contact(*leaf.source, x, th, f, q)
                                                  : point_contact(leaf, x.x, x.y, x.z, th, f, q);
    if (hit && q.depth > best) best = q.depth, out = q;
  }
  return best > -kInf;
}

}  // namespace

bool swept_generic_d(ShapeType type, const Collider* source, const FlatShape<double>* parts, std::uint32_t n_parts,
                     const Vec3& p0, const Vec3& p1, double r, SweptContact<double>& out) {
  switch (type) {
    case ShapeType::Hull: return hull_swept(*source, p0, p1, r, out);
    case ShapeType::Mesh: return mesh_swept(*source, p0, p1, r, out);
    case ShapeType::Compound: return compound_swept(parts, n_parts, p0, p1, r, out);
    default: return false;  // the closed forms are inline (point_contact.h)
  }
}

bool point_contact_generic_d(ShapeType type, const Collider* source, const FlatShape<double>* parts,
                             std::uint32_t n_parts, const Vec3& p, double th, double f, PointContact<double>& out) {
  switch (type) {
    case ShapeType::Hull: return hull_contact(*source, p, th, f, out);
    case ShapeType::Mesh: return mesh_contact(*source, p, th, f, out);
    case ShapeType::Compound: return compound_contact(parts, n_parts, p, th, f, out);
    default: return false;  // the closed forms are inline (point_contact.h)
  }
}

}  // namespace pba::detail
