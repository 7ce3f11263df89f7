// Rigid bodies: the XPBD contact solver.
//
// Mueller, Macklin, Chentanez, Jeschke and Kim (2020), "Detailed rigid body simulation with
// extended position based dynamics", Algorithm 2. The contact pairs and manifolds are found
// once per step (src/rigid/contact_pairs.cpp); each substep then
//   1. saves the poses and integrates velocities and positions freely (gravity, forces,
//      damping; the rotation by the exact-flow splitting of Dullweber et al. 1997, which keeps
//      a tumbling body's angular momentum where the paper's explicit gyroscopic term does not),
//   2. projects the contacts as positional constraints with the generalised inverse masses
//      w = 1/m + (r x n)^T I^-1 (r x n) and compliance (eqs. 2-9), and static friction as a
//      positional constraint on the tangential motion of the contact since the substep began
//      (section 3.5); no warm starting: the multipliers start from zero each substep,
//   3. sets the velocities from the position change (eqs. 12-13),
//   4. and runs the velocity pass: dynamic friction, restitution with a threshold speed
//      (eqs. 30-34).
// The separation of a point is measured as in the other solvers, from points on the shapes'
// cores turned with the bodies, along the manifold's normal.
//
// Where this departs from the paper (each measured; docs/rigid-bodies.md):
// - Friction acts on the manifold as a whole ("patch friction", as in the other solvers): one
//   tangential constraint at the points' centroid and one twist constraint about the normal,
//   within mu times the sum of the points' normal multipliers. On a face it translates, and
//   only the part of its moment the face's pressure cannot carry turns the body (on a body of
//   inverse mass 0, and only while the face sticks: tipping()). The paper's per-point static
//   friction under Gauss-Seidel lets the first point of a face contact take the whole
//   tangential correction against only its share of the load, so a box resting below the
//   friction angle slips.
// - Overlap a point begins a substep with is pushed out by at most push_out_speed h in it, as
//   the other solvers push it out at push_out_speed; projected at once, it became a velocity
//   of overlap / h (two boxes created 0.8 m into each other flew apart at 380 m/s).
// - A manifold's points and friction are solved together as a block (project() below), and
//   the sweep over the manifolds alternates its direction.
// - Static friction is kept inside the Coulomb disc rather than dropped when it would leave
//   it: a sliding contact gets mu times the normal multiplier as positional friction, and the
//   velocity pass's dynamic friction what is left of mu times the normal impulse.
// - Step 3 in the paper is v = (x - x_prev) / h and w = 2 vec(q q_prev^-1) / h. Here the
//   velocities of the free motion are kept and only the correction is added: v += (x - x_free)
//   / h and w += 2 vec(q q_free^-1) / h. For the translation this is the same (x_free = x_prev +
//   h v); for the rotation it keeps the splitting's end-of-substep angular velocity, so a body
//   that no contact touches moves exactly as under the other solvers.
// - Static friction holds the displacement of the material point at the contact (section
//   3.5: p - p_prev, p = x + q r) only for the lever's part to the shape's core (a box's corner
//   turns with the box); along the part from the core to a round surface (a ball's radius),
//   where the contact runs over the body as it rolls, it holds h times the velocity the
//   substep ends with: that point's displacement is the cycloid's, which braked small,
//   fast-turning balls (material_motion below).
// - Dynamic friction is limited as an impulse, mu times the substep's normal impulse (eq. 30
//   limits a velocity change by h mu f_n, which holds its units only for a unit mass): lambda_n
//   / h and what the velocity pass's point rows add, swept with those rows so that they hold
//   its moment (step 4 below). Rolling resistance acts in the velocity pass, as in the others.
#include "contacts.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace pba::detail {

namespace {

// q turned by the small rotation vector `theta` (rad): q + 1/2 [theta, 0] q, normalised
// (Mueller et al. 2020, eqs. 8-9)
void turn(Quat& q, const Vec3& theta) {
  const Quat dq(0, theta.x, theta.y, theta.z);
  q = glm::normalize(q + 0.5 * (dq * q));
}

// the rotation vector of the small rotation q (rad): 2 vec(q), the sign making w >= 0
Vec3 rotation_vector(const Quat& q) {
  const Vec3 v(q.x, q.y, q.z);
  return q.w >= 0 ? 2.0 * v : -2.0 * v;
}

// the turn of a body since the start of the step, to carry its anchors along
Quat turned(const Quat& now, const Quat& start) { return now * glm::conjugate(start); }

// the lever arms of point p when the bodies have turned by ta, tb since the start of the step:
// the anchors on the shapes' cores turn with the bodies, the step from the core to the contact
// stays along the normal (a rolling ball's contact stays below its centre, a box's corner
// turns with the box; the paper's fixed material points, r = q r_local, let a ball rolling
// at 12 rad/s push 11 degrees off its contact by the end of a 60 Hz step)
// (com0_a, com0_b: the centres at the start of the step, which the point's anchors are from).
// Two balls' steps are the normal's parts of those to the shared point, which lies off the line
// of centres when the normal is the touch's (touch_normal): each arm then goes from its ball's
// centre along the normal, and a frictionless push has no moment about either centre.
void levers(const ContactPair& c, int j, const Vec3& com0_a, const Vec3& com0_b, const Quat& ta, const Quat& tb,
            Vec3& ra, Vec3& rb) {
  const SolverPoint& p = c.points[j];
  Vec3 step_a = (p.at - com0_a) - p.sa, step_b = (p.at - com0_b) - p.sb;
  if (c.balls != 0) step_a = glm::dot(step_a, c.normal) * c.normal, step_b = glm::dot(step_b, c.normal) * c.normal;
  ra = ta * p.sa + step_a;
  rb = tb * p.sb + step_b;
}

// how far the body's material point at the contact has moved in the substep, the lever to it
// from the centre being core + step (m): core, to the point of the shape's core, turns with the
// body, so the material point there is the same one all substep and is held by its
// displacement, (x + core) - (x_start + q_start q^-1 core) (a box's corner or edge, which
// sticks when it does not move); step, from the core along the normal to the surface (a
// ball's or a capsule's radius), does not, as the contact runs over a round surface: the
// material point there changes as the body rolls, and it is held by h times the velocity the
// substep ends with, h w x step, step 3's w = w_free + 2 vec(q q_free^-1) / h (w_free: the free
// motion's angular velocity, which the solve leaves alone). Held by its displacement too, the
// point on the radius followed the cycloid, r (phi - sin phi) along the rolling of a turn phi
// (and beyond phi = pi the turn read as one the other way): static friction took that for
// slip and braked the ball, which slid once the brake passed mu (on 20 degrees, mu = 1, 8
// substeps of 1/60 s, balls of 1 mm, 5 mm and 1 cm rolled at 0.21, 0.82 and 0.97 of (5/7) g sin
// theta). Held by the end velocity everywhere (core included), boxes leaning on each other on
// edges rocked without end (2 of the 25 of RigidSleep.BoxesLeaningOnEachOtherFallAsleepAndStayPut,
// at up to 0.25 m/s, in 38 of 40 drops): for a corner the two measures differ by its chord's
// centripetal part, theta^2 r a substep, which the end velocity leaves free to slip.
Vec3 material_motion(const Vec3& x, const Vec3& x_start, const Quat& q, const Quat& q_start, const Vec3& w_free,
                     const Quat& q_free, double h, const Vec3& core, const Vec3& step) {
  return x - x_start + core - (q_start * glm::conjugate(q)) * core +
         glm::cross(h * w_free + rotation_vector(q * glm::conjugate(q_free)), step);
}

// The moment of a face's static friction about a body's centre that the face's pressure
// cannot carry (kg m^2, as a positional angular impulse; 0 while it can). Static friction on a
// face translates (project() below); physically its moment about the centre, c x f (c: the
// lever to the points' centroid, f: the friction on the body, kg m), is carried by the normal
// pressure moving over the face, its centre shifted by delta = -(n x M) / N (M: that moment
// across the normal, N: the points' total multiplier) from where the points push now. The
// face carries it while that shift stays within the extent along delta of the points that
// touch (`touching`: a point the manifold keeps apart, such as a 24-gon's next vertices 2 cm
// up, holds nothing); beyond it the pressure sits at the face's edge and what is left,
// (1 - tau) M (tau: the share the face carries), turns the body about its centre (the pivot at
// the edge comes from the next substep's point rows): a box held on a slope by friction tips
// once tan(theta) > width / height. The multipliers and friction are
// the substep's totals; the body's own sign (b gets +f, a gets -f) is the caller's. `edge`,
// `share`: the two points (j, j for one) between which the pressure then sits, at `share` of
// the way from the first to the second (set where it returns other than 0; -1 if nowhere).
Vec3 tipping(const ContactPair& c, const Vec3* levers, const Vec3& centroid, const double* normal, const bool* touching,
             const Vec3& f, std::array<int, 2>& edge, double& share) {
  double total = 0;
  Vec3 pressure(0);
  for (int j = 0; j < c.count; ++j) total += normal[j], pressure += normal[j] * (levers[j] - centroid);
  if (total <= 0) return Vec3(0);
  Vec3 moment = glm::cross(centroid, f);
  moment -= glm::dot(moment, c.normal) * c.normal;
  const Vec3 shift = -glm::cross(c.normal, moment) / total;
  const double length = glm::length(shift);
  if (length == 0) return Vec3(0);
  edge = {-1, -1};
  if (!std::isfinite(length)) return moment;  // (a friction coefficient near the largest double)
  // where a ray from the pressure's centre along u leaves the touching points' polygon: the
  // largest crossing of a segment between two of them (the polygon's edges among them; the
  // centre, a mean of touching points, lies within it). The farthest touching point along u
  // instead, a corner off the ray, made a box turned 30 degrees about the slope's normal tip
  // at 35 degrees, not 30
  const Vec3 u = shift / length, v = glm::cross(c.normal, u);
  const Vec3 from = pressure / total;
  double reach = 0;  // along u from the pressure's centre (m)
  for (int i = 0; i < c.count; ++i) {
    if (!touching[i] && !(normal[i] > 0)) continue;
    const Vec3 qi = levers[i] - centroid - from;
    const double ai = glm::dot(qi, u), bi = glm::dot(qi, v);
    if (bi == 0 && ai >= reach) reach = ai, edge = {i, i}, share = 0;
    for (int j = i + 1; j < c.count; ++j) {
      if (!touching[j] && !(normal[j] > 0)) continue;
      const Vec3 qj = levers[j] - centroid - from;
      const double aj = glm::dot(qj, u), bj = glm::dot(qj, v);
      if ((bi < 0 && bj > 0) || (bi > 0 && bj < 0)) {
        const double at = bi / (bi - bj), crossing = ai + at * (aj - ai);
        if (crossing >= reach) reach = crossing, edge = {i, j}, share = at;
      }
    }
  }
  const double carried = std::clamp(reach / length, 0.0, 1.0);
  return (1 - carried) * moment;
}

// A body's turn by the angular impulse `moment` (kg m^2, tipping()'s) about its centre, added
// to `dt` (kg m^2), and the face's pressure, which then sits at the face's edge, moved there:
// the substep's normal multipliers `total_normal` (this block's totals; the change from the
// substep's so far, `normal`, is `lambda`) go to the two points `edge` that the pressure's
// centre lies between (the first `1 - share` of them, the second `share`), their sum kept.
// Left where the block put them, the multipliers of the points away from the edge let the
// next iteration's block pull those points back into the fixed body (a multiplier may fall to
// 0) and so undo the turn: at substep_iterations 4 a box 2-10 degrees past its tipping angle
// on a mu 1.5 slope stood, and slid 0.11-0.14 m down it. (Turned about the edge instead, the
// edge pushed out along the normal with the turn, the box tipped too, but thin rods dropped on
// the ground gained 1-18% of their energy.)
void tip(const Vec3& moment, const std::array<int, 2>& edge, double share, int count, const double* total_normal,
         const double* normal, double* lambda, Vec3& dt) {
  dt += moment;
  if (moment == Vec3(0) || edge[0] < 0) return;
  double sum = 0;
  for (int j = 0; j < count; ++j) sum += total_normal[j];
  for (int j = 0; j < count; ++j) lambda[j] = -normal[j];
  lambda[edge[0]] += (1 - share) * sum, lambda[edge[1]] += share * sum;
}

}  // namespace

// One manifold's positional constraints (Mueller et al. 2020, eqs. 2-9 and section 3.5),
// linearised at the poses now and solved together: the points' non-penetration (lambda >= 0,
// compliance alpha~), two tangential static friction rows at the points' centroid and one
// twist row about the normal, both kept within mu times the normal multipliers. Projected
// Gauss-Seidel over these at most seven rows, 4 x manifold_iterations sweeps of the small
// matrix K = J M^-1 J^T (cheap: no poses move), then the impulses applied to the poses once.
// Sweeping the constraints on the poses one at a time instead (as eq. 4 reads) converges
// slowly on a face: the first point corrected turns the body, the friction at the centroid
// sees the turn as slip, and what is left, divided by h into a velocity, rocks a stack (a box
// on a 25 degree slope, mu 0.5, crept at 1.3 cm/s with one sweep of each).
void RigidContacts::project(RigidBodySystem& s, ContactPair& c, XpbdPair& x, double h, double alpha, double max_push,
                            bool relax, int fixed, double allow, bool first) {
  constexpr int kRows = Manifold::kMaxPoints + 3;
  const ContactSettings& cs = s.settings_;
  auto a = view(s, c.a), b = view(s, c.b);
  static const Mat3 kFixed(0.0);
  const Mat3& ia = fixed & 1 ? kFixed : inv_inertia[c.a];
  const Mat3& ib = fixed & 2 ? kFixed : inv_inertia[c.b];
  if (fixed & 1) a.inv_mass = 0;
  if (fixed & 2) b.inv_mass = 0;
  if (a.inv_mass == 0 && b.inv_mass == 0) return;
  // the rows: a change of constraint lb.dxb + ab.dthb - la.dxa - aa.dtha, and its error now
  Vec3 la[kRows], aa[kRows], lb[kRows], ab[kRows];
  double error[kRows], lambda[kRows] = {};
  const Quat ta = turned(*a.q, s.q0_[c.a]), tb = turned(*b.q, s.q0_[c.b]);
  Vec3 ca(0), cb(0), core_a(0), core_b(0);
  Vec3 a_levers[Manifold::kMaxPoints], b_levers[Manifold::kMaxPoints];
  const int n = c.count;
  bool overlap = false;
  for (int j = 0; j < n; ++j) {
    const SolverPoint& p = c.points[j];
    Vec3 ra, rb;
    levers(c, j, s.com0_[c.a], s.com0_[c.b], ta, tb, ra, rb);
    a_levers[j] = ra, b_levers[j] = rb;
    ca += ra, cb += rb;
    core_a += ta * p.sa, core_b += tb * p.sb;
    la[j] = lb[j] = c.normal;
    aa[j] = glm::cross(ra, c.normal), ab[j] = glm::cross(rb, c.normal);
    error[j] = glm::dot((*b.com + tb * p.sb) - (*a.com + ta * p.sa), c.normal) + p.offset;
    if (relax) {
      // relax_overlap: a point that began the step touching (at the poses of the step's start)
      // is brought to the overlap `allow`, moved at most max_push, both ways (x: scratch, its
      // multipliers' bound lifted); a point apart is kept apart
      const double start = glm::dot((s.com0_[c.b] + p.sb) - (s.com0_[c.a] + p.sa), c.normal) + p.offset;
      if (start <= 0) {
        error[j] -= start + std::clamp(-start - allow, -max_push, max_push);
        x.normal[j] = std::numeric_limits<double>::max();  // (finite: alpha 0 times it)
      }
      overlap = overlap || error[j] != 0;
      continue;
    }
    // overlap the substep began with is pushed out at most push_out_speed h a substep (what
    // this substep's motion closed is undone in full): projected at once and made a velocity
    // by step 3, 0.8 m of overlap flung two boxes apart at 380 m/s. (Only a point overlapping
    // more than that now can need it: resting contacts skip the start's separation.)
    if (error[j] < -max_push) {
      const double start = glm::dot((x_start[c.b] + turned(q_start[c.b], s.q0_[c.b]) * p.sb) -
                                        (x_start[c.a] + turned(q_start[c.a], s.q0_[c.a]) * p.sa),
                                    c.normal) + p.offset;
      if (start < -max_push) error[j] += -max_push - start;
    }
  }
  if (relax && !overlap) return;
  ca /= static_cast<double>(n), cb /= static_cast<double>(n);
  core_a /= static_cast<double>(n), core_b /= static_cast<double>(n);
  if (!relax) {  // (the friction rows; relax_overlap solves the points alone)
    // static friction: the tangential motion in the substep of the material points at the
    // centroid (material_motion); twist: the relative turn about the normal since the substep
    // began
    const Vec3 moved =
        material_motion(*b.com, x_start[c.b], *b.q, q_start[c.b], *b.w, q_free[c.b], h, core_b, cb - core_b) -
        material_motion(*a.com, x_start[c.a], *a.q, q_start[c.a], *a.w, q_free[c.a], h, core_a, ca - core_a);
    const Vec3 tangent[2] = {c.t1, c.t2};
    for (int d = 0; d < 2; ++d) {
      la[n + d] = lb[n + d] = tangent[d];
      // on a face (three or more points) static friction translates only: the points block
      // the turn its lever would give, and with the turn in, what the sweep over the manifolds
      // left of it became a rocking velocity (the 20-stack fell at 15 s, and even at 32
      // substeps). What of its moment the face cannot carry is given below (tipping())
      const bool face = n >= 3;
      aa[n + d] = face ? Vec3(0) : glm::cross(ca, tangent[d]);
      ab[n + d] = face ? Vec3(0) : glm::cross(cb, tangent[d]);
      error[n + d] = glm::dot(moved, tangent[d]);
    }
    la[n + 2] = lb[n + 2] = Vec3(0);
    aa[n + 2] = ab[n + 2] = c.normal;
    error[n + 2] = glm::dot(rotation_vector(*b.q * glm::conjugate(q_start[c.b])) -
                                rotation_vector(*a.q * glm::conjugate(q_start[c.a])),
                            c.normal);
  }
  const bool friction = !relax && c.friction > 0;
  const bool twist = friction && c.twist_radius > 0;
  const int rows = relax ? n : n + 3;
  // K = J M^-1 J^T
  double k[kRows][kRows];
  for (int r = 0; r < rows; ++r)
    for (int q = 0; q < rows; ++q)
      k[r][q] = a.inv_mass * glm::dot(la[r], la[q]) + b.inv_mass * glm::dot(lb[r], lb[q]) +
                glm::dot(aa[r], ia * aa[q]) + glm::dot(ab[r], ib * ab[q]);
  // projected Gauss-Seidel on (K + alpha~) dlambda = -C - alpha~ lambda (eq. 4), lambda >= 0
  // for the points, the friction rows inside mu times the points' total
  auto residual = [&](int r) {
    double v = error[r];
    for (int q = 0; q < rows; ++q) v += k[r][q] * lambda[q];
    return v;
  };
  const Vec3 carried = x.friction;
  bool sticks = true;  // the static friction inside its disc at the last sweep
  for (int sweep = 0; sweep < 4 * cs.manifold_iterations; ++sweep) {
    double total = 0;
    for (int j = 0; j < n; ++j) {
      // a point apart (C > 0) stays at its lower bound unless the others would push it in
      const double kk = k[j][j] + alpha;
      if (kk > 0)
        lambda[j] = std::max(lambda[j] - (residual(j) + alpha * (x.normal[j] + lambda[j])) / kk, -x.normal[j]);
      total += x.normal[j] + lambda[j];
    }
    if (!friction || total == 0) continue;
    // static friction: the tangential rows together, inside the disc mu * total
    for (int d = 0; d < 2; ++d)
      if (k[n + d][n + d] > 0) lambda[n + d] -= residual(n + d) / k[n + d][n + d];
    const Vec3 t = carried + lambda[n] * c.t1 + lambda[n + 1] * c.t2;
    const double limit = c.friction * total, len = glm::length(t);
    sticks = len <= limit;
    if (len > limit) {
      const Vec3 clamped = t * (limit / len) - carried;
      lambda[n] = glm::dot(clamped, c.t1), lambda[n + 1] = glm::dot(clamped, c.t2);
    }
    // twist, inside mu * total * the points' mean distance from the centroid
    if (twist && k[n + 2][n + 2] > 0) {
      const double tl = c.friction * total * c.twist_radius;
      lambda[n + 2] = std::clamp(x.twist + lambda[n + 2] - residual(n + 2) / k[n + 2][n + 2], -tl, tl) - x.twist;
    }
  }
  // apply the impulses to the poses
  Vec3 dxa(0), dxb(0), dta(0), dtb(0);
  for (int r = 0; r < rows; ++r) {
    dxa -= (a.inv_mass * lambda[r]) * la[r], dta -= lambda[r] * aa[r];
    dxb += (b.inv_mass * lambda[r]) * lb[r], dtb += lambda[r] * ab[r];
  }
  if (first && friction && n >= 3 && sticks) {
    // a face's static friction translates (above); the part of its moment that the face's
    // pressure cannot carry turns a body on a fixed one (inverse mass 0 here: static,
    // kinematic, or a dynamic body asleep) about its centre (tipping; the pivot at the face's
    // edge comes from the next substep's point rows), once a substep, in its first iteration,
    // the face's pressure moved to that edge (tip() above) so that the later iterations'
    // blocks keep the turn. Given after each iteration as the totals' tipping less the
    // iteration's start's, with the pressure left where the blocks put it, the later
    // iterations undid the turn, and at substep_iterations 4 a box 2-10 degrees past its
    // tipping angle on a mu 1.5 slope did not tip and slid 0.11-0.14 m. Bodies on dynamic ones
    // keep translating only: there each body's share is carried by its other contacts, which
    // the sweep over the manifolds does not see here, and given in full, the moments felled
    // the 10- and 20-stacks. Only while the face sticks: given here while sliding, rods 1 mm x
    // 4 m dropped at 10 and 30 degrees still rocked with 2-27 times the 2% of their energy the
    // bound leaves them after 9 s. (A sliding face's moment is so lost: the velocity pass's
    // friction is capped at mu times the normal impulse less the static friction's, about 0
    // once that is clamped; docs/rigid-bodies.md, "XPBD, tipping".)
    double after[Manifold::kMaxPoints];
    bool touching[Manifold::kMaxPoints];
    for (int j = 0; j < n; ++j) {
      after[j] = x.normal[j] + lambda[j];
      touching[j] = error[j] <= 0;
    }
    const Vec3 f_after = x.friction + lambda[n] * c.t1 + lambda[n + 1] * c.t2;
    std::array<int, 2> edge{-1, -1};
    double share = 0;
    if (a.inv_mass == 0 && b.inv_mass > 0)
      tip(tipping(c, b_levers, cb, after, touching, f_after, edge, share), edge, share, n, after, x.normal, lambda,
          dtb);
    if (b.inv_mass == 0 && a.inv_mass > 0)
      tip(-tipping(c, a_levers, ca, after, touching, f_after, edge, share), edge, share, n, after, x.normal, lambda,
          dta);
  }
  *a.com += dxa, *b.com += dxb;
  // (a body relax_overlap holds, or one that cannot move, keeps its rotation's bits: turn()
  // renormalises)
  if (!relax || a.inv_mass != 0) turn(*a.q, ia * dta);
  if (!relax || b.inv_mass != 0) turn(*b.q, ib * dtb);
  for (int j = 0; j < n; ++j) x.normal[j] += lambda[j];
  x.friction += lambda[n] * c.t1 + lambda[n + 1] * c.t2;
  x.twist += lambda[n + 2];
}

// A switch to XPBD from another solver: the overlap its contacts rest at (the soft step's
// spring deflection, sequential impulses' slop; 1.7 and 3.7 mm deep at the bottom of a
// 10-stack) is brought to the overlap XPBD itself rests at by moving the poses alone, before
// the first substep. Left to the substeps, overlap beyond XPBD's own was pushed out a substep's
// correction at a time, which step 3 made a velocity (a resting 10-stack switched to XPBD
// jumped to 0.27 m/s from the soft step and 0.46 m/s from sequential impulses); pushed out to
// none, the stack fell back into XPBD's own overlap (a 20-stack at 0.30 m/s).
// XPBD's own overlap at rest: with no compliance, what one sweep a substep leaves of the
// gravity drop g h^2 that every body's free motion adds. Measured in a stack of equal boxes
// built under XPBD, a contact rests (g h^2) times the number of boxes it carries deep (at a
// step's start the ground's contact holds none and the one above it both theirs), n (n + 1) /
// 2 g h^2 summed under the top of an n-stack (2.3 mm at 10, 8.9 mm at 20, at 8 substeps of
// 1/60 s): a contact carrying force F on a body of mass m rests F h^2 / m deep, plus the
// compliance's alpha F (spread over the points). The relaxation estimates F for each manifold
// from the weight above it (each body's weight and what it carries, split over the manifolds
// that hold it up) and brings each touching point to that overlap, both ways (what is beyond
// it pushed out; a point shallower set into it, where XPBD would let it fall), moving it at
// most the pair's slop (slop_of; the other solvers rest within it). The estimate matches
// XPBD's rest in total under the top of a column, n (n + 1) / 2 g h^2, not contact by contact
// (the ground's and the next contact differ at XPBD's step start, as above).
// A manifold holds a body up when its normal, turned into the body, points against gravity
// (kSupportLift below): a wall beside a column touches every box and holds none up; counted as
// a support, it made every box level 1 and took half of each box's weight, which became no
// force through its level normal (a 10-stack against a wall 1 mm in jumped to 0.46 m/s from
// sequential impulses). The weight is split over the supports in proportion to how much each
// holds up.
// Position-only Gauss-Seidel converges slowly up a column (the sweeps needed grow as its height
// squared), so the manifolds are taken from the fixed bodies up (shock propagation, Guendelman,
// Bridson and Fedkiw 2003): each body's level is its distance in supporting manifolds from a
// fixed body (a breadth-first search over them; in every touching manifold under no gravity,
// where none supports), and a manifold between levels moves only its upper body; a column is
// relaxed in one sweep, and `kRelaxSweeps` take the turns the points' levers give.
void RigidContacts::relax_overlap(RigidBodySystem& s, double h, const Vec3& gravity) {
  constexpr int kRelaxSweeps = 4;
  constexpr int kFloating = std::numeric_limits<int>::max();
  const std::size_t n = s.type_.size(), m = pairs.size();
  // the touching manifolds (some point not apart at the step's start) by body: relax_start[i]
  // to relax_start[i + 1] in relax_adjacent
  relax_start.assign(n + 1, 0);
  relax_allow.assign(m, -1);  // -1: apart, left out; else the overlap (m) left to a point
  for (std::size_t k = 0; k < m; ++k) {
    const ContactPair& c = pairs[k];
    for (int j = 0; j < c.count; ++j) {
      const SolverPoint& p = c.points[j];
      if (glm::dot((s.com0_[c.b] + p.sb) - (s.com0_[c.a] + p.sa), c.normal) + p.offset <= 0) {
        relax_allow[k] = 0, ++relax_start[c.a], ++relax_start[c.b];
        break;
      }
    }
  }
  for (std::size_t i = 1; i <= n; ++i) relax_start[i] += relax_start[i - 1];
  relax_adjacent.resize(relax_start[n]);
  for (std::size_t k = 0; k < m; ++k)
    if (relax_allow[k] == 0) {
      relax_adjacent[--relax_start[pairs[k].a]] = static_cast<std::uint32_t>(k);
      relax_adjacent[--relax_start[pairs[k].b]] = static_cast<std::uint32_t>(k);
    }
  // how much manifold c holds body u up: its normal turned into u, against gravity (1 under
  // no gravity, where every touching manifold counts). A manifold supports u above
  // kSupportLift: a face steeper than that (84 degrees from level) holds a weight only by a
  // friction coefficient over tan(acos 0.1) = 9.9, so a wall beside a column, or a floor under
  // a row that gravity presses along it, carries none of it
  constexpr double kSupportLift = 0.1;
  const double g_length = glm::length(gravity);
  const Vec3 up = g_length > 0 ? -gravity / g_length : Vec3(0);
  auto lift = [&](const ContactPair& c, std::uint32_t u) {
    return g_length > 0 ? glm::dot(c.b == u ? c.normal : -c.normal, up) : 1.0;
  };
  // each body's level, breadth first from the fixed bodies (static, kinematic, asleep) through
  // the supporting manifolds: 0 for those, else one more than the lowest of the bodies it
  // rests on; relax_queue: the bodies reached, by level
  relax_level.assign(n, kFloating);
  relax_queue.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (view(s, i).inv_mass == 0 && relax_start[i] < relax_start[i + 1])
      relax_level[i] = 0, relax_queue.push_back(static_cast<std::uint32_t>(i));
  for (std::size_t head = 0; head < relax_queue.size(); ++head) {
    const std::uint32_t u = relax_queue[head];
    for (std::uint32_t e = relax_start[u]; e < relax_start[u + 1]; ++e) {
      const ContactPair& c = pairs[relax_adjacent[e]];
      const std::uint32_t v = c.a == u ? c.b : c.a;
      if (relax_level[v] == kFloating && lift(c, v) > kSupportLift)
        relax_level[v] = relax_level[u] + 1, relax_queue.push_back(v);
    }
  }
  // the weight each body carries, from the top down (its mass and the shares of the bodies on
  // it), split over its supports on lower levels in proportion to their lift, and each
  // manifold's overlap left: the upper body's share of it, F, times h^2 / m and the compliance
  // over the points
  relax_carried.assign(n, 0);
  for (std::size_t r = relax_queue.size(); r-- > 0;) {
    const std::uint32_t u = relax_queue[r];
    const int level = relax_level[u];
    if (level == 0) continue;
    relax_carried[u] += 1 / s.inv_mass_[u];
    auto supports = [&](const ContactPair& c) {
      return relax_level[c.a == u ? c.b : c.a] < level && lift(c, u) > kSupportLift;
    };
    double lifts = 0;  // (> 0: the body was reached through a support on the level below)
    for (std::uint32_t e = relax_start[u]; e < relax_start[u + 1]; ++e) {
      const ContactPair& c = pairs[relax_adjacent[e]];
      if (supports(c)) lifts += lift(c, u);
    }
    for (std::uint32_t e = relax_start[u]; e < relax_start[u + 1]; ++e) {
      const std::uint32_t k = relax_adjacent[e];
      const ContactPair& c = pairs[k];
      if (!supports(c)) continue;
      const std::uint32_t v = c.a == u ? c.b : c.a;
      const double share = relax_carried[u] * lift(c, u) / lifts;  // kg
      if (relax_level[v] > 0) relax_carried[v] += share;
      const double force = share * std::abs(glm::dot(gravity, c.normal));  // N
      relax_allow[k] = force * (h * h * s.inv_mass_[u] + s.settings_.contact_compliance / c.count);
    }
  }
  // the touching manifolds from the fixed bodies up (a counting sort by the lower level; those
  // of bodies no fixed body is reached from last)
  std::size_t levels = 0;
  for (const std::uint32_t u : relax_queue) levels = std::max(levels, static_cast<std::size_t>(relax_level[u]) + 1);
  relax_bucket.assign(levels + 2, 0);
  auto bucket = [&](const ContactPair& c) {
    const int low = std::min(relax_level[c.a], relax_level[c.b]);
    return low == kFloating ? levels : static_cast<std::size_t>(low);
  };
  for (std::size_t k = 0; k < m; ++k)
    if (relax_allow[k] >= 0) ++relax_bucket[bucket(pairs[k]) + 1];
  for (std::size_t l = 1; l < relax_bucket.size(); ++l) relax_bucket[l] += relax_bucket[l - 1];
  relax_order.resize(relax_bucket.back());
  for (std::size_t k = 0; k < m; ++k)
    if (relax_allow[k] >= 0) relax_order[relax_bucket[bucket(pairs[k])]++] = static_cast<std::uint32_t>(k);
  for (int sweep = 0; sweep < kRelaxSweeps; ++sweep)
    for (const std::uint32_t k : relax_order) {
      ContactPair& c = pairs[k];
      const int la = relax_level[c.a], lb = relax_level[c.b];
      XpbdPair scratch{};
      project(s, c, scratch, h, 0, slop_of(s, c.a, c.b), true, la < lb ? 1 : lb < la ? 2 : 0, relax_allow[k], false);
    }
}

void RigidContacts::step_xpbd(RigidBodySystem& s, double dt, const Vec3& gravity) {
  const ContactSettings& cs = s.settings_;
  const std::size_t n = s.type_.size();
  const int substeps = cs.substeps;
  const double h = dt / substeps;
  // compliance per substep (alpha / h^2, eq. 4) and the restitution threshold: the setting or
  // the speed gravity gives in two substeps, whichever is larger (eq. 34)
  // (at most the largest double: beyond it, contact_compliance 1e308, inf * 0 made the
  // projection NaN; the largest is as soft, a contact that pushes nothing)
  const double alpha = std::min(cs.contact_compliance / (h * h), std::numeric_limits<double>::max());
  const double threshold = std::max(cs.restitution_threshold, 2 * glm::length(gravity) * h);
  x_start.resize(n), x_free.resize(n), q_start.resize(n), q_free.resize(n);
  xpbd.resize(pairs.size());
  // after another solver: the overlap it rested at pushed out by the poses alone
  if (last_solver != RigidSolverType::Xpbd && last_solver != kNoSolver) relax_overlap(s, h, gravity);
  for (int sub = 0; sub < substeps; ++sub) {
    // 1. free motion from the saved poses
    for (std::size_t i = 0; i < n; ++i) x_start[i] = s.com_[i], q_start[i] = s.q_[i];
    find_bounces(s, h, gravity, false, s.v_.data(), s.w_.data(), s.q_.data());
    s.integrate_velocities(h, gravity);
    // the normal velocities before the position solve, for restitution
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const ContactPair& c = pairs[k];
      const Quat ta = turned(s.q_[c.a], s.q0_[c.a]), tb = turned(s.q_[c.b], s.q0_[c.b]);
      for (int j = 0; j < c.count; ++j) {
        Vec3 ra, rb;
        levers(c, j, s.com0_[c.a], s.com0_[c.b], ta, tb, ra, rb);
        const Vec3 dv = s.v_[c.b] + glm::cross(s.w_[c.b], rb) - s.v_[c.a] - glm::cross(s.w_[c.a], ra);
        xpbd[k].approach[j] = glm::dot(dv, c.normal);
      }
    }
    s.integrate_positions(h);
    // the world inverse inertias of the bodies that turned far in the free motion, at their
    // poses now, as the other solvers take them after each substep's positions (kInertiaTurn).
    // Kept at the step's start, a thin box (0.09 x 1 x 0.05 m) tumbling into another box at
    // 120 m/s had its contacts' corrections turned through an inverse inertia its own had
    // left: each substep's turn, kept as an angular velocity by step 3, came out along a light
    // axis, and it spun up fiftyfold a substep to 2e8 rad/s within one 60 Hz step
    // (RigidSolvers.AThinBoxTumblingIntoABoxDoesNotSpinUp)
    refresh_inertia(s);
    for (std::size_t i = 0; i < n; ++i) x_free[i] = s.com_[i], q_free[i] = s.q_[i];
    for (XpbdPair& x : xpbd) {
      for (double& l : x.normal) l = 0;
      x.twist = 0;
      x.friction = Vec3(0);
    }
    // 2. positional contacts and static friction, Gauss-Seidel over the manifolds, each
    // manifold's small problem solved as a block; the sweep runs forward and backward in
    // turn (symmetric Gauss-Seidel): always forward, what one manifold's correction left in
    // the next one down the stack became a velocity at the end of every substep, the same
    // way each time, and a 10-stack fell within 10 s
    for (int it = 0; it < cs.substep_iterations; ++it)
      for (std::size_t k = 0; k < pairs.size(); ++k) {
        const std::size_t m = (sub + it) % 2 ? pairs.size() - 1 - k : k;
        project(s, pairs[m], xpbd[m], h, alpha, cs.push_out_speed * h, false, 0, 0, it == 0);
      }
    // 3. velocities from the corrections of the poses
    for (std::size_t i = 0; i < n; ++i) {
      if (s.type_[i] != BodyType::Dynamic || s.asleep_[i]) continue;
      s.v_[i] += (s.com_[i] - x_free[i]) / h;
      s.w_[i] += rotation_vector(s.q_[i] * glm::conjugate(q_free[i])) / h;
    }
    // 4. the velocity pass over the manifolds that pushed in this substep
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      ContactPair& c = pairs[k];
      const XpbdPair& x = xpbd[k];
      double total = 0;
      for (int j = 0; j < c.count; ++j) total += x.normal[j];
      if (total == 0) {
        // apart this substep: nothing pushed
        for (int j = 0; j < c.count; ++j) c.normal_impulse[j] = 0;
        c.tangent_impulse[0] = c.tangent_impulse[1] = c.twist_impulse = 0;
        c.rolling_impulse = Vec3(0);
        continue;
      }
      auto a = view(s, c.a), b = view(s, c.b);
      const Mat3& ia = inv_inertia[c.a];
      const Mat3& ib = inv_inertia[c.b];
      const Quat ta = turned(*a.q, s.q0_[c.a]), tb = turned(*b.q, s.q0_[c.b]);
      // the normal force of the substep as an impulse (N s): lambda / h (eq. 30's h f_n)
      const double normal_impulse = total / h;
      // restitution at each point that pushed: the normal velocity becomes e times the
      // approach before the position solve, or 0 below the threshold (eqs. 33-34); this also
      // takes back the push-out velocity of step 3, as a relax pass would. A point of the
      // manifold that did not push (on a face the block's multipliers are not unique, and
      // some corners get none) only has its approach stopped: left alone, such corners kept
      // approaching, tilted boxes landing on each other, and a falling column of ten fell
      // over. Swept `manifold_iterations` times, as the points are coupled, each point's
      // impulse kept from pulling more than the position solve pushed there (lambda / h, 0
      // where it did not push). Until 2026-12-03 the points that did not push were bounced
      // too, at e times their approach, one application at a time: corners that had not
      // touched threw frictionless boxes colliding at e = 1 apart with up to 25% more energy
      // than they met with (3.7% now, as the impulse solvers' 3%)
      // Then dynamic friction at the centroid: a tangential impulse against the sliding, up
      // to mu times the substep's normal impulse less what static friction took (eq. 30 limits
      // the velocity change by h mu f_n, which only holds units for a unit mass; as an impulse
      // it is Coulomb's law). The normal impulse is the position solve's, lambda / h, and what
      // the points' rows gave (the restitution, or the stop of an approach the position solve
      // did not reach; at least -lambda / h a point). Each friction sweep is followed by the
      // points' rows again, which hold its moment about the centre; their impulses there are
      // a couple and do not raise the limit (counted, with friction and rows swept together, a
      // box sliding down a 60 degree slope at mu = 1, whose trailing corners had no multiplier
      // to give back, slid 1.6% slow). With mu lambda / h applied once after the points, a
      // landing met by a speculative contact (which leaves only the overlap at the substep's
      // end to the position solve, so lambda / h was a fraction of the landing's impulse) got
      // a fraction of its friction, and the friction's moment, unheld, tipped a box onto its
      // leading edge and threw it up: a 1 m box landing flat at 5.8 m/s while moving at 6 m/s
      // hopped at 1.5 m/s and slid 2.73 m after the touch, where Coulomb's law at the landing
      // leaves 6 - mu 5.8 m/s and 0.99 m (now 0.98 m, the soft step's;
      // RigidFriction.ABoxLandingFlatWhileSlidingStopsWhereCoulombSays).
      Vec3 ca(0), cb(0);
      for (int j = 0; j < c.count; ++j) {
        Vec3 ra, rb;
        levers(c, j, s.com0_[c.a], s.com0_[c.b], ta, tb, ra, rb);
        ca += ra, cb += rb;
      }
      ca /= static_cast<double>(c.count), cb /= static_cast<double>(c.count);
      const Vec3 statics = x.friction / h;  // static friction's impulse (N s)
      Vec3 sliding(0);                      // dynamic friction's, over the sweeps (N s)
      double given[Manifold::kMaxPoints] = {};
      // the points' rows: the restitution, or the stop of the approach
      auto points = [&] {
        for (int j = 0; j < c.count; ++j) {
          Vec3 ra, rb;
          levers(c, j, s.com0_[c.a], s.com0_[c.b], ta, tb, ra, rb);
          const Vec3 dvj = *b.v + glm::cross(*b.w, rb) - *a.v - glm::cross(*a.w, ra);
          const double approach = x.approach[j];
          const double e = approach <= -threshold ? c.restitution : 0;
          const double target = x.normal[j] == 0 ? 0.0 : std::max(-e * approach, 0.0);  // see above
          const double m = effective_mass(a.inv_mass, b.inv_mass, ia, ib, ra, rb, c.normal);
          const double dvn = target - glm::dot(dvj, c.normal);
          const double gj = std::max(given[j] + dvn * m, -x.normal[j] / h);
          apply(a, b, ia, ib, ra, rb, (gj - given[j]) * c.normal);
          given[j] = gj;
        }
      };
      for (int sweep = 0; sweep < cs.manifold_iterations; ++sweep) points();
      // the substep's normal impulse: the position solve's and the rows' (N s); the rows
      // swept again below only hold the friction's moment, a couple, and do not count
      double pushed = normal_impulse;
      for (int j = 0; j < c.count; ++j) pushed += given[j];
      pushed = std::max(pushed, 0.0);
      const double limit = std::max(c.friction * pushed - glm::length(statics), 0.0);
      for (int sweep = 0; sweep < cs.manifold_iterations; ++sweep) {
        const Vec3 dv = *b.v + glm::cross(*b.w, cb) - *a.v - glm::cross(*a.w, ca);
        const Vec3 vt = dv - glm::dot(dv, c.normal) * c.normal;
        const double speed = glm::length(vt);
        Vec3 next = sliding;
        if (speed > 0)
          next -= (speed * effective_mass(a.inv_mass, b.inv_mass, ia, ib, ca, cb, vt / speed)) * (vt / speed);
        const double len = glm::length(next);
        if (len > limit) next *= limit / len;
        apply(a, b, ia, ib, ca, cb, next - sliding);
        sliding = next;
        if (limit > 0) points();
      }
      const Vec3 friction = statics + sliding;
      // dynamic twist friction and rolling resistance on the relative spin
      double twist = x.twist / h;
      if (c.twist_radius > 0) {
        const double k = glm::dot(c.normal, (ia + ib) * c.normal);
        const double spin = glm::dot(*b.w - *a.w, c.normal);
        const double limit = std::max(c.friction * pushed * c.twist_radius - std::abs(twist), 0.0);
        const double j = k > 0 ? std::clamp(-spin / k, -limit, limit) : 0;
        *a.w -= ia * (j * c.normal);
        *b.w += ib * (j * c.normal);
        twist += j;
      }
      if (c.rolling > 0) {
        Vec3 j = -(rolling_mass[k] * (*b.w - *a.w));
        const double limit = c.rolling * pushed, len = glm::length(j);
        if (len > limit) j *= limit / len;
        *a.w -= ia * j;
        *b.w += ib * j;
        c.rolling_impulse = j;
      }
      // the substep's impulses, for contacts(), islands and warm starting after a switch
      for (int j = 0; j < c.count; ++j) c.normal_impulse[j] = x.normal[j] / h;
      c.tangent_impulse[0] = glm::dot(friction, c.t1);
      c.tangent_impulse[1] = glm::dot(friction, c.t2);
      c.twist_impulse = twist;
    }
    // 5. the bodies that bounced off fixed bodies only keep at most their energy bound: no
    // more than they began the substep with plus the work of gravity along their path
    bound_bounces_to_work(s, gravity, x_start.data());
    bound_bounces(s, false);
  }
}

}  // namespace pba::detail
