// pba collide, shapes (workbook chapter 5): the geometry every collision client shares.
//
// A ColliderShape is a value: the shape's kind, its few parameters in its own frame, and
// for the shapes with a large body (convex hulls, triangle meshes, compounds) a shared,
// immutable pointer to it, built once and used by any number of colliders. Every shape
// has bounds, a ray cast and mass properties from a density; the convex ones (sphere,
// capsule, box, hull) have a support function. Nothing here knows of velocities, bodies
// or particles: those are the collide module's clients (Jolt's Physics/Collision and
// Box2D's collision.h keep the same line).
//
// Conventions: lengths in metres, densities in kg/m^3, masses in kg, inertia in kg m^2.
// A capsule's axis is its local +Y; a box is centred on its frame's origin.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "pba/core.h"

namespace pba {

/// Coefficients of a surface's collision response.
struct SurfaceMaterial {
  /// Coefficient of restitution e in [0, 1]: the normal speed after a bounce is e times
  /// the normal speed before it, so a ball dropped from height h rebounds to e^2 h.
  double restitution = 0.5;
  /// Coulomb friction coefficient mu >= 0 (finite): each contact removes up to mu times
  /// the normal impulse from the tangential velocity, never reversing it.
  double friction = 0.0;
};

/// An axis-aligned bounding box, lo <= hi componentwise (m).
struct Aabb {
  Vec3 lo{0, 0, 0};  ///< smallest corner (m)
  Vec3 hi{0, 0, 0};  ///< largest corner (m)

  /// True when the two boxes overlap or touch.
  bool overlaps(const Aabb& o) const {
    // all six comparisons, combined without branches (trees and pair lists test boxes whose
    // outcome no branch predictor can guess)
    return (lo.x <= o.hi.x) & (o.lo.x <= hi.x) & (lo.y <= o.hi.y) & (o.lo.y <= hi.y) & (lo.z <= o.hi.z) &
           (o.lo.z <= hi.z);
  }
  /// True when `o` lies inside this box (touching counts).
  bool contains(const Aabb& o) const {
    return lo.x <= o.lo.x && lo.y <= o.lo.y && lo.z <= o.lo.z && o.hi.x <= hi.x && o.hi.y <= hi.y &&
           o.hi.z <= hi.z;
  }
  /// The smallest box around both.
  Aabb merged(const Aabb& o) const { return {glm::min(lo, o.lo), glm::max(hi, o.hi)}; }
  /// This box grown by `m` metres on every side.
  Aabb grown(double m) const { return {lo - Vec3(m), hi + Vec3(m)}; }
  /// Surface area (m^2), the cost measure of bounding-volume trees.
  double area() const {
    const Vec3 d = hi - lo;
    return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
  }
  /// Centre (m).
  Vec3 center() const { return 0.5 * (lo + hi); }
};

/// A ray: the points origin + s direction for s in [0, max_distance].
struct Ray {
  Vec3 origin{0, 0, 0};     ///< start (m), finite
  Vec3 direction{0, 0, 1};  ///< unit direction (pba::ray_cast and QueryWorld normalise a finite non-zero one)
  double max_distance = 1;  ///< length (m), finite and >= 0
};

/// Where a ray first meets a surface.
struct RayHit {
  bool hit = false;          ///< false: the ray misses (the other fields are unset)
  double distance = 0;       ///< distance along the ray to the hit (m), in [0, max_distance]
  Vec3 point{0, 0, 0};       ///< hit point (m)
  Vec3 normal{0, 0, 0};      ///< unit outward surface normal at the hit
  std::uint32_t feature = 0; ///< face, triangle or compound child hit (0 for smooth shapes)
};

/// Mass properties of a solid of uniform density.
struct MassProperties {
  double volume = 0;       ///< m^3
  double mass = 0;         ///< kg (density x volume)
  Vec3 center{0, 0, 0};    ///< centre of mass in the shape's frame (m)
  Mat3 inertia{0.0};       ///< inertia tensor about the centre of mass, shape axes (kg m^2)
};

/// Collider shapes. Plane, Sphere and Box keep their values from before the collide module
/// (they are hashed in scene files and tests).
enum class ShapeType : std::uint8_t {
  Plane,     ///< the half-space below a plane; the normal points out of it. Static only.
  Sphere,    ///< a solid ball of `radius` about the origin
  Box,       ///< a solid box of `half_extents` about the origin
  Capsule,   ///< the segment (0, -half_height, 0)-(0, half_height, 0) swept by `radius`
  Hull,      ///< a convex polyhedron (`hull`)
  Mesh,      ///< a static triangle mesh (`mesh`), two-sided; no volume, no mass
  Compound,  ///< several shapes at local poses (`compound`)
};

/// Lower-case name of a shape type ("plane", "capsule", ...), for messages and files.
std::string_view to_string(ShapeType t);

/// A convex polyhedron with its faces and a half-edge structure (Gregorius 2014,
/// "Implementing Quickhull"; the layout SAT and face clipping want). Immutable once built.
class ConvexHull {
 public:
  /// One directed edge of a face loop. `twin` is the same edge in the neighbouring face.
  struct HalfEdge {
    std::uint32_t origin = 0;  ///< vertex the edge starts from
    std::uint32_t twin = 0;    ///< the opposite half edge
    std::uint32_t next = 0;    ///< the next half edge around the same face (counter-clockwise from outside)
    std::uint32_t face = 0;    ///< the face it bounds
  };
  /// A planar face: its outward plane and one of its half edges.
  struct Face {
    Vec3 normal{0, 0, 1};    ///< outward unit normal
    double offset = 0;       ///< plane: normal . p = offset for p on the face (m)
    std::uint32_t edge = 0;  ///< one half edge of the face's loop
  };

  /// Builds the convex hull of a point cloud by quickhull (robust to duplicate and
  /// coplanar points: coplanar faces are merged, points within the tolerance of a face
  /// are dropped). The tolerance is 1e-9 of the cloud's extent (sum of its bounding box's
  /// sizes): every input point lies within twice that of the hull, and faces are planar to
  /// it. Vertices are input points, in input order. Throws Error naming `where` for
  /// non-finite points or points beyond a float's range (|component| > 3.4e38, the
  /// colliders' range; "where[i]"), fewer than 4 points, more than 2^26, or a cloud that
  /// is flat, collinear or a single point within the tolerance (no volume).
  static std::shared_ptr<const ConvexHull> build(std::span<const Vec3> points, std::string_view where = "hull");
  /// The hull of the box |x| <= half.x, |y| <= half.y, |z| <= half.z (6 faces, 8 vertices).
  static std::shared_ptr<const ConvexHull> box(const Vec3& half_extents);

  std::span<const Vec3> vertices() const { return vertices_; }       ///< corner points (m)
  std::span<const HalfEdge> edges() const { return edges_; }         ///< half edges, twins adjacent (2i, 2i+1)
  std::span<const Face> faces() const { return faces_; }             ///< faces
  /// The vertex farthest along `direction` (any non-zero vector), by hill climbing from `hint`.
  std::uint32_t support_index(const Vec3& direction, std::uint32_t hint = 0) const;
  /// The point farthest along `direction`.
  Vec3 support(const Vec3& direction) const { return vertices_[support_index(direction)]; }
  /// The vertices as three arrays of coordinates (m): all x, then all y, then all z, each of
  /// length vertices().size() rounded up to even (the last vertex repeated): the layout of
  /// the narrow phase's vectorised support scan.
  std::span<const double> vertex_soa() const { return vertex_soa_; }
  /// Centroid of the solid (m) and its volume (m^3), computed at build.
  Vec3 centroid() const { return centroid_; }
  /// Volume (m^3).
  double volume() const { return volume_; }
  /// Radius of the largest ball about centroid() inside the hull (m): the least distance
  /// from the centroid to a face plane.
  double inner_radius() const { return inner_radius_; }
  /// Radius of the smallest ball about centroid() holding the hull (m): the distance to the
  /// farthest vertex.
  double outer_radius() const { return outer_radius_; }
  /// The face planes as four arrays: all normal x, all y, all z (unit normal), then all
  /// offsets (m), each of length faces().size() rounded up to even (the last face
  /// repeated): the layout of the narrow phase's vectorised face bounds.
  std::span<const double> face_soa() const { return face_soa_; }
  /// The edges (edge i: half edges 2i and 2i + 1) as ten arrays, each of length
  /// edges().size() / 2 rounded up to even (the last edge repeated): the x, y, z of u, the
  /// unit normal of half edge 2i's face; of v, half edge 2i + 1's; of the origin of half
  /// edge 2i (m); then the secant of half the angle between u and v, sqrt(2 / (1 + u . v))
  /// (>= 1, infinite for a fold of 180 degrees), which bounds how far a unit vector on
  /// the arc from u to v can exceed, along any vector, the larger of u's and v's
  /// components. The layout of the narrow phase's vectorised edge bounds.
  std::span<const double> edge_soa() const { return edge_soa_; }
  /// One half edge (the even one, 2i) of each edge direction, ascending: edge i is left out
  /// when its vector (the end of half edge 2i less its origin, m) equals an earlier kept
  /// edge's exactly or is its exact negation (a square pyramid's base: 8 edges, 6
  /// directions). The narrow phase's edge axes against triangles: parallel edges give the
  /// same axes to the bit, or their exact negations. Made at build, so a contact need not
  /// compare its edges pairwise.
  std::span<const std::uint32_t> edge_directions() const { return edge_directions_; }
  /// Local bounds.
  Aabb bounds() const { return bounds_; }
  /// Mass properties at `density` (kg/m^3), exact for the polyhedron (Mirtich 1996 or
  /// the tetrahedral decomposition of Tonon 2004).
  MassProperties mass_properties(double density) const;

 private:
  friend struct HullBuilder;
  std::vector<Vec3> vertices_;
  std::vector<HalfEdge> edges_;
  std::vector<Face> faces_;
  std::vector<std::uint32_t> vertex_edge_;  // one half edge leaving each vertex (hill climbing)
  std::vector<double> vertex_soa_;          // see vertex_soa()
  std::vector<double> face_soa_;            // see face_soa()
  std::vector<double> edge_soa_;            // see edge_soa()
  std::vector<std::uint32_t> edge_directions_;  // see edge_directions()
  Vec3 centroid_{0, 0, 0};
  double volume_ = 0;
  double inner_radius_ = 0;
  double outer_radius_ = 0;
  Aabb bounds_{};
};

/// A static triangle mesh with its own bounding-volume hierarchy and edge adjacency, so
/// convex shapes can collide with it without ghost contacts on internal edges. Immutable
/// once built; two-sided (a triangle's normal is (b - a) x (c - a), normalised).
class TriangleMesh {
 public:
  /// A node of the BVH: bounds and either two children or a run of triangles.
  struct Node {
    Aabb box{};
    std::uint32_t first = 0;  ///< leaf: first index into triangle_order(); inner: left child
    std::uint32_t count = 0;  ///< leaf: triangles (> 0); inner: 0 (right child = first + 1)
  };

  /// Builds the mesh (BVH by binned surface-area heuristic, Wald 2007; deterministic).
  /// Throws Error naming `where` and the field for non-finite vertices or vertices beyond a
  /// float's range (|component| > 3.4e38, the colliders' range), an index out of range, a
  /// degenerate triangle (|ab x ac| <= 1e-12 times its longest edge squared: repeated or
  /// collinear corners), no triangles, or more than 2^28 vertices or triangles.
  static std::shared_ptr<const TriangleMesh> build(std::span<const Vec3> vertices,
                                                   std::span<const std::array<std::uint32_t, 3>> triangles,
                                                   std::string_view where = "mesh");

  std::span<const Vec3> vertices() const { return vertices_; }  ///< vertices (m)
  std::span<const std::array<std::uint32_t, 3>> triangles() const { return triangles_; }  ///< vertex indices
  std::span<const Node> nodes() const { return nodes_; }        ///< BVH, root at 0
  std::span<const std::uint32_t> triangle_order() const { return order_; }  ///< leaf runs index this
  /// For each triangle, a bit per edge (ab = 1, bc = 2, ca = 4) set when the edge is
  /// convex or a boundary (contacts may use its normal); internal flat or concave edges
  /// are clear, so a contact on them takes the face normal instead (no ghost contacts).
  /// "Flat" is a bend of sine below 1e-4 (so float-rounded flat meshes stay flat);
  /// non-manifold edges (3+ triangles) and edges whose two triangles wind inconsistently
  /// are set (their side is ambiguous).
  std::span<const std::uint8_t> edge_flags() const { return edge_flags_; }
  /// Unit normal of triangle t.
  Vec3 normal(std::uint32_t t) const { return normals_[t]; }
  /// Local bounds.
  Aabb bounds() const { return nodes_.empty() ? Aabb{} : nodes_[0].box; }
  /// Calls `visit(t)` for every triangle whose bounds overlap `box` (local frame), in the
  /// order of the leaves of nodes() (depth first, the first child first). Never allocates.
  template <class F>
  void query(const Aabb& box, F&& visit) const;

 private:
  friend struct MeshBuilder;
  // The tree query() walks: nodes() with its inner nodes only, each holding both children's
  // bounds in float rounded outwards (a child that overlaps a box in double overlaps it here,
  // so the walk reaches every leaf the exact tree would), 64 bytes, one cache line a node; a
  // child is an inner node (count 0: `first` indexes query_nodes_) or a leaf's run of
  // triangle_order() (first, count).
  struct QueryNode {
    float lo[2][3], hi[2][3];
    std::uint32_t first[2], count[2];
  };
  std::vector<Vec3> vertices_;
  std::vector<std::array<std::uint32_t, 3>> triangles_;
  std::vector<Vec3> normals_;
  std::vector<std::uint8_t> edge_flags_;
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> order_;
  std::vector<QueryNode> query_nodes_;  // root first; empty when the root is a leaf
  std::vector<Aabb> order_boxes_;       // each triangle's exact bounds, in triangle_order()
};

template <class F>
void TriangleMesh::query(const Aabb& box, F&& visit) const {
  // each triangle of a leaf's run by its own (exact) bounds
  auto leaf = [&](std::uint32_t first, std::uint32_t count) {
    for (std::uint32_t i = first; i < first + count; ++i)
      if (order_boxes_[i].overlaps(box)) visit(order_[i]);
  };
  if (nodes_.empty() || !nodes_[0].box.overlaps(box)) return;
  if (nodes_[0].count > 0) return leaf(nodes_[0].first, nodes_[0].count);
  // depth-first with a fixed stack (the builder caps the depth at 60): an entry is a child
  // that overlaps the box (its count in the high half: 0 for an inner node), the second
  // child pushed first, so the leaves come in the order of a walk of nodes()
  std::uint64_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const std::uint64_t e = stack[--top];
    const auto first = static_cast<std::uint32_t>(e), count = static_cast<std::uint32_t>(e >> 32);
    if (count > 0) {
      leaf(first, count);
      continue;
    }
    const QueryNode& n = query_nodes_[first];
    for (int c = 1; c >= 0; --c)
      if ((n.lo[c][0] <= box.hi.x) & (box.lo.x <= n.hi[c][0]) & (n.lo[c][1] <= box.hi.y) & (box.lo.y <= n.hi[c][1]) &
          (n.lo[c][2] <= box.hi.z) & (box.lo.z <= n.hi[c][2]))
        stack[top++] = (std::uint64_t(n.count[c]) << 32) | n.first[c];
  }
}

struct CompoundShape;

/// A collision shape in its own frame: the kind, its parameters, and for hulls, meshes and
/// compounds a shared immutable body. Copying is cheap (shared pointers).
struct ColliderShape {
  ShapeType type = ShapeType::Plane;  ///< which of the fields below apply
  /// Plane: unit normal in the local frame; the solid is on the negative side.
  Vec3 normal{0, 1, 0};
  /// Plane: the plane is { p : normal . p = offset } in the local frame (m, finite).
  double offset = 0;
  /// Sphere and capsule: radius (m), finite and > 0.
  double radius = 0.5;
  /// Box: half extents (m) along the local axes, each finite and > 0.
  Vec3 half_extents{0.5, 0.5, 0.5};
  /// Capsule: half the length of the core segment along local +Y (m), finite and >= 0.
  double half_height = 0.5;
  /// Hull: the polyhedron (non-null for ShapeType::Hull).
  std::shared_ptr<const ConvexHull> hull{};
  /// Mesh: the triangles (non-null for ShapeType::Mesh).
  std::shared_ptr<const TriangleMesh> mesh{};
  /// Compound: the children (non-null for ShapeType::Compound).
  std::shared_ptr<const CompoundShape> compound{};

  /// A plane { p : n . p = offset } (n and offset are divided by |n|; throws for a zero
  /// or non-finite normal or offset).
  static ColliderShape plane(const Vec3& n, double offset);
  /// A sphere of radius r.
  static ColliderShape sphere(double r);
  /// A box with half extents h.
  static ColliderShape box(const Vec3& h);
  /// A capsule along local +Y: core segment of length 2 half_height, radius r.
  static ColliderShape capsule(double half_height, double r);
  /// A convex hull (throws for a null pointer).
  static ColliderShape convex(std::shared_ptr<const ConvexHull> h);
  /// A triangle mesh (throws for a null pointer).
  static ColliderShape triangles(std::shared_ptr<const TriangleMesh> m);

  /// True for the shapes with a support function (sphere, capsule, box, hull).
  bool is_convex() const {
    return type == ShapeType::Sphere || type == ShapeType::Capsule || type == ShapeType::Box ||
           type == ShapeType::Hull;
  }
  /// Throws Error naming `where` and the bad field (zero normal, radius or half extent
  /// <= 0, non-finite values, missing hull / mesh / compound body). A plane's normal
  /// may have any non-zero length (scene files store it as written); queries normalise it.
  void validate(std::string_view where) const;
};

/// A compound's child: a shape at a pose in the compound's frame.
struct CompoundChild {
  ColliderShape shape{};  ///< any shape but a plane or a mesh
  Pose pose{};            ///< placement in the compound's frame
};

/// A rigid group of shapes (a table from a box and four capsules). Immutable once built.
struct CompoundShape {
  std::vector<CompoundChild> children;  ///< at least one
  Aabb local_bounds{};                  ///< bounds of all children in the compound frame

  /// Validates the children (no planes, meshes, empty lists) and computes the bounds.
  static std::shared_ptr<const CompoundShape> build(std::vector<CompoundChild> children,
                                                    std::string_view where = "compound");
};

/// The world bounds of `s` at pose `p`. A plane's bounds are infinite on the axes it is
/// not perpendicular to (use a plane as a static shape only).
Aabb bounds(const ColliderShape& s, const Pose& p);
/// The point of a convex shape farthest along `direction` in its local frame (direction
/// need not be unit). Sphere and capsule include their radius. Undefined for non-convex types.
Vec3 support(const ColliderShape& s, const Vec3& direction);
/// The rounding radius of a convex shape (sphere and capsule: `radius`; box and hull: 0):
/// support(s, d) = core support + core_radius(s) d / |d|, the core being a point or segment.
double core_radius(const ColliderShape& s);
/// Mass properties at `density` (kg/m^3, finite and > 0). Planes and meshes have no volume:
/// throws Error naming `where`.
MassProperties mass_properties(const ColliderShape& s, double density, std::string_view where = "shape");
/// The nearest surface point of a shape to a query point (world frame).
struct PointDistance {
  /// Signed distance (m): positive outside, negative inside a solid (its depth). Meshes
  /// are two-sided surfaces: their distance is unsigned (>= 0).
  double distance = 0;
  Vec3 point{0, 0, 0};   ///< closest surface point (m)
  Vec3 normal{0, 1, 0};  ///< outward unit normal there (for a mesh, towards the query point)
  /// Box or hull: the face of the closest point (box faces in ConvexHull::box order
  /// +x, -x, +y, -y, +z, -z; nearest an edge or corner, one of its faces); mesh: the
  /// triangle; compound: the child; else 0.
  std::uint32_t feature = 0;
};

/// The signed distance from `world_point` to the surface of `s` at pose `p`, with the
/// closest point and its normal (exact for every shape; a compound gives the nearest
/// child's, which is exact outside and the deepest child's depth inside). A point at the
/// centre of a sphere or on a capsule's core takes the local +Y normal; a point on a mesh
/// takes the triangle's normal. Throws pba::Error naming the argument for a point that is not
/// finite or beyond a float's range (|component| > 3.4e38 m, as QueryWorld::closest_point),
/// or a pose whose position is so or whose rotation is not unit (to 1e-6)
/// ("point_distance(pose).rotation: ...").
PointDistance point_distance(const ColliderShape& s, const Pose& p, const Vec3& world_point);

/// Casts a ray (world frame) against the shape at pose `p`. The direction need not be
/// unit: a finite non-zero one is normalised (a unit one, to 4 ulps, is used as it is, so
/// the hits equal the QueryWorld's bit for bit), and distance and max_distance are metres
/// along it whatever its length. A non-finite origin or direction, a zero direction or a
/// max_distance that is negative or not finite throws pba::Error naming the field
/// ("ray_cast(ray).direction: ..."), and so does a pose whose position is not finite or
/// beyond a float's range or whose rotation is not unit to 1e-6 ("ray_cast(pose).rotation"). A ray starting inside a solid hits at distance 0 with
/// the normal exactly minus the normalised direction. The feature is the face of a box
/// (ConvexHull::box order) or hull, the triangle of a mesh (two-sided: the normal faces
/// the ray; the closest hit, ties to the lower index), the child of a compound. Never
/// allocates on valid input.
RayHit ray_cast(const ColliderShape& s, const Pose& p, const Ray& ray);

}  // namespace pba
