// Rigid bodies, private: the contact pairs, their manifolds and the solvers' per-point data.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "body_frame.h"
#include "collide/narrow_internal.h"
#include "pba/collide/broad_phase.h"
#include "pba/collide/narrow_phase.h"
#include "pba/rigid.h"
#include "solver.h"

namespace pba::detail {

/// "None" for the contact pipeline's indices.
inline constexpr std::uint32_t kNoIndex = 0xffffffffu;

/// One contact point as the solver sees it: where it is, its anchors and its separation (what
/// the fill reads of it: its overlap and feature id are kept apart, ContactPair::depth, id).
struct SolverPoint {
  // the point (midway between the two surfaces) in the world at the start of the step (m);
  // its anchors from the centres of mass are at - com_a and at - com_b (com at the start of
  // the step: RigidBodySystem::com0_, which prepare() and the solvers read as com_ then)
  Vec3 at{0, 0, 0};
  // the separation now is dot(core_b_now - core_a_now, n) + offset, where core_x are the
  // points of the shapes' cores (a sphere's centre, a capsule's segment, a box's surface) at
  // sa, sb from the centres of mass, turned with the bodies: a rolling ball's surface point
  // turns away from the contact, its centre does not
  Vec3 sa{0, 0, 0}, sb{0, 0, 0};
  double offset = 0;              // (m)
};

/// A touching or speculative pair of shapes of two bodies. Friction acts on the manifold as
/// a whole ("patch friction", as PhysX and Jolt do): two tangential constraints at the
/// centroid of the points, limited together to the disc mu * (sum of normal impulses), and
/// one twist constraint about the normal, limited to mu * sum * the points' mean distance
/// from the centroid. Per-point friction clamped point by point lets opposing sideways
/// impulses at different points survive (they cancel in the sum but use up the disc), which
/// measurably weakens sliding friction.
///
/// RigidContacts::update() rewrites the pairs in place each step (no value-initialisation:
/// at 20,000 manifolds that alone took milliseconds), so every field the solver reads must be
/// written by update() (contact_pairs.cpp, emit) or by prepare(). The pairs stream from memory
/// three times a step (emit writes them, prepare's fill reads them in colour order, store
/// writes the impulses back), so they hold only what those and the public queries need, in
/// ten cache lines: the key (with the rolling impulse, which only a one-point lane's fill
/// reads), what every lane's fill reads (the frame, the material, the impulses together in
/// one line, all that store() writes, the centroid and the count), the points (what the fill
/// reads of them), then the points' overlaps and ids. While the blocks' layout stands
/// (RigidContacts::lanes_kept) a lane keeps its bodies, so the fill of a manifold of four
/// points reads eight of the ten lines, not the key's nor the overlaps' (the fill waits on the
/// pairs' lines: docs/benchmarks.md, "A resting pile's step"). A rolling pair's
/// mass is kept apart (RigidContacts::rolling_mass), as are the solver's per-point approach
/// speeds and largest impulses, which stay in the blocks (RigidContacts::lane_of).
struct alignas(64) ContactPair {
  // ---- line 0: the key, and the rolling impulse
  std::uint32_t slot_a = 0, slot_b = 0;    // body handle slots (stable across removals)
  std::uint32_t shape_a = 0, shape_b = 0;  // shape indices within the bodies
  std::uint32_t sub = 0;                   // the triangle of a mesh shape (0 for other shapes)
  std::uint32_t a = 0, b = 0;              // dense body indices this step
  std::uint32_t record = kNoIndex;         // its CachedManifold (contact_pairs.cpp; impulses go back there)
  Vec3 rolling_impulse{0, 0, 0};  // accumulated rolling-resistance angular impulse (N m s)
  // ---- line 1: the normal, the first tangent and the material
  // from a to b, and the friction basis; (t1, t2, normal) is right-handed (t1 x t2 = normal),
  // which the solver's contact frame relies on (src/rigid/solver.h)
  alignas(64) Vec3 normal{0, 0, 1};
  Vec3 t1{1, 0, 0};
  double friction = 0, restitution = 0;  // mixed coefficients
  // ---- line 2: the accumulated impulses (N s per substep; the twist's N m s)
  double normal_impulse[Manifold::kMaxPoints] = {0, 0, 0, 0};  // by point
  double tangent_impulse[2] = {0, 0};  // along t1, t2
  double twist_impulse = 0;            // about the normal
  double rolling = 0;                  // mixed rolling-resistance coefficient times radius (m)
  // ---- line 3: the second tangent, the centroid and the count
  Vec3 t2{0, 0, 1};
  Vec3 ca{0, 0, 0};           // friction anchor (the points' centroid) from a's centre of mass (m)
  double twist_radius = 0;    // mean distance of the points from the centroid (m)
  int count = 0;              // points
  // 1 for two balls, or a ball or capsule and a capsule, with one point: the lever arms go from each core point
  // (a ball's centre, a point of a capsule's axis) along the normal (the tangential parts of the points' sa, sb:
  // fill_lanes, xpbd_rigid.cpp's levers), not to the shared point `at`, off the cores' line when the normal is
  // the touch's (touch_normal, touch_cores), so a frictionless push has no moment about either core; else 0
  std::uint32_t balls = 0;
  // ---- lines 4-8: the points; line 9: their overlaps and feature ids, which the fill does not read
  SolverPoint points[Manifold::kMaxPoints];
  double depth[Manifold::kMaxPoints] = {0, 0, 0, 0};  // each point's overlap at the start of the step (m)
  std::uint32_t id[Manifold::kMaxPoints] = {0, 0, 0, 0};  // each point's feature id (warm starting)

  /// The tangential impulse in world axes (N s per substep): what the next step re-projects
  /// onto its tangents (valid until the pair is rewritten).
  Vec3 friction_impulse() const { return tangent_impulse[0] * t1 + tangent_impulse[1] * t2; }

  // the ordering of pairs (by body slots, then shapes): deterministic, and binary-searchable
  bool operator<(const ContactPair& o) const {
    if (slot_a != o.slot_a) return slot_a < o.slot_a;
    if (slot_b != o.slot_b) return slot_b < o.slot_b;
    if (shape_a != o.shape_a) return shape_a < o.shape_a;
    if (shape_b != o.shape_b) return shape_b < o.shape_b;
    return sub < o.sub;
  }
};
static_assert(offsetof(ContactPair, normal_impulse) % 64 == 0 &&
                  offsetof(ContactPair, twist_impulse) + sizeof(double) <= offsetof(ContactPair, normal_impulse) + 64,
              "store() writes one cache line of a pair");
/// The first byte of a pair that the fill of a kept lane of more than one point reads (the
/// lines before it hold the key and the rolling impulse).
inline constexpr std::size_t kPairFillStart = offsetof(ContactPair, normal);
static_assert(kPairFillStart == 64 && offsetof(ContactPair, normal_impulse) == 128 && offsetof(ContactPair, count) < 256 &&
                  offsetof(ContactPair, points) == 256 && offsetof(ContactPair, depth) == 576 && sizeof(ContactPair) == 640,
              "a pair's lines: the key, the frame and material, the impulses, the centroid, the points, their overlaps");

/// Pointers to one body's solver state (velocities, centre and orientation) and its inverse mass.
struct BodyView {
  Vec3* v;
  Vec3* w;
  Vec3* com;
  Quat* q;
  double inv_mass;
};

/// 1 / (J M^-1 J^T) for an impulse along unit `d` at anchors ra, rb (kg): the inverse of the
/// generalised inverse mass w = 1/ma + 1/mb + (ra x d)^T Ia^-1 (ra x d) + (rb x d)^T Ib^-1 (rb x d)
/// (ma, mb inverse masses); 0 when neither body can move.
inline double effective_mass(double ma, double mb, const Mat3& ia, const Mat3& ib, const Vec3& ra, const Vec3& rb,
                             const Vec3& d) {
  const Vec3 ca = glm::cross(ra, d), cb = glm::cross(rb, d);
  const double k = ma + mb + glm::dot(ca, ia * ca) + glm::dot(cb, ib * cb);
  return k > 0 ? 1 / k : 0;
}

/// Applies the impulse `p` (N s) at anchors ra, rb to the velocities: +p to b, -p to a.
inline void apply(BodyView& a, BodyView& b, const Mat3& ia, const Mat3& ib, const Vec3& ra, const Vec3& rb,
                  const Vec3& p) {
  *a.v -= a.inv_mass * p;
  *a.w -= ia * glm::cross(ra, p);
  *b.v += b.inv_mass * p;
  *b.w += ib * glm::cross(rb, p);
}

/// A shape's entry in the broad phase (contact_pairs.cpp): its tight bounds (the shape's
/// bounds grown by the speculative distance and the step's motion), and the fat bounds that
/// the tree holds for it (the tight ones grown by a margin and stretched along the motion).
struct ShapeProxy {
  Aabb box{};               // tight bounds, as of the body's last update (m)
  Aabb fat{};               // the tree's bounds (m); infinite for a plane
  std::uint32_t body = 0;   // dense index
  std::uint32_t shape = 0;  // index within the body
  std::uint32_t slot = kNoIndex;  // the body's handle slot; kNoIndex: a free entry
  std::int32_t node = -1;   // leaf of the tree; -1 for a plane (kept in `unbounded`) or a free entry
};

/// A pair of shapes whose fat bounds overlap: the persistent pair list, sorted by key.
struct ShapePair {
  std::uint32_t slot_a = 0, slot_b = 0, shape_a = 0, shape_b = 0;  // key, as in ContactPair
  std::uint32_t proxy_a = 0, proxy_b = 0;                          // ShapeProxy indices
  std::uint32_t cache = kNoIndex;  // its PairCache, once the narrow phase has seen it
  // the two shapes' kinds (a shape's never changes), set when the pair is found: the plan of
  // make_manifolds picks a pair's path by them without reading the shapes' definitions, which
  // lie anywhere in memory (its wait on b's, a line a pair made anew, was 15% of its samples
  // on the terrain; collide_pair reads them later, asked for some pairs ahead)
  ShapeType type_a = ShapeType::Plane, type_b = ShapeType::Plane;
  bool operator<(const ShapePair& o) const {
    if (slot_a != o.slot_a) return slot_a < o.slot_a;
    if (slot_b != o.slot_b) return slot_b < o.slot_b;
    if (shape_a != o.shape_a) return shape_a < o.shape_a;
    return shape_b < o.shape_b;
  }
};

/// A set of 64-bit keys (open addressing, linear probing, deletion by backward shift; grown,
/// never shrunk): which shape pairs the list holds, so the pairs that moved shapes find are
/// told from new ones in O(1) instead of by sorting them all (Box2D v3 keeps its pair set
/// the same way). Key 0 is reserved (never a pair: a pair's two proxies differ).
struct PairSet {
  std::vector<std::uint64_t> slots;  // 0: empty
  std::size_t count = 0;
  bool contains(std::uint64_t key) const;
  /// Adds `key`; false when it was there already.
  bool insert(std::uint64_t key);
  /// Asks for the line where a search for `key` starts (a hint; nothing changes).
  void prefetch(std::uint64_t key) const;
  void erase(std::uint64_t key);
  void clear();
};

/// The PairSet key of a shape pair: its two proxies.
inline std::uint64_t pair_key(std::uint32_t proxy_a, std::uint32_t proxy_b) {
  return (std::uint64_t{proxy_a} << 32 | proxy_b) + 1;
}

/// What the narrow phase last found for a shape pair, kept between steps: the relative pose
/// of the bodies then (body b's centre of mass and principal frame in body a's principal
/// frame), the speculative margin used, the SAT cache, and the manifolds (one, or one per
/// touching triangle of a mesh). While the relative pose stays within the reuse thresholds,
/// the manifolds are carried over instead of made again (Jolt's body pair cache).
struct PairCache {
  Vec3 rel_position{0, 0, 0};
  Quat rel_rotation{1, 0, 0, 0};
  double margin = -1;  // (m); < 0: nothing computed yet
  NarrowPhaseCache narrow{};
  std::uint32_t first = kNoIndex;  // first CachedManifold; the next free PairCache when free
  std::uint32_t mesh_query = kNoIndex;  // a mesh pair's MeshQueryCache (in mesh_queries), once made
};

/// A manifold in the bodies' frames, and the impulses it carried. What emit() reads every step
/// the manifold is carried over comes first (five of its seven cache lines), the impulses last:
/// they are read only when no entry of `pairs` holds them (`last`, settle()).
struct CachedManifold {
  std::uint32_t next = kNoIndex;  // the shape pair's next manifold (mesh triangles); free list
  std::uint32_t sub = 0;          // mesh triangle (0 otherwise)
  // the entry of `pairs` that holds its latest impulses (the solver's), or kNoIndex when the
  // fields below do: the impulses are saved here only when that entry is about to be reused
  std::uint32_t last = kNoIndex;
  int count = 0;
  bool normal_in_b = false;       // the normal is kept in body b's frame (else a's)
  // the soft step's shift of the contact springs' rest separation (m, >= 0): as much as the
  // position pass (push_out.cpp) moved the manifold's bodies apart beyond what the springs
  // hold, so that the springs still see the overlap they carry the load at (in the padding
  // before `normal`)
  float preload = 0;
  Vec3 normal{0, 0, 1};           // unit, from a to b, in that body's principal frame
  // the points, fixed to the bodies: the points of the two shapes' cores (a sphere's centre, a
  // box's surface) in each body's principal frame from its centre of mass (m), a row a
  // coordinate (a's x, y, z, then b's) and a column a point, so that emit() loads each
  // coordinate of all the points at once; and their feature ids
  double core[6][Manifold::kMaxPoints] = {};
  std::uint32_t id[Manifold::kMaxPoints] = {};
  Vec3 core_a(int k) const { return {core[0][k], core[1][k], core[2][k]}; }
  Vec3 core_b(int k) const { return {core[3][k], core[4][k], core[5][k]}; }
  // what does not change while the pair lasts: the shapes' core radii (m), and the mixed
  // material with the mix rules it was mixed by
  double radius_a = 0, radius_b = 0;
  double mixed_friction = 0, mixed_restitution = 0, mixed_rolling = 0;
  MixRule friction_mix = MixRule::GeometricMean, restitution_mix = MixRule::Maximum;
  // the impulses it carried at the end of its last step (while `last` is kNoIndex)
  double normal_impulse[Manifold::kMaxPoints] = {0, 0, 0, 0};  // by point (N s per solver step)
  Vec3 friction{0, 0, 0};  // the tangential impulse in world axes
  double twist = 0;
  Vec3 rolling{0, 0, 0};
};

/// Softness of a contact: Catto's soft step coefficients for a spring of `hertz` and
/// damping ratio `zeta` integrated implicitly over h (Box2D v3 b2MakeSoft).
struct Softness {
  double bias_rate = 0;      // 1/s
  double mass_scale = 1;     // in (0, 1]
  double impulse_scale = 0;  // in [0, 1)
};
Softness make_soft(double hertz, double zeta, double h);
/// The soft step's largest spring step h w (rad) for a contact against a body that cannot
/// move (static, kinematic or asleep): 1, so 1 / (2 pi h) Hz (contact_solver.cpp, pass()).
inline constexpr double kStaticStepAngle = 1.0;

/// Contact tolerances scaled to small bodies. ContactSettings::linear_slop (5 mm) and
/// speculative_distance (2 cm) are lengths sized, as Box2D's, for bodies of 5 cm half size and
/// more (their ratios to such a body's half size: at most 0.1 and 0.4). A pair whose thinner
/// body is smaller takes those ratios of its half size instead (PhysX sizes its contact offset
/// per shape the same way): a 1 cm cube (half size 5 mm) reaches for speculative points 2 mm
/// out, not 2 cm, which took its top face's corners for contact points; it matches its
/// points for the warm start within 0.5 mm, not within its own half size; and the rigid passes'
/// Baumgarte term (sequential impulses, TGS: the blocks' `slop`), the soft step's position pass
/// and the continuous pass's target leave 0.5 mm of overlap, not its whole half size. At the
/// settings' values cubes of 1 mm to 1 cm half size came to rest up to 46 degrees over, a
/// corner 1.4 half sizes deep or spinning at up to 60 rad/s (tests/rigid/test_rigid_contact.cpp,
/// RigidSmallBodies). A pair with no body under 5 cm half size keeps the settings' values.
inline constexpr double kSlopPerHalfSize = 0.1, kSpeculativePerHalfSize = 0.4;
/// The linear slop (m) of a pair whose thinner body's smallest half size is `thin` (m):
/// the setting, or kSlopPerHalfSize of `thin` when that is smaller.
inline double pair_slop(const ContactSettings& cs, double thin) {
  return std::min(cs.linear_slop, kSlopPerHalfSize * thin);
}
/// The speculative distance (m) of a pair whose thinner body's smallest half size is `thin`
/// (m) and whose bodies' points may travel up to `turn` (m) in the step by turning: the
/// setting, or kSpeculativePerHalfSize of `thin` plus `turn` when that is smaller (a thin rod
/// tumbling onto the ground brings its far corners in by turning, which the bodies' linear
/// travel added to the margin does not count).
inline double pair_speculative(const ContactSettings& cs, double thin, double turn) {
  return std::min(cs.speculative_distance, kSpeculativePerHalfSize * thin + turn);
}
/// The manifold reuse distance scaled to small bodies. A pair keeps its manifold while its
/// points move against each other by less than ContactSettings::reuse_distance (1 mm), and
/// the narrow phase makes the manifold that much beyond the speculative margin. A pair whose
/// thinner body is under 5 cm half size takes kReusePerHalfSize of its half size instead (the
/// setting's ratio to the slop, 0.2, times kSlopPerHalfSize: 5 cm and more keep the setting,
/// bit for bit). At the setting a 0.5 mm cube (1 mm across) had its manifold made 1.2 mm out,
/// so its four points took corners 0.3 to 0.9 mm off the ground in place of bottom ones;
/// dropped 10 cm it came to rest up to 50 degrees over (soft step; sequential impulses 46,
/// TGS 9 at 120 Hz), flipping between two poses at 40-70 rad/s. The margin did it: with the
/// setting's margin and the scaled reuse test the cube ended as before (the same tilts); with
/// the scaled margin and the setting's reuse test it rested on a face.
inline constexpr double kReusePerHalfSize = 0.02;
/// The reuse distance (m) of a pair whose thinner body's smallest half size is `thin` (m):
/// the setting, or kReusePerHalfSize of `thin` when that is smaller.
inline double pair_reuse(const ContactSettings& cs, double thin) {
  return std::min(cs.reuse_distance, kReusePerHalfSize * thin);
}

/// Sorts `keys` stably by their high 32 bits, of which only the lowest `bits` (<= 32) may be
/// set: least digit first, 8 bits a pass (ceil(bits / 8) passes, each stable, so the sort is),
/// through `spare` (resized to keys'). RigidContacts::tree_order's sort.
inline void sort_by_high_word(std::vector<std::uint64_t>& keys, std::vector<std::uint64_t>& spare, int bits) {
  spare.resize(keys.size());
  for (int shift = 32; shift < 32 + bits; shift += 8) {
    std::array<std::uint32_t, 257> start{};
    for (const std::uint64_t k : keys) ++start[((k >> shift) & 0xff) + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (const std::uint64_t k : keys) spare[start[(k >> shift) & 0xff]++] = k;
    keys.swap(spare);
  }
}

/// The contact state of a RigidBodySystem: this step's contact pairs for the solver, the
/// broad phase and the pair cache behind them (contact_pairs.cpp), and the solver passes.
/// Grown, never shrunk: steady state does not allocate.
struct RigidContacts {
  std::vector<ContactPair> pairs;  // this step's manifolds, for the solver (sorted by key)
  std::size_t emitted = 0;         // pairs written so far this step
  std::size_t last_count = 0;      // pairs of last step
  // world inverse inertia by dense body: at the start of the step, and for a body that turns
  // far in it at its pose of the last substep (refresh_inertia)
  std::vector<Mat3> inv_inertia;
  std::vector<Quat> inertia_q;          // by dense body: the orientation inv_inertia is of
  std::vector<std::uint8_t> refreshed;  // scratch of refresh_inertia, by body (and the spare row, and 3 bytes the gathers read past it): 1 when refreshed
  std::vector<std::uint32_t> refresh_list;  // scratch of refresh_inertia: the bodies it refreshed
  std::size_t continuous_hits = 0;     // bodies put back to a time of impact, all steps
  // scratch of continuous(): the moving (dynamic, kinematic) non-bullet bodies whose bounds
  // a bullet's path reaches (dense indices), swept against at their poses at the step's end
  std::vector<std::uint32_t> bullet_targets;
  std::vector<std::uint32_t> late_bullets;  // scratch of continuous(): the awake bullets, swept last
  // scratch of continuous(), made once a step that has bullets (prepare_targets): the
  // moving non-bullet bodies whose bounding box at the step's end (their centre of mass +-
  // their reach) sticks out of every one of their shapes' fat boxes in the tree by more than
  // kTargetSlack, or that have no shape in the tree (dense indices, ascending): each bullet tests
  // them one by one. Every other moving body's end box lies within target_excess (m) of one
  // of its fat boxes, so a tree query of a bullet's path grown by that much finds it.
  std::vector<std::uint32_t> loose_targets;
  double target_excess = 0;
  /// For the tests: when set, continuous() also finds each bullet's moving targets by the
  /// scan of every body that the tree's query replaced, and throws pba::Error naming the
  /// bullet and the body when the two lists differ (off: the scan is not made).
  static inline bool check_bullet_targets = false;
  /// For the tests: the targets that check found in both lists, all steps (counted when set).
  static inline std::size_t checked_targets = 0;
  double impulse_h = 0;  // the time step (s) the carried impulses were accumulated over; 0: none yet
  // the least smallest half size of any body created (m; not raised when one is destroyed):
  // whether some pair may take less than the settings' slop (pair_slop)
  double thinnest = std::numeric_limits<double>::infinity();
  // the farthest any body's shape frame lies from its centre of mass (m; of every body created,
  // not lowered when one is destroyed): check_finite holds the centres within a float's range
  // less this, so every shape's frame is within it
  double frame_reach = 0;
  /// The linear slop (m) of the pair of bodies a, b (dense indices): pair_slop() of the
  /// thinner when some body may be small enough to take less (`thinnest`), else the setting.
  double slop_of(const RigidBodySystem& s, std::uint32_t a, std::uint32_t b) const {
    const double setting = s.settings_.linear_slop;
    if (!(kSlopPerHalfSize * thinnest < setting)) return setting;
    return pair_slop(s.settings_, std::min(s.min_extent_[a], s.min_extent_[b]));
  }

  // ---- the broad phase and the pair cache (contact_pairs.cpp) ----
  std::vector<ShapeProxy> proxies;            // by proxy index (with free entries)
  std::vector<std::uint32_t> statics;         // proxies of static bodies (indices into proxies)
  std::vector<std::uint32_t> unbounded;       // proxies of planes (not in the tree)
  std::vector<std::vector<std::uint32_t>> body_proxies;  // by body slot: its proxies, by shape
  // by body slot (up to the last static one): a static body's pose at its last update
  std::vector<Pose> static_pose;
  DynamicTree tree{0.1};                      // the bounded proxies' fat boxes
  std::vector<ShapePair> shape_pairs, merged; // the persistent pair list (and merge scratch)
  PairSet pair_set;                           // the pairs in shape_pairs, by proxies
  std::vector<ShapePair> found;               // scratch: pairs of the moved proxies this step
  std::vector<std::uint64_t> hits;            // scratch: the moved proxies' query hits (proxy << 32 | other)
  std::vector<ShapePair> candidates;          // scratch: the hits that may pair, in the hits' order
  std::vector<std::uint32_t> moved;           // scratch: proxies new or moved this step (in the tree's order)
  // scratch of update_proxies, by entry of `moved` as first listed: the fat box a leaf is to
  // get (grown by the margin when set; a leaf keeps its place, only its box changes; a new
  // proxy's and a plane's entry is kept only to line up with `moved`, never read), and the
  // entries' sort keys (tree_order)
  std::vector<Aabb> moved_box;
  std::vector<std::uint64_t> moved_keys, moved_keys_spare;
  std::vector<std::uint32_t> moved_spare;
  std::vector<std::uint8_t> was_moved;        // scratch: 1 for the proxies in `moved`
  // the handle slots of the dynamic bodies set_pose moved since the last step (wake_touched
  // wakes the sleepers they jumped into), each once (jumped_slot: 1 for a slot listed, by
  // handle slot; jumped holds room for every slot, so set_pose allocates only as slots are
  // issued), and wake_touched's flags of them by dense body
  std::vector<std::uint32_t> jumped;
  std::vector<std::uint8_t> jumped_slot;
  std::vector<std::uint8_t> jumped_flag;
  std::vector<std::int32_t> moved_leaves;     // scratch: the tree leaves of `moved` (find_new_pairs)
  std::vector<PairCache> caches;              // pool
  std::vector<PairCache> caches_spare;        // scratch: the pool in pair order (reorder_caches), as large
  std::vector<CachedManifold> manifolds;      // pool
  std::vector<Manifold> mesh_scratch;         // collide_mesh output
  Manifold pair_manifold;                     // scratch: a convex pair's manifold (collide_into)
  std::vector<MeshQueryCache> mesh_queries;   // pool: mesh pairs' triangles near the shape
  std::vector<std::uint32_t> free_mesh_queries;  // its free entries
  std::vector<int> group_of, group_first;     // scratch: the mesh manifolds' groups of one normal
  std::vector<narrow::Candidate> merge_scratch;  // scratch: a group's points
  /// make_manifolds' plan for a touching pair, made before its span of pairs is walked.
  struct PairPlan {
    /// What becomes of a pair this step (make_manifolds).
    enum class Fate : std::uint8_t { Asleep, End, Apart, Touching };
    Vec3 rel_position{0, 0, 0};        // b's centre in a's frame (m)
    Quat rel_rotation{1, 0, 0, 0};     // b's frame in a's frame
    double margin = 0;                 // the speculative margin of this step (m)
    double reuse = 0;                  // the pair's reuse distance (m): pair_reuse() of its thinner body
    std::uint32_t batched = kNoIndex;  // its manifold in box_manifolds (a box-box pair), or kNoIndex
    bool same = false;                 // its manifolds are carried over
  };
  std::vector<PairPlan::Fate> fates;          // scratch: by shape pair of the span being walked
  std::vector<PairPlan> plans;                // scratch: the same, written for touching pairs only
  std::vector<PairQuery> box_queries;         // scratch: the box-box pairs to make, for collide_batch
  std::vector<Manifold> box_manifolds;        // scratch: their manifolds
  std::vector<NarrowPhaseCache> fresh_narrow; // scratch: by box query, the narrow cache of a pair without a cache yet
  std::uint32_t free_proxy = kNoIndex, free_cache = kNoIndex, free_manifold = kNoIndex;
  // by dense body, for this step's update(): how far the body travels in the step, up to its
  // size (min(|v| dt, extent), m; update_proxies), which the speculative margins are made of;
  // and its rotation matrix, made the first time emit() needs it this step (rotation())
  std::vector<double> travel;
  std::vector<Mat3> rotations;
  std::vector<std::uint32_t> rotation_stamp;  // the update() that made rotations[i]
  std::uint32_t stamp = 0;                    // this update()'s
  // by proxy, its shape's world pose at the step's start (compose(body_pose, local)), made by
  // update_proxies for the bodies it moves or the first time shape_pose() needs it this step:
  // the narrow phase made it per pair, two normalised products a body, the ground's for each
  // of the rain's 5,000 pairs made a step
  std::vector<Pose> shape_poses;
  std::vector<std::uint32_t> shape_pose_stamp;  // the update() that made shape_poses[q]
  std::size_t bodies_seen = 0;                // the bodies update_proxies() saw last step
  std::size_t reinserted_since_check = 0;     // tree moves since its quality was last checked
  double tree_ratio = 0;                      // the tree's area ratio after its last rebuild

  /// Finds the shape pairs whose bounds overlap, wakes sleeping islands that a moving body
  /// reaches, and gives each pair its manifolds (reused while the bodies' relative pose
  /// barely changed, else made by the narrow phase), with last step's impulses.
  void update(RigidBodySystem& s, double dt);
  /// Forgets body `slot` (being destroyed at dense index `i`; the last body moves to `i`).
  void remove_body(RigidBodySystem& s, std::uint32_t slot, std::size_t i);
  // update()'s parts
  // how far (m) body i's points may travel in the last step by turning: |w| times its reach
  // over the step, up to its reach (pair_speculative's `turn`; contact_pairs.cpp)
  static double turn_travel(const RigidBodySystem& s, std::size_t i);
  void update_proxies(RigidBodySystem& s, double dt);
  // update_proxies' common case for dense bodies i..i+3 at once (AVX2): each dynamic, awake and
  // not new, with one ball or box at its origin unturned, its principal frame its own, centred;
  // false, having changed nothing, when one is not (contact_pairs.cpp)
  bool proxies4_avx2(RigidBodySystem& s, std::size_t i, double dt);
  void find_new_pairs(RigidBodySystem& s);
  /// Puts `moved` in the tree's order (contact_pairs.cpp): by its leaves' parents' node
  /// indices, stably, planes last; `set_boxes`: the leaves flagged in moved_keys get their
  /// moved_box on the way.
  void tree_order(bool set_boxes);
  /// Moved entry i's leaf gets its new fat box moved_box[i], and its proxy the box the tree
  /// keeps (for the entries whose key, moved_keys before tree_order's sort, has bit 31 set).
  void set_moved_box(std::size_t i) {
    ShapeProxy& p = proxies[moved[i]];
    tree.set_leaf_box(p.node, moved_box[i]);
    p.fat = tree.fat_box(p.node);
  }
  void wake_touched(RigidBodySystem& s);
  void make_manifolds(RigidBodySystem& s);
  void collide_pair(RigidBodySystem& s, const ShapePair& p, PairCache& c, std::uint32_t a, std::uint32_t b,
                    double reach, const Manifold* made = nullptr);
  void emit(RigidBodySystem& s, const ShapePair& p, std::uint32_t record, std::uint32_t a, std::uint32_t b);
  /// Body i's rotation matrix at its orientation now (made once a step: a body is in several manifolds).
  const Mat3& rotation(const RigidBodySystem& s, std::uint32_t i) {
    if (rotation_stamp[i] != stamp) rotations[i] = glm::mat3_cast(s.q_[i]), rotation_stamp[i] = stamp;
    return rotations[i];
  }
  /// Proxy q's shape's world pose (m, unit quaternion) at the poses of this step's start: shape
  /// k of dense body i (q's). Poses that change after update() (the solver's) are not seen.
  /// (The stamp's test inlined where it is asked, the pose made by make_shape_pose: as one call,
  /// some 24 instructions a pose for the rain's 20,000 a landing step, nearly all made already.)
  const Pose& shape_pose(const RigidBodySystem& s, std::uint32_t q, std::uint32_t i, std::uint32_t k) {
    if (shape_pose_stamp[q] != stamp) [[unlikely]]
      make_shape_pose(s, q, i, k);
    return shape_poses[q];
  }
  /// Makes proxy q's shape pose at this step's start into shape_poses[q] and stamps it
  /// (shape_pose's out-of-line half).
  void make_shape_pose(const RigidBodySystem& s, std::uint32_t q, std::uint32_t i, std::uint32_t k);
  void settle(std::uint32_t record);
  void settle_all();
  std::uint32_t new_cache();
  /// The pair caches moved into the order of shape_pairs (the free ones dropped).
  void reorder_caches();
  std::uint32_t new_manifold();
  void free_manifolds(PairCache& c);
  void free_pair(ShapePair& p);

  // the velocity solvers' constraints (src/rigid/solver.h): blocks by colour, then the overflow's
  std::vector<ContactBlock> blocks;
  std::vector<AnchorBlock> anchors;  // by block: what measuring its separations needs
  std::size_t block_count = 0;     // blocks in use
  std::size_t colored_blocks = 0;  // blocks [0, colored_blocks) are coloured, the rest overflow
  static constexpr std::uint32_t kOverflow = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> color_of;     // by pair: its colour (kOverflow: solved one at a time)
  std::vector<std::uint32_t> color_count;  // manifolds of each colour
  std::uint32_t overflow_count = 0;        // manifolds in the overflow
  std::vector<std::size_t> color_block;    // colour c's blocks from color_block[c]; then the overflow's
  // the coloured one-point manifolds (src/rigid/solver.h, OnePointBlock): colour c's in blocks
  // [color_ones[c], color_ones[c + 1]) of `ones`, solved after its ContactBlocks
  std::vector<OnePointBlock> ones;
  std::vector<OnePointAnchors> one_anchors;  // by one-point block
  std::size_t one_blocks = 0;                // one-point blocks in use
  std::vector<std::size_t> color_ones;
  std::vector<std::uint32_t> ones_of_color;  // scratch of build(): each colour's one-point manifolds
  std::vector<std::uint8_t> one_of;          // by pair, 1 when it went to a one-point block (build())
  /// A block's lanes' inverse masses and impulse units as fill_block gathered them (doubles:
  /// the block keeps them times the unit, in floats), kept for the next step's fill while the
  /// layout stands (lanes_kept).
  struct LaneMasses {
    double ma[kLanes], mb[kLanes];  // the bodies' inverse masses (1/kg; 0 for one that does not move)
    double unit[kLanes];            // the lane's impulse unit
  };
  std::vector<LaneMasses> block_masses, one_masses;  // by block of `blocks`, of `ones`
  // The blocks' layout stands when the colours stood (colors_kept: color() kept last step's)
  // and every pair goes to the same kind of block as last step (one_of): then by_color,
  // lane_of and each lane's pair are last step's, and so are its bodies, write masks, inverse
  // masses and impulse unit (a body's type and mass do not change while it lives; whether it
  // moves is part of the colours' key), and its slop while the setting and `thinnest` are
  // those it was found with (kept_slop, kept_thinnest). build() then leaves them in the lanes
  // (lanes_kept) and fill_block gathers only what the poses change. reuse_lanes: the switch
  // (RigidBodySystem::set_lane_reuse); lanes_filled: the blocks hold a layout (cleared by
  // build() until it has filled them, and by prepare() for XPBD, which fills none).
  bool colors_kept = false, lanes_kept = false, lanes_filled = false, reuse_lanes = true;
  double kept_slop = -1, kept_thinnest = -1;  // (m)
  // by pair: its points (emit() writes it with the pair's count, remove_body() moves it with
  // the pair), so that build() sorts the one-point manifolds out without reading each pair
  // (a line of 640 bytes apart: +1.4% of the 2870 pyramid's step when it did)
  std::vector<std::uint8_t> pair_points;
  std::vector<std::uint32_t> one_cursor;     // scratch of build()
  std::vector<std::size_t> roll_start;       // colour c's lanes that roll are rolls[roll_start[c], roll_start[c + 1])
  // colouring scratch: contact-graph levels by body, the dynamic pairs' adjacency, bands by pair
  std::vector<std::uint32_t> level, adjacency_start, adjacency, queue, cursor, band_of, band_start, by_band;
  std::vector<std::uint32_t> mask_band;    // by body: the band its mask is for
  std::vector<std::uint64_t> mask;         // by body: the colours of that band it has manifolds in
  std::vector<std::uint32_t> by_color;     // the pairs by colour, in pair order within each
  std::vector<std::size_t> offset;         // scratch: each colour's start in by_color
  std::vector<std::uint32_t> band_colors;  // each band's first colour, then the number of colours
  // what the colours were made from: by body whether it moves, and the solver; and whether this
  // step's pairs have last step's bodies and rolling entry by entry (emit() clears pairs_same
  // at the first that does not; colored_once is cleared when the pairs were changed otherwise).
  // color() keeps the colours when none of it changed
  std::vector<std::uint8_t> color_moving;
  std::vector<std::uint32_t> color_key;  // scratch of color(): each pair's bodies a, b in pair order
  bool color_tgs = false, colored_once = false, pairs_same = false;
  bool backward = true;  // this step runs each band's colours last to first (alternating by step)
  /// The columns (columns.cpp): each awake dynamic body's height in bodies resting face on
  /// face along `up` (unit, against gravity) from one that rests on a body that does not move,
  /// into column_level (0: on no such column); returns the largest level^3 / (2 x smallest half
  /// size) over the bodies (1/m; the load the column model asks of the contacts) and the tallest
  /// level in `tallest`. O(bodies + pairs); no allocation once the scratch has grown.
  /// With `give` (the halving's budgets, ContactSettings::auto_substeps_sag_fraction and
  /// auto_substeps_sag), also the most static sag (m) of a body on the contacts' carried loads
  /// at the angular rates w_dynamic, w_static (rad/s) into column_sag_top: each face contact is
  /// a spring m_eff w^2 under its load, and a body sinks as on its springs to the bodies under
  /// it (columns.cpp); and into column_sag_ratio the most of that sag over the body's size and
  /// of each touching contact's own deflection over its smaller moving body's size.
  double measure_columns(const RigidBodySystem& s, const Vec3& up, int& tallest, bool give = false,
                         double w_dynamic = 0, double w_static = 0);
  // its scratch: by body the level and the first of its edges (bodies resting on it) in
  // column_edge, the (lower, upper) face pairs, the breadth-first queue
  std::vector<std::uint32_t> column_level, column_start, column_edge, column_queue;
  std::vector<std::uint64_t> column_pairs;
  // with the sag: a face contact's load (N) and stiffness (N/m) by face pair, then by edge;
  // by body the sum over its supports of load + stiffness x the support's sink, and of the
  // stiffness (its sink is their ratio)
  struct ColumnSpring {
    double load = 0, stiffness = 0;
  };
  std::vector<ColumnSpring> column_sink, column_pair_spring, column_spring;
  /// The braced model (columns.cpp, "Braced piles"), with the halving's budgets: the load, in
  /// the column model's n^3 g / (w^2 s), under which the pile measured last stands on its
  /// springs (those measure_columns gave its face pairs) with the margin a free column of cubes
  /// has at that load: kGreenhill over the smallest factor on gravity that the tilt chain of
  /// its levels stands (its levels: bodies carrying a common body on face contacts whose
  /// springs are each the stiffest between moving bodies of the body they rest on). Into column_braced; -1 when the levels do not make a tree (a level resting on
  /// two, or on itself), where the column model's is taken. Needs the loads of a step. O(bodies + face points) per
  /// factor tried; no allocation once the scratch has grown. Needs measure_columns' face pairs.
  double measure_braced(const RigidBodySystem& s, const Vec3& up, double g);
  /// Whether the face pairs of the last measure_columns are those the last measure_braced was
  /// made from (the same bodies, in the same order, each lower moving or not), and the other
  /// touching pairs' loads fall on the same lower bodies in the same order. O(pairs measured).
  bool brace_faces_same() const;
  /// Whether the trees of levels brace_order[begin, end) (whole trees) stand gravity times
  /// `factor` (K - factor G positive definite) in both horizontal directions.
  bool braced_stands(double factor, std::uint32_t begin, std::uint32_t end);
  // its scratch. By face pair (touching, 3 points or more, within 45 degrees of the vertical,
  // with a moving upper body): the pair, its bodies, load (N) and spring (N/m, m_eff w^2) and
  // the height of its points' centroid along up (m)
  struct BraceFace {
    std::uint32_t pair, lower, upper;
    double load, stiffness, z;
    bool moving;  // the lower body moves
  };
  std::vector<BraceFace> brace_face;
  // a face pair's bodies and whether its lower body moves, as one key; by face pair, the keys
  // of the last measure_braced's (brace_faces_same)
  static std::uint64_t face_key(const BraceFace& f) {
    return std::uint64_t{f.lower} << 33 | std::uint64_t{f.upper} << 1 | static_cast<std::uint64_t>(f.moving);
  }
  std::vector<std::uint64_t> brace_key;
  // by load of a pair that is no face pair (brace_load), its lower body, at the last measure_braced
  // (brace_faces_same: a load come or gone since counts as a change, from the step after it carried)
  std::vector<std::uint32_t> brace_load_key;
  // by touching pair that is no such face pair (a ball's point, an edge, a steep face, a body
  // that does not move pressing from above) with a moving lower body: the lower body, the
  // vertical part of the pair's load (N) and the height of its points' centroid along up (m)
  struct BraceLoad {
    std::uint32_t lower;
    double load, z;
  };
  std::vector<BraceLoad> brace_load;
  // by body: its union-find root, the first body under it that its load ties into its level,
  // its level, the sums for the height it tilts about (its supports' centroids weighted by
  // their loads), and its stiffest face spring to a moving body (N/m)
  struct BraceBody {
    std::uint32_t root, down, level;
    double fz, f, z, stiffest;
    int supports;
  };
  std::vector<BraceBody> brace_body;
  // by level: the level it rests on (kNoIndex: none that moves), its depth from the ground,
  // the root of its tree (the level under it that rests on none that moves),
  // bodies, the gravity term G (N m per rad^2 of its bodies' tilt), its smallest body's size
  // (m), and by direction the sum, least and most of its bodies' coordinates (m), whether it
  // turns as a level (psi), and its blocks of the tilt chain's stiffness: D on its (tilt,
  // turn, lift) and C to its support level's
  struct BraceLevel {
    std::uint32_t parent, depth, count, root;
    double gravity, size;
    double sum[2], lo[2], hi[2];
    bool psi[2];
    double d[2][9], c[2][9];
  };
  std::vector<BraceLevel> brace_level;
  // the levels by tree (root), each after every level resting on it; the order by depth
  // alone, and the counting sorts' counts, on the way
  std::vector<std::uint32_t> brace_order, brace_tree, brace_count;
  std::vector<std::array<double, 9>> brace_s;  // a level's block as the elimination leaves it
  // the last measure_braced (-1: the column model's, also while it is owed), and whether it
  // is owed for the last measure_columns (RigidBodySystem::step_substeps)
  double column_braced = -1;
  bool brace_due = false;
  // the rates (rad/s) the last measure_columns took its springs at, dynamic and static, and
  // the gravity (m/s^2) of the last measure_braced: its load is scaled to the step's
  // (RigidBodySystem::step_substeps), as a varying dt or a changed contact_hertz moves them
  double column_rate = 0, column_static_rate = 0, column_braced_g = 0;
  // the rates (rad/s) of the measure the last measure_braced was made from, and the steps since
  // it (kept across measures whose face pairs are its, up to kMeasureEvery steps)
  double brace_rate = 0, brace_static_rate = 0;
  int brace_age = 0;
  // the gravity (m/s^2) of the last measure_columns: its sag is scaled to the step's as the
  // braced load is (the loads it was made from went with it)
  double column_g = 0;
  // the last measure (RigidBodySystem::step_substeps): its result, the bodies and the up it
  // was made for, the steps since, and whether it stands (cleared when a body is destroyed)
  double column_need = 0;
  double column_sag_top = 0;  // the sag it predicted (m; with the halving's budgets)
  // the most, over the awake bodies and the touching contacts, of that sag (a contact's own
  // deflection) over the body's size, twice its smallest half size (the smaller body's)
  double column_sag_ratio = 0;
  int column_top = 0;
  std::size_t column_bodies = 0;
  Vec3 column_up{0, 0, 0};
  int column_age = 0;
  bool column_known = false;
  double hertz_scale = 1;  // the soft step's factor on contact_hertz this step (auto_substeps)
  double gravity_speed = 0;  // |g| of this step (m/s^2): the soft step's cap on carried impulses
  struct LaneRef {
    std::uint32_t block, lane;
    double restitution;  // the pair's (kept here, so the pass does not read the pair again)
    bool one;            // block is one of `ones`
  };
  std::vector<LaneRef> restitution_lanes;  // the lanes with restitution, in pass order
  /// A lane that rolls: what its rolling resistance reads and writes in each pass, copied from
  /// its pair by build() (read in lane order, not from the pairs and inverse inertias in pair
  /// order), and its impulse, written back to the pair by finish_velocities().
  struct Rolling {
    Mat3 mass{0.0};          // the pair's rolling_mass (kg m^2)
    Mat3 ia{0.0}, ib{0.0};   // the bodies' world inverse inertias (1 / (kg m^2))
    Vec3 impulse{0, 0, 0};   // accumulated (N m s per substep)
    double rolling = 0;      // the pair's coefficient times radius (m)
    std::uint32_t key = 0;   // block * kLanes + lane (of `blocks`)
    std::uint32_t pair = 0, a = 0, b = 0;
    bool write_a = false, write_b = false;  // the body moves (the solver writes it)
  };
  std::vector<Rolling> rolls;      // the ContactBlocks' lanes that roll, by key (the coloured ones first; one-point lanes roll in their blocks)
  std::size_t colored_rolls = 0;   // of them, in coloured blocks
  std::vector<Mat3> rolling_mass;  // by pair, for those that roll: set_rolling_mass (kg m^2)
  // by pair: its lane of the blocks (block * kLanes + lane; plus kOneLane for a lane of
  // `ones`), while lanes_valid: the blocks keep
  // the approach speeds and largest impulses of the last step for manifold() until the next prepare
  std::vector<std::uint32_t> lane_of;
  std::vector<std::uint8_t> pairs_of;  // by body: its pairs this step, up to 2 (carry_fresh_slides)
  static constexpr std::uint32_t kOneLane = 0x80000000u;
  bool lanes_valid = false;
  // by body, and a last spare row for empty lanes: the velocities while the solver runs, the
  // motion since the start of the step (dp, then the turn w, x, y, z), and the warm-start
  // velocity changes for the next integration
  std::vector<SolverBody> rows;
  // the velocities and angular velocities the step started from, which prepare() made the
  // rows of (swapped out of the system's arrays by finish_velocities, which writes those
  // anew: no copy), while `start_kept`: the approach speeds before the solve of the lanes that
  // do not bounce are made from them when asked for (solver_report), not by every prepare
  std::vector<Vec3> start_v, start_w;
  bool start_kept = false;
  std::vector<double> motion;
  std::vector<SolverBody> warm;
  SimdPath simd = best_simd_path();        // the path of the coloured blocks and the free motion
  // the awake dynamic bodies this step (dense indices, ascending), by the kind of their free
  // rotation (FreeRotation, integrate_wide.cpp); in the soft step, after split_coasting, only
  // those a contact lane holds (refresh_inertia, the free motion's lanes and the passes see
  // these; the coasting ones are stepped apart by coast())
  std::array<std::vector<std::uint32_t>, kFreeRotations> moving;
  bool moving_damped = true;  // some of them have linear or angular damping
  bool moving_torqued = true;  // some of them have a torque other than +0 (all three components' bits zero)
  // the soft step's moving bodies that no contact lane holds this step, by kind (split off
  // `moving` by split_coasting, which leaves the others there), and its scratch by body
  std::array<std::vector<std::uint32_t>, kFreeRotations> coasting;
  std::vector<std::uint32_t> drifting;  // the others whose step has a closed form (coast())
  std::vector<std::uint8_t> in_lanes;  // split_coasting's, by body: 0 no lane, 1 a lane writes it, 2 drifts
  std::vector<double> coast_lanes;  // coast()'s free motion lanes of a chunk of them
  // the free motion's lanes over the soft step's and TGS's substeps (solver.h, FreeLine): kind k's blocks
  // from free_lanes.data() + free_lanes_at[k] (64-byte aligned). While live (from
  // gather_free_motion to scatter_free_motion) the moving bodies' centres and frames are the
  // lanes', not the system's arrays'
  std::vector<double> free_lanes;
  std::array<std::size_t, kFreeRotations> free_lanes_at{};
  bool free_lanes_live = false;
  std::vector<std::uint32_t> kinematic;  // this step's kinematic bodies, in index order (their exact motion)
  bool built = false;       // the blocks hold this step's manifolds (cleared by store())
  bool has_colors = false;  // color_of holds the last step's colours

  /// The world inverse inertias as the solvers see them, at the bodies' orientations now
  /// (1/(kg m^2)), of bodies[0 .. count) (nullptr: bodies 0 .. count) into inv_inertia, and
  /// those orientations into inertia_q: zero while asleep; for the float solvers the moments
  /// at most kSolverInertiaRatio apart. A lane type at a time on the SIMD paths, every path
  /// giving glm's bits.
  void world_inv_inertias(const RigidBodySystem& s, const std::uint32_t* bodies, std::size_t count);
  /// After the positions of a substep moved (the soft step, sequential impulses, TGS): each
  /// awake body whose inverse inertia the blocks hold at an orientation that is now
  /// kInertiaTurn / (its ratio of moments - 1) or more away gets it at its pose now, and so do
  /// the rows of its lanes that depend on it (inverse inertias, K, effective masses, rolling
  /// masses); their frames, arms and impulses stay. A body of three equal moments never needs
  /// it (its inverse inertia is the same in every frame). While the free motion's lanes are
  /// live (the soft step's and TGS's substeps, FreeLanesScope) the frames now and the spreads
  /// are read from the lanes, and a refreshed body's frame is written into the system's q_
  /// (where world_inv_inertias reads it); else both come from the system's arrays.
  void refresh_inertia(RigidBodySystem& s);
  /// The free motion's lanes of kind k (FreeRotation) while they are live, else nullptr.
  double* free_lanes_of(std::size_t k) { return free_lanes_live ? free_lanes.data() + free_lanes_at[k] : nullptr; }
  /// Fills the free motion's lanes of this step's moving bodies for substeps of h (s) under
  /// gravity (m/s^2), and makes them live (rigid_body.cpp). Only before the step's first
  /// substep: the lanes' start-of-step pose is taken from the pose now (com_, q_), which is
  /// com0_ and q0_ until the first substep moves a body.
  void gather_free_motion(RigidBodySystem& s, double h, const Vec3& gravity);
  /// Puts the lanes' centres and frames back into the bodies' arrays; the lanes are no longer live.
  void scatter_free_motion(RigidBodySystem& s);
  /// The soft step, after prepare(): moves the bodies of `moving` that no block's lane writes
  /// (no contact point this step: nothing in the substeps reads or changes them but their own
  /// free motion) into `drifting` when their step has a closed form (no damping, no torque,
  /// and three equal principal moments or no angular velocity: coast()), else into
  /// `coasting` by kind, each list keeping its order.
  /// (For the soft step's substeps of h (s) under gravity (m/s^2); a step in which a drifting
  /// body would pass kMaxRigidSpeed has none: they all coast.)
  void split_coasting(RigidBodySystem& s, double h, const Vec3& gravity, int substeps);
  /// A substep's change of body i's velocity when it drifts (m/s): h (gravity scale g +
  /// inverse mass force), gravity in m/s^2. (The linear term of integrate_wide.cpp's
  /// step_changes, written for one body: a change to either is a change to both.)
  static Vec3 drift_change(const RigidBodySystem& s, std::uint32_t i, double h, const Vec3& gravity);
  /// The drifting bodies' step in closed form (their centres and velocities the substeps'
  /// sums, their frames one turn by the constant angular velocity), then the coasting bodies'
  /// `substeps` substeps of h (s) under gravity (m/s^2), a chunk of them
  /// at a time over all the substeps (the free motion's kernels in the substeps' order for
  /// each body: the same bits as the substeps' sweeps), their motion since the start of the
  /// step not written (only the contact lanes read it); throws as integrate_velocities does
  /// when a velocity goes beyond kMaxRigidSpeed (rigid_body.cpp).
  void coast(RigidBodySystem& s, double h, const Vec3& gravity, int substeps);
  /// The free motion's lanes live over a solver's substeps: gathered when made, the centres and
  /// frames put back when it ends, on an unwind too (the soft step and TGS share it, so no
  /// solver can leave the lanes live past its step, where a later step would read them stale).
  struct FreeLanesScope {
    RigidContacts& c;
    RigidBodySystem& s;
    FreeLanesScope(RigidContacts& contacts, RigidBodySystem& system, double h, const Vec3& gravity)
        : c(contacts), s(system) {
      c.gather_free_motion(s, h, gravity);
    }
    ~FreeLanesScope() {
      if (c.free_lanes_live) c.scatter_free_motion(s);
    }
    FreeLanesScope(const FreeLanesScope&) = delete;
    FreeLanesScope& operator=(const FreeLanesScope&) = delete;
  };
  /// World inverse inertias; for the velocity solvers, the colours, the blocks and the
  /// carried impulses in the warm-start accumulators.
  void prepare(RigidBodySystem& s);
  /// The pairs' colours by contact-graph level (color_of, color_count, overflow_count).
  void color(RigidBodySystem& s);
  /// The blocks from the pairs and their colours.
  void build(RigidBodySystem& s);
  /// The pairs by_color[first, first + lanes) into block b's lanes, in their contact frames
  /// (the arithmetic on 8 or 4 lanes at once on the SIMD paths; the same bits on every path).
  /// B: ContactBlock (of `blocks`, `count` of them in use) or OnePointBlock (of `ones`).
  /// Returns the lanes whose pairs roll (bit l: lane l), so that build() lists them in `rolls`
  /// without reading the pairs again (by then their lines have left L1: 0.6 L1 read misses a
  /// manifold in a pyramid where none rolls).
  template <class B>
  std::uint32_t fill_block(RigidBodySystem& s, B* block_array, AnchorsOf<B::kPoints>* anchor_array, std::size_t count,
                  std::size_t b, std::size_t first);
  /// The inverse of rolling pair `index`'s relative angular inverse inertia (kg m^2) from
  /// inv_inertia, into rolling_mass[index] (prepare for XPBD, fill_block for the other solvers);
  /// nothing for a pair that does not roll.
  void set_rolling_mass(std::uint32_t index);
  /// Point p of pair k as the last step's solver saw it: its normal velocity before the solve
  /// (m/s; < 0 closes) and its largest single normal impulse (N s), from the pair's lane of
  /// the blocks; false (and nothing written) when no blocks hold the pair (XPBD, or no step yet).
  bool solver_report(std::size_t k, int p, double& approach, double& max_impulse) const;
  /// The bodies' arrays as the kernels see them.
  BodyArrays arrays(RigidBodySystem& s);
  /// The velocities back from the solver's rows to the system's arrays, and the rolling
  /// impulses to their pairs.
  void finish_velocities(RigidBodySystem& s);
  /// Adds every manifold's carried impulses to the warm-start accumulators; colored: also the
  /// coloured blocks' (false: build() added them as it filled the blocks).
  void accumulate_warm(RigidBodySystem& s, bool colored = true);
  /// The same for the rolling resistance of a lane that rolls.
  void warm_rolling(const Rolling& x);
  /// Rolling resistance of `x`, lane l of block k.
  void roll(Rolling& x, const ContactBlock& k, int l);
  /// One pass over the contacts: `bias` asks for position correction (false: the relax pass),
  /// `soft` for the soft-step constraint; `update_sep` first measures the separations at the
  /// poses now, `warm_next` then adds the impulses to the warm-start accumulators. The
  /// colours run first to last (the ground contacts last), each followed by the rolling
  /// resistance of its lanes that roll, then the overflow in pair order.
  void pass(RigidBodySystem& s, double h, bool bias, bool soft, bool update_sep, bool warm_next);
  /// Measures the separations at the poses now (after positions moved without a relax pass).
  void update_separations(RigidBodySystem& s);
  /// The colour of pair k in the last step (the number of colours for the overflow), -1 when
  /// not coloured.
  long color_of_pair(std::size_t k) const;
  /// Rescales the carried impulses to the solver's time step h (s): they were accumulated
  /// over steps of `impulse_h` (N s per substep of the soft step, TGS and XPBD, per step of
  /// sequential impulses), so a switch of solver, of substeps or of dt would otherwise start
  /// from impulses too large or too small by their ratio (a 5-stack switched from sequential
  /// impulses to TGS was kicked to 0.19 m/s).
  void carry_impulses(double h);
  /// Starts the soft step's and TGS's manifolds that are set down at rest on a slope past their
  /// friction angle from the impulses that hold them there, not from none (docs/rigid-bodies.md,
  /// "A start-up slide on a slope"): a pair that carries nothing, touches, and whose bodies'
  /// gravity over a substep (impulse_h) presses b onto a along the normal with less than
  /// 1 / mu times its slide along the plane, carries the normal impulse that stops the press and
  /// the friction mu times it against the slide (N s per substep), where it is the moving body's
  /// only pair. Others keep none.
  void carry_fresh_slides(const RigidBodySystem& s);
  /// Restitution for points that approached faster than the threshold, then the energy bound
  /// of the bodies that bounced off fixed bodies only (bound_bounces; dt: the step, s).
  void restitution(RigidBodySystem& s, double dt, const Vec3& gravity);
  /// The bodies whose every manifold this step is against bodies that do not move (static or
  /// asleep; not kinematic, not awake dynamic) and one of whose manifolds has restitution, into
  /// `bounces`, with their free motion over the next `h` seconds (under gravity, forces and
  /// torques, from the velocities v, w at orientations q, the system's now) and its energy
  /// bound. from_lanes: the manifolds of restitution_lanes (the impulse solvers); otherwise
  /// the pairs (XPBD).
  void find_bounces(RigidBodySystem& s, double h, const Vec3& gravity, bool from_lanes, const Vec3* v,
                    const Vec3* w, const Quat* q);
  /// Each of `bounces`' bodies whose kinetic energy is now above its bound gets its velocities
  /// at the free motion plus the largest fraction of the contacts' change from it that keeps
  /// it at the bound (the root of a quadratic). rows: the velocities are the solver's rows
  /// (else the system's arrays).
  void bound_bounces(RigidBodySystem& s, bool rows);
  /// Each of `bounces`' bodies whose kinetic energy after the restitution pass is above both
  /// its energy before the pass and its energy at the step's start plus the work of gravity
  /// and force along the step's path (a body that rose during the step cannot also get back
  /// all that it approached with) gets its velocities before the pass plus the largest
  /// fraction of the pass's change that keeps it at that bound (the solver's rows; bodies
  /// under a torque are left as they are).
  void bound_bounce_work(RigidBodySystem& s, const Vec3& gravity);
  /// XPBD, a substep's bounces (before bound_bounces): each of `bounces`' bodies gets at most
  /// the kinetic energy it began the substep with plus the work of gravity and force along
  /// the path it took in it (from x_start to its centre now), and never less than its free
  /// motion's (bodies under a torque are left as they are). The bound of find_bounces lets a
  /// body that rose in the substep keep the energy it began with at the height it rose to:
  /// a tumbling 1 mm rod whose edges touched the ground in substep after substep as it rose
  /// gained m g times the rise each time, about 1e-3 of its start (docs/rigid-bodies.md, "The
  /// elastic bound").
  void bound_bounces_to_work(RigidBodySystem& s, const Vec3& gravity, const Vec3* x_start);
  /// The work of gravity and the body's force on body i along the path from `from` to its
  /// centre now (J).
  static double path_work(const RigidBodySystem& s, std::uint32_t i, const Vec3& gravity, const Vec3& from);
  // A collision with bodies that do not move cannot leave a body with more kinetic energy (in
  // their frame) than the larger of what it had and what its free motion would have had (a
  // bounce with e <= 1 gives back at most what the impact took). The solvers' passes over the
  // several points of a slender body's manifold can: a thin rod's end (4 points 2 mm apart,
  // principal moments 2,000,000 : 1) gained a thousandfold in a few bounces
  // (docs/rigid-bodies.md). Dynamic neighbours are left out: energy passes legitimately
  // through a chain (Newton's cradle).
  struct Bounce {
    std::uint32_t body;
    double bound;  // max(kinetic energy now, after the free motion) (J)
    double start, free;  // the kinetic energy now and after the free motion (J)
    Vec3 v, wb;    // the free motion's velocity (m/s) and angular velocity in the body frame (rad/s)
    Vec3 pre_v, pre_w;  // the solver's velocity (m/s) and world angular velocity (rad/s) before the restitution pass
  };
  std::vector<Bounce> bounces;
  std::vector<std::uint8_t> shared;  // by body, scratch of find_bounces (1: touches a body that moves; 2: listed)
  /// Sweeps fast bodies (and bullets) against static shapes, and bullets also against the
  /// moving non-bullet bodies at their poses at the step's end, and puts each back at its
  /// first time of impact (continuous.cpp).
  void continuous(RigidBodySystem& s);
  // continuous()'s parts for the bullets (continuous.cpp): how far the moving bodies' boxes at
  // the step's end stick out of their fat boxes (once a step), and bullet i's moving targets
  // along `path` (its path's bounds grown by its reach), into bullet_targets
  void prepare_targets(const RigidBodySystem& s);
  void find_targets(const RigidBodySystem& s, std::size_t i, const Aabb& path);
  /// The soft step's position pass after its substeps (push_out.cpp): when some point
  /// overlaps more than the linear slop at the poses now (or a manifold's springs have a
  /// shifted rest), moves the bodies of the manifolds that touch those bodies apart (without
  /// turning them) until none overlaps more than half the slop, shifts those manifolds'
  /// springs by as much, and takes away the approach of the bodies it moved apart. `gravity`
  /// says which body of a contact supports the other. True when it ran.
  bool push_out(RigidBodySystem& s, const Vec3& gravity);
  /// push_out's scratch: the deep manifolds (pair indices; in its second round the pairs of
  /// the pushed bodies, listed from the blocks), by body whether it is pushed, the manifolds to
  /// sweep, and by body its move.
  struct Ordered {
    double height;  // of the lower body (m; -1e300 for a body that does not move)
    double before;  // the deepest point's separation before the pass (m)
    double after;   // and after it (m)
    double ma, mb;  // the bodies' inverse masses for the pass (1/kg; 0: held still)
    bool held;      // the lower body is held still as the upper one's support
    double slop;    // the pair's linear slop (m): pair_slop() of its thinner body
    Vec3 n;         // the normal, from a to b
    std::uint32_t pair, a, b;
    std::uint32_t record;  // the pair's CachedManifold (its preload)
  };
  std::vector<std::uint32_t> deep;
  std::vector<std::uint32_t> preloaded;  // the pairs whose manifold has a preload (emit() lists them)
  std::vector<std::uint8_t> pushed;
  std::vector<Ordered> order;
  std::vector<Vec3> lift;  // by body: its move in the pass (m)
  /// Writes the blocks' impulses back to the pairs (after the soft step, sequential impulses
  /// and TGS; XPBD writes its own), for next step's warm start and contacts().
  void store();
  /// The TGS solver's step after prepare(): substeps of biased rigid iterations, positions,
  /// relax iterations (src/rigid/tgs.cpp); step() then runs the restitution pass.
  void step_tgs(RigidBodySystem& s, double dt, const Vec3& gravity);
  /// The XPBD solver's step after prepare(): substeps of positions, positional contacts and
  /// static friction, velocities from the positions, the velocity pass (src/rigid/xpbd_rigid.cpp).
  void step_xpbd(RigidBodySystem& s, double dt, const Vec3& gravity);

  // XPBD scratch: the poses at the start of the substep and after its free motion, by dense
  // body; each point's and manifold's multipliers (N s^2) and approach speeds, by pair
  std::vector<Vec3> x_start, x_free;
  std::vector<Quat> q_start, q_free;
  struct XpbdPair {
    double normal[Manifold::kMaxPoints];    // normal multipliers of the points
    double approach[Manifold::kMaxPoints];  // normal velocities before the position solve (m/s)
    Vec3 friction;                          // the static friction's positional impulse on b (kg m)
    double twist;                           // the static twist multiplier about the normal
  };
  std::vector<XpbdPair> xpbd;
  /// XPBD: one manifold's positional contacts and static friction, solved as a block.
  // (h: the substep, s; max_push: the most of a point's overlap at the start of the substep
  // pushed out in it, m)
  // (relax: the points' rows alone, for relax_overlap: a point that began the step touching
  // brought to the overlap `allow` (m), moved at most max_push either way, by the poses alone,
  // no multiplier kept; fixed: 1, 2 hold body a, b still; first: the substep's first
  // iteration, which turns a tipping body)
  void project(RigidBodySystem& s, ContactPair& c, XpbdPair& x, double h, double alpha, double max_push, bool relax,
               int fixed, double allow, bool first);
  /// XPBD after a switch from another solver, for substeps of h (s) under gravity (m/s^2): the
  /// overlap brought to XPBD's own at rest by moving the poses alone, from the fixed bodies up
  /// (src/rigid/xpbd_rigid.cpp).
  void relax_overlap(RigidBodySystem& s, double h, const Vec3& gravity);
  // relax_overlap's scratch: by dense body, the touching manifolds (relax_start into
  // relax_adjacent), the level (contacts from a fixed body), the weight carried (kg) and the
  // bodies breadth first; by pair, the overlap left (m; -1: apart); the pairs from the fixed
  // bodies up and the counting sort's buckets
  std::vector<std::uint32_t> relax_start, relax_adjacent, relax_queue, relax_order, relax_bucket;
  std::vector<int> relax_level;
  std::vector<double> relax_carried, relax_allow;
  /// No solver yet (last_solver before the first step).
  static constexpr RigidSolverType kNoSolver = static_cast<RigidSolverType>(255);
  RigidSolverType last_solver = kNoSolver;  ///< the solver of the last step
  /// Body i's solver state.
  static BodyView view(RigidBodySystem& s, std::size_t i) {
    return {&s.v_[i], &s.w_[i], &s.com_[i], &s.q_[i], s.asleep_[i] ? 0.0 : s.inv_mass_[i]};
  }
  /// For the tests of check_finite's call sites: writes `value` into number `component` of
  /// dense body i's centre (which 0, m), velocity (1, m/s), angular velocity (2, rad/s) or
  /// frame (3, the quaternion's four numbers), then runs check_finite (which throws naming the body).
  static void poison_and_check(RigidBodySystem& s, int which, std::size_t i, int component, double value);
  /// Whether dense body i's centre and every one of its shapes' frames fit a float (the
  /// colliders' range; check_finite's and fail's test, one body at a time).
  static bool in_float_range(const RigidBodySystem& s, std::size_t i);
};

}  // namespace pba::detail
