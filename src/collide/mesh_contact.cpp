// Convex shapes against static triangle meshes: every triangle the BVH returns for the
// shape's bounds is a thin two-sided hull; the closest points of a sphere's or capsule's core
// (closed forms), else GJK (or EPA when the cores overlap), give its normal and closest
// points, and a normal that comes from an internal edge or vertex whose flags are clear is
// replaced by the face normal before the manifold is built (the
// "internal edge" cure of Jolt's ActiveEdges and Box2D's smooth segments: such an edge
// lies flat or concave between two faces, so its own normal would be a ghost contact).
#include <cmath>

#include "narrow_internal.h"

namespace pba {

using namespace narrow;

namespace {

// which of the triangle's features the point q (on it) lies on: the mask of edges it
// touches (ab = 1, bc = 2, ca = 4; 0 = the interior; two bits = a vertex)
std::uint8_t feature_edges(const Vec3 t[3], const Vec3& q) {
  const Vec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
  const double nn = glm::dot(n, n);
  // barycentric weights of q: u for a, v for b, w for c
  const double v = glm::dot(glm::cross(q - t[0], t[2] - t[0]), n) / nn;
  const double w = glm::dot(glm::cross(t[1] - t[0], q - t[0]), n) / nn;
  const double u = 1 - v - w;
  constexpr double kOn = 1e-9;  // relative: the closest point of GJK is exact to rounding
  std::uint8_t m = 0;
  if (w <= kOn) m |= 1;  // opposite c: edge ab
  if (u <= kOn) m |= 2;  // opposite a: edge bc
  if (v <= kOn) m |= 4;  // opposite b: edge ca
  return m;
}

// The closest points ca (on the segment p-q; p = q for a point) and cb (on the triangle) in
// closed form (Ericson 2005, 5.1.5 and 5.1.9): apart, the nearest pair is an end of the
// segment against the triangle or the segment against one of its edges (a segment parallel
// to the face has such a pair among its nearest ones). False when the segment passes
// through the triangle or lies in its plane: the cores overlap, and EPA finds the depth.
bool core_triangle_closest(const Vec3& p, const Vec3& q, const Vec3 tri[3], const Vec3& face_normal, Vec3& ca,
                           Vec3& cb) {
  bool interior = false;
  ca = p;
  cb = closest_on_triangle(p, tri[0], tri[1], tri[2], interior);
  if (p == q) return true;
  const double dp = glm::dot(face_normal, p - tri[0]), dq = glm::dot(face_normal, q - tri[0]);
  if ((dp <= 0 && dq >= 0) || (dp >= 0 && dq <= 0)) {
    if (dp == dq) return false;  // in the plane
    // where the segment crosses the plane: inside the triangle, the cores overlap
    const Vec3 x = p + (dp / (dp - dq)) * (q - p);
    closest_on_triangle(x, tri[0], tri[1], tri[2], interior);
    if (interior) return false;
  }
  double best = glm::dot(ca - cb, ca - cb);
  const Vec3 cq = closest_on_triangle(q, tri[0], tri[1], tri[2], interior);
  if (const double d = glm::dot(q - cq, q - cq); d < best) best = d, ca = q, cb = cq;
  for (int k = 0; k < 3; ++k) {
    Vec3 c1, c2;
    closest_segments(p, q, tri[k], tri[(k + 1) % 3], c1, c2);
    if (const double d = glm::dot(c1 - c2, c1 - c2); d < best) best = d, ca = c1, cb = c2;
  }
  return true;
}

// one triangle against the convex shape (both in the mesh's frame); true when in contact
bool collide_triangle(const ColliderShape& a, const Pose& pa, const ConvexProxy& A, const Vec3 tri[3],
                      const Vec3& face_normal, std::uint8_t flags, double margin, std::uint32_t t, Manifold& m) {
  m.count = 0;
  m.sub_shape_b = t;
  Vec3 n, point_a, point_b;
  // a sphere's or capsule's core (a point or a segment) apart from the triangle: the closest
  // points in closed form give what GJK converges to (its stop at a 1e-10 m gap, and its
  // test for touching cores, a closest point within 1e-12 m of the origin, kept)
  bool closed = false;
  if (a.type == ShapeType::Sphere || a.type == ShapeType::Capsule) {
    const Segment s = a.type == ShapeType::Capsule ? capsule_core(a, pa) : Segment{pa.position, pa.position};
    Vec3 ca, cb;
    if (core_triangle_closest(s.p, s.q, tri, face_normal, ca, cb)) {
      const Vec3 v = ca - cb;
      const double vv = glm::dot(v, v);
      if (vv > 1e-24) {
        const double dist = std::sqrt(vv);
        if (dist - A.radius > margin) return false;
        n = -v / dist;
        point_a = ca + A.radius * n;
        point_b = cb;
        closed = true;
      }
    }
  }
  if (!closed) {
    ConvexProxy B;
    B.type = ShapeType::Mesh;
    B.triangle = tri;
    if (!contact_normal(A, B, margin, n, point_a, point_b)) return false;
  }
  // an internal (flat or concave) edge or vertex takes the face normal, on the side of
  // the triangle where the shape's centre is (a hull's centroid: its origin may lie on its
  // surface, as a pyramid's at the middle of its base, and a pyramid resting on its base
  // had its side picked by rounding and was pushed through the mesh)
  const std::uint8_t on = feature_edges(tri, point_b);
  const bool internal = on == 0 || (on & flags) == 0;
  Vec3 use = n;
  if (internal) {
    const Vec3 centre = a.type == ShapeType::Hull ? apply(pa, a.hull->centroid()) : pa.position;
    const double side = glm::dot(centre - tri[0], face_normal) >= 0 ? 1.0 : -1.0;
    use = -side * face_normal;
  }
  // the triangle as the reference face (B's), the shape's support feature along the
  // normal as the incident one (Jolt's ManifoldBetweenTwoFaces, with the triangle's three
  // side planes)
  WorldFace rf;
  rf.normal = -use;  // the triangle's side that faces the shape
  rf.offset = glm::dot(rf.normal, tri[0]);
  rf.count = 3;
  const bool flipped = glm::dot(glm::cross(tri[1] - tri[0], tri[2] - tri[0]), rf.normal) < 0;
  for (int k = 0; k < 3; ++k) {
    // counter-clockwise about the reference normal
    const int i = flipped ? 2 - k : k;
    rf.pts[std::size_t(k)] = {tri[i], vertex_id(std::uint32_t(i)), std::uint32_t(i)};
    rf.half_edges[std::size_t(k)] = std::uint32_t(flipped ? (i + 2) % 3 : i);
  }
  std::array<Candidate, kMaxPolygon> cand;
  int count = 0;
  const double radius = A.radius;
  if (a.type == ShapeType::Box || a.type == ShapeType::Hull) {
    Poly P;
    poly_of(a, P);
    double dot = 0;
    const std::uint32_t f = most_aligned_face(P, pa.rotation, use, &dot);
    // a GJK/EPA normal is clipped against when it is a face normal of the shape to rounding
    // (as in collide()); a snapped one when the shape's face is within ~2.5 degrees of it
    if (dot >= (internal ? 0.999 : 1 - 1e-9)) {
      WorldFace inf;
      world_face(P, pa, f, inf);
      count = clip_faces(rf, inf.pts.data(), inf.count, false, -use, 0.0, margin, false, cand.data());
    }
  } else if (a.type == ShapeType::Capsule) {
    const Segment s = capsule_core(a, pa);
    if (std::abs(glm::dot(s.q - s.p, use)) < 0.05 * glm::length(s.q - s.p)) {
      std::array<ClipPoint, 2> seg{ClipPoint{s.p, 0, kLabelMask}, ClipPoint{s.q, 1, kLabelMask}};
      count = clip_faces(rf, seg.data(), 2, true, -use, radius, margin, false, cand.data());
    }
  }
  if (count <= 0) {
    // one point: the shape's deepest point along the normal onto the triangle's plane
    if (internal) {
      point_a = A.support(use) + radius * use;
      point_b = point_a - (glm::dot(rf.normal, point_a) - rf.offset) * rf.normal;
    }
    cand[0] = {point_a, point_b, glm::dot(point_a - point_b, use), 0};
    if (cand[0].depth < -margin) return false;
    count = 1;
  }
  // the triangle's features are B's: their ids carry the flip bit
  for (int i = 0; i < count; ++i) cand[std::size_t(i)].id |= kIdFlip;
  reduce(cand.data(), count, use, m);
  m.sub_shape_b = t;
  return m.count > 0;
}

}  // namespace

int collide_mesh(const ColliderShape& a, const Pose& pose_a, const ColliderShape& mesh, const Pose& pose_mesh,
                 std::span<Manifold> out, const NarrowPhaseSettings& settings) {
  check_pose(pose_a, "collide_mesh: pose_a");
  check_pose(pose_mesh, "collide_mesh: pose_mesh");
  check_shape(a, "collide_mesh: shape_a");
  if (!a.is_convex()) throw Error("collide_mesh: shape_a must be convex, got a " + std::string(to_string(a.type)));
  if (mesh.type != ShapeType::Mesh || !mesh.mesh) throw Error("collide_mesh: mesh must be a triangle mesh with a body");
  const double margin = settings.speculative_margin;
  if (!(margin >= 0 && std::isfinite(margin)))
    require_non_negative(margin, "collide_mesh: NarrowPhaseSettings.speculative_margin");

  // the shape in the mesh's frame, and its bounds there grown by the margin
  const Pose local = compose(inverse(pose_mesh), pose_a);
  const Aabb box = bounds(a, local).grown(margin);
  const TriangleMesh& M = *mesh.mesh;
  const ConvexProxy A = ConvexProxy::of(a, local);
  // the shape's reach along a direction d for the triangles' plane test: a box's, capsule's
  // or sphere's core spans d . centre -+ sum |d . axis_k| (axes scaled by the half extents,
  // a capsule's by its half length) with no support calls; a hull's, its two support points
  const Mat3 r = glm::mat3_cast(local.rotation);
  Vec3 axes[3] = {Vec3(0), Vec3(0), Vec3(0)};
  if (a.type == ShapeType::Box)
    axes[0] = r[0] * a.half_extents.x, axes[1] = r[1] * a.half_extents.y, axes[2] = r[2] * a.half_extents.z;
  else if (a.type == ShapeType::Capsule)
    axes[0] = r[1] * a.half_height;
  const bool hull = a.type == ShapeType::Hull;
  int written = 0;
  M.query(box, [&](std::uint32_t t) {
    if (written >= int(out.size())) return;
    const auto& idx = M.triangles()[t];
    const Vec3 tri[3] = {M.vertices()[idx[0]], M.vertices()[idx[1]], M.vertices()[idx[2]]};
    // a shape wholly beyond the margin on one side of the triangle's plane is beyond it from
    // the triangle (two support points settle what GJK would: a separating axis); the test
    // is kept a rounding's width short of the margin, so nothing GJK would keep is dropped
    const Vec3 nf = M.normal(t);
    const double plane = glm::dot(nf, tri[0]), slack = margin + 1e-12 * (1 + std::abs(plane));
    double lo, hi;
    if (hull) {
      lo = glm::dot(nf, A.support(-nf)), hi = glm::dot(nf, A.support(nf));
    } else {
      const double c = glm::dot(nf, local.position);
      const double w = std::abs(glm::dot(nf, axes[0])) + std::abs(glm::dot(nf, axes[1])) + std::abs(glm::dot(nf, axes[2]));
      lo = c - w, hi = c + w;
    }
    const double above = lo - A.radius - plane;
    const double below = plane - hi - A.radius;
    if (above > slack || below > slack) return;
    Manifold& m = out[std::size_t(written)];
    if (!collide_triangle(a, local, A, tri, nf, M.edge_flags()[t], margin, t, m)) return;
    // back to the world
    m.normal = pose_mesh.rotation * m.normal;
    for (int i = 0; i < m.count; ++i) {
      m.points[std::size_t(i)].point_a = apply(pose_mesh, m.points[std::size_t(i)].point_a);
      m.points[std::size_t(i)].point_b = apply(pose_mesh, m.points[std::size_t(i)].point_b);
    }
    ++written;
  });
  return written;
}

}  // namespace pba
