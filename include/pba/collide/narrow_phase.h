// pba collide, narrow phase (workbook chapter 5): contact manifolds between two shapes.
//
// collide() takes two shapes at their poses and returns a Manifold: one unit normal from
// A to B and up to four contact points, each with its points on both surfaces, a depth
// (positive when the surfaces overlap, negative when they are apart but closer than the
// speculative margin) and a feature id that stays the same while the same pair of
// features touches, so a rigid solver can warm-start its impulses by id (Box2D's
// b2ManifoldPoint.id, Jolt's SubShapeIDPair play this role).
//
// Pairs and their algorithms:
//   sphere, capsule pairs and sphere-box    closed forms (closest points of points and segments)
//   convex vs plane                         the support feature's vertices below the plane
//   box-box, box-hull, hull-hull            separating axes (Gregorius 2013) and face clipping,
//                                           or GJK/EPA and clipping of the normal's faces
//   capsule-box                             the closest points of the core segment and the box in
//                                           closed form, GJK/EPA when they meet; then clipping
//   capsule-hull, sphere-hull               GJK on the cores (van den Bergen 2003), EPA when
//                                           the cores overlap, then feature clipping
// GJK and EPA are also public for distance queries and for the student stepper sample.
//
// Conventions: metres, world frame. Nothing here allocates.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "pba/collide/shape.h"
#include "pba/core.h"

namespace pba {

/// One contact point of a manifold.
struct ContactPoint {
  Vec3 point_a{0, 0, 0};   ///< point on A's surface (world, m)
  Vec3 point_b{0, 0, 0};   ///< point on B's surface (world, m)
  /// (point_a - point_b) . normal (m): > 0 penetrating, < 0 separated by -depth but within
  /// the speculative margin.
  double depth = 0;
  /// Stable feature id: built from the pair of features (face, edge, vertex indices) that
  /// made the point; equal ids in two frames mean the same contact.
  std::uint32_t id = 0;

  /// The midpoint of the two surface points (m), where a solver applies the impulse.
  Vec3 position() const { return 0.5 * (point_a + point_b); }
};

/// A contact manifold: one normal and up to four points. Plain data.
struct Manifold {
  static constexpr int kMaxPoints = 4;  ///< points a manifold holds at most
  Vec3 normal{0, 0, 1};                 ///< unit normal pointing from A to B
  std::array<ContactPoint, kMaxPoints> points{};  ///< the first `count` are valid
  int count = 0;                        ///< number of points, 0..4 (0: no contact)
  std::uint32_t sub_shape_b = 0;        ///< B's part the manifold is against: the mesh triangle (0 otherwise)
};

/// How collide() treats box-box, box-hull and hull-hull pairs.
enum class ConvexMethod : std::uint8_t {
  Sat,     ///< separating axes (faces, then Gauss-map-pruned edge pairs) and face clipping
  GjkEpa,  ///< GJK, EPA when overlapping, then clipping against the found normal's faces
};

/// Settings of collide().
struct NarrowPhaseSettings {
  /// Pairs closer than this (m, finite, >= 0) produce speculative points with negative depth.
  double speculative_margin = 0.02;
  /// Algorithm for box and hull pairs.
  ConvexMethod method = ConvexMethod::Sat;
};

/// The separating (or least penetrating) feature of the last SAT run between a pair, tested
/// first in the next frame: a separated pair usually exits after one axis test.
struct SatCache {
  /// Which feature pair the cached axis comes from.
  enum class Kind : std::uint8_t { None, FaceA, FaceB, Edges };
  Kind kind = Kind::None;     ///< None: nothing cached
  std::uint32_t index_a = 0;  ///< FaceA: face of A; Edges: half edge of A
  std::uint32_t index_b = 0;  ///< FaceB: face of B; Edges: half edge of B
};

/// Per-pair state kept between frames (owned by the caller, e.g. the contact pair).
struct NarrowPhaseCache {
  SatCache sat{};  ///< SAT's cached feature
};

/// The contact manifold of shapes `a` at `pose_a` and `b` at `pose_b`. Supported pairs:
/// any two of sphere, capsule, box and hull, and any of these against a plane (either
/// order). Poses must be finite with unit rotations; `settings.speculative_margin` finite
/// and >= 0. Throws Error naming the bad value, or the pair for unsupported type pairs
/// (meshes and compounds go through their own traversal). `cache` may be null.
Manifold collide(const ColliderShape& a, const Pose& pose_a, const ColliderShape& b, const Pose& pose_b,
                 const NarrowPhaseSettings& settings = {}, NarrowPhaseCache* cache = nullptr);

/// One pair of collide_batch(): collide()'s arguments, with the pair's own margin.
struct PairQuery {
  const ColliderShape* a = nullptr;   ///< shape A (not owned; must not be null)
  Pose pose_a{};                      ///< A's pose (world)
  const ColliderShape* b = nullptr;   ///< shape B (not owned; must not be null)
  Pose pose_b{};                      ///< B's pose (world)
  double margin = 0.02;               ///< speculative margin (m, finite, >= 0)
  NarrowPhaseCache* cache = nullptr;  ///< the pair's cache (may be null), read and updated as collide() does
};

/// Which SIMD path collide_batch() runs box-box pairs on, and collide_mesh() a box's or
/// hull's edge axes against a triangle (Avx512 there runs the AVX2 lanes). Every path gives
/// the same bits; a path the processor lacks falls back to the best one it has.
enum class BatchPath : std::uint8_t {
  Best,    ///< the fastest the processor has (AVX2 where present: measured faster than AVX-512)
  Scalar,  ///< one pair at a time (collide()'s own path)
  Avx2,    ///< 4 pairs at a time in AVX2 registers
  Avx512,  ///< 8 pairs at a time in AVX-512 registers
};

/// collide() of many pairs: out[i] equals collide(*pairs[i].a, pairs[i].pose_a, *pairs[i].b,
/// pairs[i].pose_b, {pairs[i].margin, method}, pairs[i].cache) to the bit, and every cache is
/// left as collide() leaves it. Box-box pairs under ConvexMethod::Sat run several at a time
/// in SIMD lanes (their separating axes, reference and incident faces side by side, so their
/// dependent chains overlap and their branches become masks); every other pair runs collide().
/// Requires out.size() >= pairs.size(). Throws Error like collide() for a bad pair (when
/// several are bad, a box pair's error may come after a later pair's; out is then partly
/// written); never allocates.
void collide_batch(std::span<const PairQuery> pairs, std::span<Manifold> out,
                   ConvexMethod method = ConvexMethod::Sat, BatchPath path = BatchPath::Best);

/// The triangles of a mesh near a convex shape, kept by the caller between collide_mesh()
/// calls for one shape and mesh (a contact pair's): the mesh query of a box a little larger
/// than the shape's, so while the shape's query box stays inside it the next calls test
/// these triangles' bounds instead of walking the mesh's tree. Any shape may use it (the
/// box decides); reset it (`MeshQueryCache{}`) when its mesh is destroyed, as another mesh
/// built at the same address would be taken for it.
struct MeshQueryCache {
  static constexpr int kCapacity = 16;  ///< at most this many triangles are kept
  const TriangleMesh* mesh = nullptr;   ///< the mesh `triangles` index (null: nothing kept)
  Aabb box{};                           ///< the box queried (mesh frame, m)
  std::uint32_t count = 0;              ///< triangles kept
  std::uint32_t triangles[kCapacity]{}; ///< those whose bounds overlap `box`, in TriangleMesh::query()'s order
};

/// The contact manifolds of a convex shape `a` (sphere, capsule, box or hull) against a
/// static triangle mesh `mesh`: one manifold per touching triangle (Manifold::sub_shape_b
/// is the triangle), normals from `a` to the mesh, in the order the mesh's BVH visits the
/// triangles (deterministic). Candidate triangles come from TriangleMesh::query with a's
/// bounds grown by the margin; each triangle is a thin two-sided hull (a sphere's or capsule's
/// core apart from it takes the closest points in closed form, GJK's answer to 1e-10 m; a box
/// or hull separating axes where it overlaps the triangle or lies over its face, EPA's depth
/// and normal; GJK otherwise, EPA for a core through the triangle). A contact on an
/// internal edge or vertex whose edge flags are clear (flat or concave, see
/// TriangleMesh::edge_flags) takes the triangle's face normal, so a shape sliding over a
/// flat mesh gets no ghost contacts from the edges between its triangles. Writes at most
/// out.size() manifolds and returns how many; never allocates. Throws Error like collide().
/// `cache` (may be null): the triangles near the shape, kept between calls; the same
/// manifolds, to the bit, with or without it. `path`: Scalar runs the plain path (a box's
/// or hull's axes one at a time, every turn by the mesh's rotation made); the others turn the
/// shape and test its edge axes four at a time in AVX2 lanes where the processor has them,
/// and leave out the turns of a mesh that is only moved where they give the same bits. The
/// same manifolds, to the bit, on every path.
int collide_mesh(const ColliderShape& a, const Pose& pose_a, const ColliderShape& mesh, const Pose& pose_mesh,
                 std::span<Manifold> out, const NarrowPhaseSettings& settings = {}, MeshQueryCache* cache = nullptr,
                 BatchPath path = BatchPath::Best);

// --- a segment and a box in closed form -------------------------------------------------

/// The closest points of a segment and a solid box, both given in the box's frame (the box
/// centred at the origin, its faces at +-half_extents). Where the closest points are not
/// unique (a segment parallel to a face or an edge) the segment's point is the one nearest
/// its start.
struct SegmentBoxClosest {
  double t = 0;                  ///< the segment's point is p + t (q - p), t in [0, 1] (1)
  Vec3 on_segment{0, 0, 0};      ///< the segment's closest point (box frame, m)
  Vec3 on_box{0, 0, 0};          ///< the box's point nearest it: on_segment clamped to the box (box frame, m)
  double distance2 = 0;          ///< |on_segment - on_box|^2 (m^2): 0 when the segment meets the box
};

/// The closest points of segment p-q and the box of half extents h (all in the box's frame,
/// m; h > 0), exact up to rounding: the squared distance along the segment is a convex piecewise
/// quadratic with at most six breakpoints (a coordinate crossing a slab face), minimised on the
/// piece where its slope changes sign. Collide's capsule-box pairs use it for the apart case
/// (GJK and EPA where the core segment meets the box). Never allocates. Throws Error naming
/// the value for a non-finite p or q or a half extent that is not finite and > 0.
SegmentBoxClosest segment_box_closest(const Vec3& p, const Vec3& q, const Vec3& h);

// --- GJK and EPA --------------------------------------------------------------------

/// A convex shape's core at a pose, as GJK sees it: the support function of a point,
/// segment, box or hull, and the rounding radius added around it (sphere and capsule).
struct ConvexProxy {
  ShapeType type = ShapeType::Sphere;  ///< Sphere, Capsule, Box, Hull, or Mesh for one triangle
  Vec3 half_extents{0, 0, 0};          ///< box half extents (m)
  double half_height = 0;              ///< capsule core half length (m)
  double radius = 0;                   ///< core radius (m): sphere and capsule radius, else 0
  const ConvexHull* hull = nullptr;    ///< hull body, not owned
  /// ShapeType::Mesh: a single triangle, these three points (local frame, not owned).
  const Vec3* triangle = nullptr;
  Pose pose{};                         ///< placement

  /// The proxy of a convex shape at `pose` (the shape's hull must outlive the proxy).
  /// Throws Error for a non-convex shape.
  static ConvexProxy of(const ColliderShape& s, const Pose& pose);
  /// The world point of the core farthest along `d` (any non-zero direction), and the
  /// index of the vertex it is (box: corner bits xyz; hull: vertex; capsule: 0 bottom,
  /// 1 top; triangle: 0, 1, 2; sphere: 0). `hint`: a hull vertex to start the hill climb from (a previous
  /// answer makes it a step or two).
  Vec3 support(const Vec3& d, std::uint32_t* vertex = nullptr, std::uint32_t hint = 0) const;
};

/// One vertex of a GJK simplex: a point w = a - b of the Minkowski difference A - B of the
/// cores, and the support points it came from. Plain data without member initialisers (EPA
/// keeps a hundred of them per call): value-initialise it (`SimplexVertex v{};`) for zeros.
struct SimplexVertex {
  Vec3 a;                 ///< support point of A's core (world, m)
  Vec3 b;                 ///< support point of B's core (world, m)
  Vec3 w;                 ///< a - b (m)
  double weight;          ///< barycentric weight in the closest point v
  std::uint32_t index_a;  ///< vertex of A's core that a is (see ConvexProxy::support)
  std::uint32_t index_b;  ///< vertex of B's core that b is
};

/// Result of gjk_distance().
struct DistanceResult {
  double distance = 0;      ///< distance between the full shapes (m), 0 when they overlap
  double core_distance = 0; ///< distance between the cores (m), 0 when they overlap
  Vec3 point_a{0, 0, 0};    ///< closest point on A's surface (world, m)
  Vec3 point_b{0, 0, 0};    ///< closest point on B's surface (world, m)
  Vec3 normal{0, 0, 1};     ///< unit direction from A to B (when core_distance > 0)
  bool cores_overlap = false;  ///< true when the cores intersect (then EPA is needed)
  int iterations = 0;       ///< GJK iterations used
};

/// GJK run one iteration at a time (for the student sample; gjk_distance() uses it too).
/// Holds at most 4 simplex vertices; never allocates.
class GjkStepper {
 public:
  /// Starts a run between the cores of `a` and `b` (the proxies are copied).
  GjkStepper(const ConvexProxy& a, const ConvexProxy& b);
  /// One iteration: a support point along -v, then the simplex reduced to the smallest
  /// sub-simplex whose hull holds the point closest to the origin. Returns false once done.
  bool step();
  /// Runs to the end: the same as calling step() until it returns false, to the bit, with
  /// the support of each proxy's kind inlined into the run (contact_normal, gjk_distance).
  void run();
  /// True when the run has stopped (converged, overlapping or out of iterations).
  bool done() const { return done_; }
  /// True when the origin lies inside the simplex (the cores overlap).
  bool overlap() const { return overlap_; }
  /// The current simplex (1..4 vertices).
  std::span<const SimplexVertex> simplex() const { return {simplex_.data(), std::size_t(count_)}; }
  /// The point of the simplex closest to the origin (m): the current distance estimate.
  Vec3 closest() const { return v_; }
  /// The last support point of A - B (along -closest()).
  const SimplexVertex& last_support() const { return last_; }
  /// Iterations taken.
  int iterations() const { return iterations_; }
  /// Upper minus lower bound of the distance (m) at the last step (van den Bergen 2003).
  double gap() const { return gap_; }
  /// Closest points on the two cores (world, m), from the simplex weights.
  void closest_points(Vec3& a, Vec3& b) const;
  /// The first proxy.
  const ConvexProxy& proxy_a() const { return a_; }
  /// The second proxy.
  const ConvexProxy& proxy_b() const { return b_; }

  /// Stop when the distance's upper and lower bounds are within this (m).
  static constexpr double kTolerance = 1e-10;
  /// Iteration cap (a polytope pair converges in far fewer; curved cores are points or segments).
  static constexpr int kMaxIterations = 64;

 private:
  // step() with the supports of A and B given (step(): ConvexProxy::support; run(): a kind's)
  template <class SupportA, class SupportB>
  bool step_with(SupportA& support_a, SupportB& support_b);

  ConvexProxy a_, b_;
  // (not zeroed: the constructor writes the first vertex and last_, a step each vertex it
  // adds, and no one reads past count_; the zeroing was a quarter of the constructor's
  // instructions, a run made for every mesh triangle GJK takes)
  std::array<SimplexVertex, 4> simplex_;
  int count_ = 0;
  Vec3 v_{0, 0, 0};
  SimplexVertex last_;
  int iterations_ = 0;
  double gap_ = 0;
  bool done_ = false;
  bool overlap_ = false;
};

/// Distance and closest points of two convex shapes by GJK on their cores (van den Bergen
/// 2003), the core radii subtracted afterwards. The proxies are not checked for finiteness
/// (shapes and poses are checked where they are made): a NaN or infinite support point ends
/// the run within kMaxIterations, as EPA after it ends within its caps, with no meaningful
/// answer (a triangle of NaN points reads as overlapping cores at distance 0;
/// Gjk.NonFiniteCoresEndWithinTheIterationCaps).
DistanceResult gjk_distance(const ConvexProxy& a, const ConvexProxy& b);

/// Result of epa_penetration().
struct PenetrationResult {
  bool ok = false;          ///< false when the cores do not overlap (use gjk_distance)
  double depth = 0;         ///< penetration depth of the full shapes (m): the shortest translation of B along normal that separates them
  Vec3 normal{0, 0, 1};     ///< unit direction from A to B
  Vec3 point_a{0, 0, 0};    ///< deepest point of A inside B (world, m)
  Vec3 point_b{0, 0, 0};    ///< deepest point of B inside A (world, m)
  int iterations = 0;       ///< EPA expansions used
};

/// Penetration depth and normal of two convex shapes whose cores overlap, by the expanding
/// polytope algorithm (van den Bergen 2001) seeded with GJK's simplex. The depth is exact
/// for polytope cores up to the tolerance kEpaTolerance.
PenetrationResult epa_penetration(const ConvexProxy& a, const ConvexProxy& b);

/// EPA stops when the support distance along the nearest face's normal exceeds the face's
/// distance by less than this (m), or than 1e-15 of the shapes' largest world coordinate
/// where that is more (their rounding, beyond 100 km): the depth is then within it of the exact one.
inline constexpr double kEpaTolerance = 1e-10;

}  // namespace pba
