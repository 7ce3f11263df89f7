// Rigid bodies, private: the contact pairs, their manifolds and the solvers' per-point data.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "pba/collide/narrow_phase.h"
#include "pba/rigid.h"
#include "solver.h"

namespace pba::detail {

/// One contact point as the solver sees it: anchors, effective masses and impulses.
struct SolverPoint {
  Vec3 ra{0, 0, 0}, rb{0, 0, 0};  // anchors from the centres of mass at the start of the step (m)
  // the separation now is dot(core_b_now - core_a_now, n) + offset, where core_x are the
  // points of the shapes' cores (a sphere's centre, a capsule's segment, a box's surface) at
  // sa, sb from the centres of mass, turned with the bodies: a rolling ball's surface point
  // turns away from the contact, its centre does not
  Vec3 sa{0, 0, 0}, sb{0, 0, 0};
  double offset = 0;              // (m)
  double normal_impulse = 0;      // accumulated (N s per substep)
  double max_normal_impulse = 0;  // largest single normal impulse of the step (N s)
  double approach = 0;            // normal relative velocity before the solve (m/s)
  double depth = 0;               // overlap at the start of the step (m)
  Vec3 local{0, 0, 0};            // the point in body a's frame (m), for matching by position
  std::uint32_t id = 0;           // feature id (warm starting)
};

/// A touching or speculative pair of shapes of two bodies. Friction acts on the manifold as
/// a whole ("patch friction", as PhysX and Jolt do): two tangential constraints at the
/// centroid of the points, limited together to the disc mu * (sum of normal impulses), and
/// one twist constraint about the normal, limited to mu * sum * the points' mean distance
/// from the centroid. Per-point friction clamped point by point lets opposing sideways
/// impulses at different points survive (they cancel in the sum but use up the disc), which
/// measurably weakens sliding friction.
struct ContactPair {
  std::uint32_t slot_a = 0, slot_b = 0;    // body handle slots (stable across removals)
  std::uint32_t shape_a = 0, shape_b = 0;  // shape indices within the bodies
  std::uint32_t a = 0, b = 0;              // dense body indices this step
  NarrowPhaseCache cache{};
  // from a to b, and the friction basis; (t1, t2, normal) is right-handed (t1 x t2 = normal),
  // which the solver's contact frame relies on (src/rigid/solver.h)
  Vec3 normal{0, 0, 1}, t1{1, 0, 0}, t2{0, 0, 1};
  double friction = 0, restitution = 0, rolling = 0;  // mixed coefficients (rolling: times radius, m)
  Vec3 ca{0, 0, 0}, cb{0, 0, 0};  // friction anchor (the points' centroid) from each centre of mass (m)
  double tangent_impulse[2] = {0, 0};  // accumulated (N s per substep)
  double twist_impulse = 0;  // accumulated (N m s per substep)
  double twist_radius = 0;   // mean distance of the points from the centroid (m)
  Vec3 friction_old{0, 0, 0};  // the tangential impulse in world axes at the end of the step
  Mat3 rolling_mass{0.0};    // inverse of the relative angular inverse inertia (kg m^2)
  Vec3 rolling_impulse{0, 0, 0};  // accumulated rolling-resistance angular impulse (N m s)
  int count = 0;
  SolverPoint points[Manifold::kMaxPoints];

  // the ordering of pairs (by body slots, then shapes): deterministic, and binary-searchable
  bool operator<(const ContactPair& o) const {
    if (slot_a != o.slot_a) return slot_a < o.slot_a;
    if (slot_b != o.slot_b) return slot_b < o.slot_b;
    if (shape_a != o.shape_a) return shape_a < o.shape_a;
    return shape_b < o.shape_b;
  }
};

/// A candidate pair of shapes from the sweep (sorted before the manifolds are made: sorting
/// these, not the kilobyte-sized ContactPairs, keeps the sort cheap).
struct PairKey {
  std::uint32_t slot_a = 0, slot_b = 0, shape_a = 0, shape_b = 0;  // as in ContactPair
  std::uint32_t a = 0, b = 0;                                      // dense body indices
  bool operator<(const PairKey& o) const {
    if (slot_a != o.slot_a) return slot_a < o.slot_a;
    if (slot_b != o.slot_b) return slot_b < o.slot_b;
    if (shape_a != o.shape_a) return shape_a < o.shape_a;
    return shape_b < o.shape_b;
  }
};

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

/// A shape's entry in the sweep: its bounds this step and who owns it.
struct ShapeProxy {
  Aabb box{};
  std::uint32_t body = 0;   // dense index
  std::uint32_t shape = 0;  // index within the body
};

/// Softness of a contact: Catto's soft step coefficients for a spring of `hertz` and
/// damping ratio `zeta` integrated implicitly over h (Box2D v3 b2MakeSoft).
struct Softness {
  double bias_rate = 0;      // 1/s
  double mass_scale = 1;     // in (0, 1]
  double impulse_scale = 0;  // in [0, 1)
};
Softness make_soft(double hertz, double zeta, double h);

/// The contact state of a RigidBodySystem: pairs (this step's and last step's), scratch
/// for the sweep, and the solver passes. Grown, never shrunk: steady state does not allocate.
struct RigidContacts {
  std::vector<ContactPair> pairs, previous;
  std::vector<ShapeProxy> proxies;
  std::vector<PairKey> candidates;  // the sweep's pairs this step, sorted
  std::vector<Mat3> inv_inertia;  // world inverse inertia by dense body, fixed over the step
  std::vector<std::uint32_t> statics;  // proxies of static bodies (indices into proxies)
  std::size_t continuous_hits = 0;     // bodies put back to a time of impact, all steps
  double impulse_h = 0;  // the time step (s) the carried impulses were accumulated over; 0: none yet

  // the velocity solvers' constraints (src/rigid/solver.h): blocks by colour, then the overflow's
  std::vector<ContactBlock> blocks;
  std::size_t block_count = 0;     // blocks in use
  std::size_t colored_blocks = 0;  // blocks [0, colored_blocks) are coloured, the rest overflow
  static constexpr std::uint32_t kOverflow = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> color_of;     // by pair: its colour (kOverflow: solved one at a time)
  std::vector<std::uint32_t> color_count;  // manifolds of each colour
  std::uint32_t overflow_count = 0;        // manifolds in the overflow
  std::vector<std::size_t> color_block;    // colour c's blocks from color_block[c]; then the overflow's
  // colouring scratch: contact-graph levels by body, the dynamic pairs' adjacency, bands by pair
  std::vector<std::uint32_t> level, adjacency_start, adjacency, queue, cursor, band_of, band_start, by_band;
  std::vector<std::uint32_t> mask_band;    // by body: the band its mask is for
  std::vector<std::uint64_t> mask;         // by body: the colours of that band it has manifolds in
  std::vector<std::uint32_t> by_color;     // the pairs by colour, in pair order within each
  std::vector<std::size_t> offset;         // scratch: each colour's start in by_color
  std::vector<std::uint32_t> band_colors;  // each band's first colour, then the number of colours
  bool backward = true;  // this step runs each band's colours last to first (alternating by step)
  struct LaneRef {
    std::uint32_t block, lane;
  };
  std::vector<LaneRef> restitution_lanes;  // the lanes with restitution, in pass order
  // by body, and a last spare row for empty lanes: the velocities while the solver runs, the
  // motion since the start of the step (dp, then the turn w, x, y, z), and the warm-start
  // velocity changes for the next integration
  std::vector<SolverBody> rows;
  std::vector<double> motion;
  std::vector<SolverBody> warm;
  SimdPath simd = best_simd_path();        // the path of the coloured blocks and the free motion
  std::vector<std::uint32_t> moving;       // the awake dynamic bodies this step (dense indices)
  bool built = false;       // the blocks hold this step's manifolds (cleared by store())
  bool has_colors = false;  // color_of holds the last step's colours

  /// Finds the overlapping shape pairs, builds their manifolds and carries last step's
  /// impulses over by feature id.
  void update(RigidBodySystem& s, double dt);
  /// World inverse inertias; for the velocity solvers, the colours, the blocks and the
  /// carried impulses in the warm-start accumulators.
  void prepare(RigidBodySystem& s);
  /// The pairs' colours by contact-graph level (color_of, color_count, overflow_count).
  void color(RigidBodySystem& s);
  /// The blocks from the pairs and their colours.
  void build(RigidBodySystem& s);
  /// Pair `index` into lane l of block k.
  void fill(RigidBodySystem& s, ContactBlock& k, int l, std::uint32_t index);
  /// The bodies' arrays as the kernels see them.
  BodyArrays arrays(RigidBodySystem& s);
  /// The velocities back from the solver's rows to the system's arrays.
  void finish_velocities(RigidBodySystem& s);
  /// Adds every manifold's carried impulses to the warm-start accumulators.
  void accumulate_warm(RigidBodySystem& s);
  /// The same for the rolling resistance of overflow lane l of block k.
  void warm_rolling(RigidBodySystem& s, const ContactBlock& k, int l);
  /// Rolling resistance of overflow lane l of block k.
  void roll(RigidBodySystem& s, const ContactBlock& k, int l);
  /// One pass over the contacts: `bias` asks for position correction (false: the relax pass),
  /// `soft` for the soft-step constraint; `update_sep` first measures the separations at the
  /// poses now, `warm_next` then adds the impulses to the warm-start accumulators. The
  /// colours run first to last (the ground contacts last), then the overflow in pair order.
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
  /// Restitution for points that approached faster than the threshold.
  void restitution(RigidBodySystem& s);
  /// Sweeps fast bodies (and bullets) against static shapes and puts each back at its first
  /// time of impact (continuous.cpp).
  void continuous(RigidBodySystem& s);
  /// Writes the blocks' impulses back to the pairs and keeps each manifold's friction impulse
  /// in world axes for next step's re-projection.
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
  void project(RigidBodySystem& s, ContactPair& c, XpbdPair& x, double alpha);
  /// Body i's solver state.
  static BodyView view(RigidBodySystem& s, std::size_t i) {
    return {&s.v_[i], &s.w_[i], &s.com_[i], &s.q_[i], s.asleep_[i] ? 0.0 : s.inv_mass_[i]};
  }
};

}  // namespace pba::detail
