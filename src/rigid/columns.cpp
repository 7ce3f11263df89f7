// Rigid bodies: the soft step's substeps for tall columns (ContactSettings::auto_substeps).
//
// A column of boxes on soft contacts is an inverted pendulum chain: each face contact resists
// the boxes' relative tilt with its springs, and the weight above overturns it. Past its
// buckling load it leans over whatever the damping (docs/rigid-bodies.md, "Why 8 substeps and
// 120 Hz"). The contacts' stiffness is capped at a quarter of the substep rate, because one
// Gauss-Seidel sweep a substep does not hold a stiffer spring ("What we tried for tall stacks
// at default settings"), so the only way up is more substeps with the stiffness raised with
// them. The soft step measures its tallest columns each step and doubles the substeps and
// contact_hertz together while a column is past what the springs hold with a margin.
//
// The model. n cubes of side s and mass m on face contacts whose four points are springs of
// m_p w^2 each (m_p = m / 8 between two cubes), s / 2 from the tilt axis: each contact is a
// torsion spring k = 4 (m / 8) w^2 (s / 2)^2 = m w^2 s^2 / 8 every s of height, so the column
// bends as a beam of stiffness EI = k s = m w^2 s^3 / 8 under its own weight q = m g / s per
// metre. A column clamped at its foot and free at its top buckles under its own weight when
// q L^3 = 7.837 EI (Greenhill 1881; Timoshenko and Gere, "Theory of elastic stability", 2.11),
// L = n s: at n^3 = (7.837 / 8) w^2 s / g = 0.98 w^2 s / g. Measured at the defaults (8
// substeps, 120 Hz, the ground's contacts at 76 Hz; docs/rigid-bodies.md): the tallest columns
// that stand are 17 cubes of 10 cm, 21 of 20 cm, 30 of 50 cm and 37 of 1 m, n^3 = 0.85, 0.80,
// 0.93 and 0.87 of w^2 s / g (the softer ground and the discrete chain take the rest; the
// spring model of the tests, column_mode, gives 37 for 1 m). A column whose n^3 g / (w^2 s) is
// over kColumnLoad takes more substeps: the columns left at fewer carry at most 0.5 / 0.8 =
// 5/8 of the load under which the weakest measured column buckled.
//
// Which bodies make a column: a dynamic body resting on another on a face (a manifold of three
// points or more: one or two points are a hinge, which the springs do not hold upright and
// the model does not describe) whose normal is within 45 degrees of the vertical (steeper, the
// contact carries the body above more sideways than down: a wall is not a column), touching
// (its deepest point within the pair's linear slop). Levels are breadth first from the bodies
// that rest so on a body that does not move (static, kinematic or asleep), so a wide pile's
// height is its depth, not its width. The body's side s is taken as twice its smallest half
// size (exact for cubes; a plate lying flat counts as a cube of its thickness, which asks for
// more substeps than it needs, never fewer).
//
// Fewer substeps (ContactSettings::auto_substeps_sag_fraction, 2% of a body's size by default,
// and auto_substeps_sag in metres, none by default). The passes' cost goes with the substeps,
// so where the columns are short the step may take half of them (and half contact_hertz):
// when the columns' load fits the halved rate with the same room as the lowering above
// (kColumnLoad / 2 at the half: one-metre cubes up to 15 high), and the static sag the halving
// gives is at most half of each budget. The sag is predicted from the loads the contacts
// carried in the last step (their normal impulses per substep over the substep): a face
// contact of effective mass m_eff = 1 / (1/ma + 1/mb) (the lower body's taken as infinite when
// it does not move) on springs of w deflects by load / (m_eff w^2), and a body sinks as a body
// without turning on its springs to the bodies under it would (their stiffness-weighted mean
// of what each support sank plus its contact's deflection). For a column of cubes that is
// n g / w_g^2 + n (n - 1) g / w^2 (w_g the ground's rate), exactly the springs' sag; a
// pyramid's loads spread over the levels and the sum follows them, where the column's
// n^2 g / w^2 would take its height for a column's. The budget relative to size compares each
// body's sag with its own size (twice its smallest half size), and each touching contact's own
// deflection (any manifold: a ball's one point is no column) with the size of the smaller
// moving body on it: the springs sink a body g / w^2 whatever its size (0.17 mm on the ground
// at 4 substeps), a sixth of a 1 mm ball's radius but nothing to a one-metre cube. Back to the
// setting's substeps at once when either passes its whole bound, with kCalmTime before halving
// again in which the pairs stayed the same and every awake body moved slower than the sleep
// tolerances (at rest: the sag predicted is a rest's, and springs a quarter as stiff store four
// times the energy, which halving under a body moving on them feeds into its motion: a column
// rocking on its edges, docs/rigid-bodies.md, "Why rest").
#include <algorithm>
#include <cmath>

#include "contacts.h"

namespace pba {

namespace {

// the largest n^3 g / (w^2 s) a column may carry on the soft step's substeps (above)
constexpr double kColumnLoad = 0.5;
// the cosine of the steepest face that still counts as carrying the body above (45 degrees)
constexpr double kFaceCosine = 0.7071067811865476;
// the substeps (and contact_hertz) are raised by up to 2^this (8 -> 32 at the defaults:
// columns up to 4^(2/3) = 2.5 times as tall, at up to four times the solver's cost)
constexpr int kMostShift = 2;
// how long (s) the columns must fit half the factor before it is halved: a second is a
// period of a column's sway on its contacts (1.37 Hz for a 10-stack at the defaults), so a
// rocking column or a box sliding over it does not switch the substeps back and forth
constexpr double kCalmTime = 1;
// a column can grow while the pairs stay the same ones (a box on its edge settling onto its
// face, a speculative pair closing): measured at least every 8 steps (0.13 s at 60 Hz), within
// a small part of the time a column past its bound takes to lean (its lean grows e-fold in
// over 4 s at the 40-stack, 0.24/s), and so 1/8 of the measure's cost on a pile at rest
constexpr int kMeasureEvery = 8;

}  // namespace

namespace detail {

double RigidContacts::measure_columns(const RigidBodySystem& s, const Vec3& up, int& tallest, bool give,
                                     double w_dynamic, double w_static) {
  const std::size_t n = s.type_.size();
  auto moving = [&](std::uint32_t i) { return s.type_[i] == BodyType::Dynamic && !s.asleep_[i]; };
  // (room for every body and pair, so that steady state does not allocate)
  column_level.reserve(n), column_start.reserve(n + 1), column_queue.reserve(n);
  column_pairs.reserve(pairs.capacity()), column_edge.reserve(pairs.capacity());
  column_level.assign(n, 0);
  column_start.assign(n + 1, 0);
  column_queue.clear(), column_pairs.clear();
  if (give) {
    column_sink.reserve(n), column_pair_spring.reserve(pairs.capacity()), column_spring.reserve(pairs.capacity());
    column_sink.assign(n, {});
    column_pair_spring.clear();
  }
  // a face contact as a spring: its load (the normal impulse it carried in the last step's
  // substeps over the substep, impulse_h) and its stiffness m_eff w^2 (the points' springs in
  // parallel: for cubes face on face the points' effective masses, m / 8 each with their
  // turning, add up to the pair's m / 2)
  auto spring_of = [&](const ContactPair& c, double inv_mass, double w) {
    detail::RigidContacts::ColumnSpring k;
    if (impulse_h <= 0 || inv_mass <= 0) return k;
    for (int p = 0; p < c.count; ++p) k.load += c.normal_impulse[p];
    k.load /= impulse_h, k.stiffness = w * w / inv_mass;
    return k;
  };
  // the face pairs along `up`: the lower body's count of bodies on it, and the bodies on a
  // body that does not move (level 1)
  double ratio = 0;
  for (const ContactPair& c : pairs) {
    // (with `give`) every touching contact's own deflection under its load, over the size of
    // the smaller moving body on it: a ball's one point on the ground is no column, yet its
    // springs sink it g / w^2 (0.17 mm at 4 substeps, a sixth of a 1 mm ball's radius)
    if (give && c.count > 0 && (moving(c.a) || moving(c.b))) {
      double deepest = c.points[0].depth;
      for (int p = 1; p < c.count; ++p) deepest = std::max(deepest, c.points[p].depth);
      if (deepest >= -slop_of(s, c.a, c.b)) {
        const double inv_a = moving(c.a) ? s.inv_mass_[c.a] : 0, inv_b = moving(c.b) ? s.inv_mass_[c.b] : 0;
        const bool fixed = inv_a == 0 || inv_b == 0;
        const ColumnSpring k = spring_of(c, inv_a + inv_b, fixed ? w_static : w_dynamic);
        double side = INFINITY;
        if (moving(c.a)) side = 2 * s.min_extent_[c.a];
        if (moving(c.b)) side = std::min(side, 2 * s.min_extent_[c.b]);
        if (k.stiffness > 0 && side > 0) ratio = std::max(ratio, k.load / (k.stiffness * side));
      }
    }
    if (c.count < 3) continue;
    const double d = glm::dot(c.normal, up);
    if (std::abs(d) < kFaceCosine) continue;
    double deepest = c.points[0].depth;
    for (int p = 1; p < c.count; ++p) deepest = std::max(deepest, c.points[p].depth);
    if (deepest < -slop_of(s, c.a, c.b)) continue;
    const std::uint32_t lower = d > 0 ? c.a : c.b, upper = d > 0 ? c.b : c.a;
    if (!moving(upper)) continue;
    if (!moving(lower)) {
      if (column_level[upper] == 0) column_level[upper] = 1, column_queue.push_back(upper);
      if (give) {
        const ColumnSpring k = spring_of(c, s.inv_mass_[upper], w_static);
        column_sink[upper].load += k.load, column_sink[upper].stiffness += k.stiffness;
      }
    } else {
      column_pairs.push_back(std::uint64_t{lower} << 32 | upper);
      if (give) column_pair_spring.push_back(spring_of(c, s.inv_mass_[lower] + s.inv_mass_[upper], w_dynamic));
      ++column_start[lower + 1];
    }
  }
  // the bodies on each body (column_edge[column_start[i], column_start[i + 1]))
  for (std::size_t i = 0; i < n; ++i) column_start[i + 1] += column_start[i];
  column_edge.resize(column_pairs.size());
  if (give) column_spring.resize(column_pairs.size());
  for (std::size_t k = 0; k < column_pairs.size(); ++k) {
    const auto lower = static_cast<std::uint32_t>(column_pairs[k] >> 32);
    if (give) column_spring[column_start[lower]] = column_pair_spring[k];
    column_edge[column_start[lower]++] = static_cast<std::uint32_t>(column_pairs[k]);
  }
  // (the fill moved each start to the next body's: shift back)
  for (std::size_t i = n; i > 0; --i) column_start[i] = column_start[i - 1];
  column_start[0] = 0;
  // breadth first up the columns, with each body's load on the model and (with `give`) its
  // sink: held by the springs k_i under loads F_i to supports sunk by z_i, a body that sinks
  // without turning sinks by sum (F_i + k_i z_i) / sum k_i (one support: its z + F / k). Its
  // supports one level down are all reached before it; a support at its own level or higher
  // (a pile's bodies side by side) is left out of it, as the column model leaves it out
  double need = 0, sag = 0;
  std::uint32_t top = 0;
  for (std::size_t head = 0; head < column_queue.size(); ++head) {
    const std::uint32_t x = column_queue[head], l = column_level[x];
    const double side = 2 * s.min_extent_[x], cube = static_cast<double>(l) * l * l;
    need = std::max(need, cube / side);
    top = std::max(top, l);
    double sink = 0;
    if (give && column_sink[x].stiffness > 0) sink = column_sink[x].load / column_sink[x].stiffness;
    sag = std::max(sag, sink);
    if (side > 0) ratio = std::max(ratio, sink / side);
    for (std::uint32_t e = column_start[x]; e < column_start[x + 1]; ++e) {
      const std::uint32_t y = column_edge[e];
      if (column_level[y] == 0) column_level[y] = l + 1, column_queue.push_back(y);
      if (give && column_level[y] == l + 1) {
        const ColumnSpring& k = column_spring[e];
        column_sink[y].load += k.load + k.stiffness * sink, column_sink[y].stiffness += k.stiffness;
      }
    }
  }
  tallest = static_cast<int>(top);
  column_sag_top = sag, column_sag_ratio = ratio;
  return need;
}

}  // namespace detail

int RigidBodySystem::step_substeps(double dt, const Vec3& gravity) {
  detail::RigidContacts& c = *contacts_;
  c.hertz_scale = 1;
  profile_.column = 0;
  const int base = settings_.substeps;
  if (settings_.solver != RigidSolverType::SoftStep || !settings_.auto_substeps) {
    auto_shift_ = 0, auto_calm_ = 0;
    c.column_known = false;
    return settings_.solver == RigidSolverType::SequentialImpulse ? 1 : base;
  }
  // the contacts' angular rate (rad/s) at 2^shift times the substeps and contact_hertz (the
  // stiffness capped at a quarter of the substep rate, as the passes take it), and a static
  // contact's (twice that, at most one radian a substep)
  auto rate = [&](int shift) { return 2 * kPi * std::ldexp(std::min(settings_.contact_hertz, 0.25 * base / dt), shift); };
  auto static_rate = [&](int shift) { return std::min(2 * rate(shift), detail::kStaticStepAngle * std::ldexp(base / dt, shift)); };
  // halving (a sag budget: relative to the bodies' sizes, auto_substeps_sag_fraction, and
  // in metres, auto_substeps_sag) needs whole substeps
  const double budget = settings_.auto_substeps_sag, fraction = settings_.auto_substeps_sag_fraction;
  const int least = (budget > 0 || fraction > 0) && base % 2 == 0 ? -1 : 0;
  const double g = glm::length(gravity);
  // the same contact pairs as the last step
  const bool settled = c.pairs_same && c.pairs.size() == c.last_count;
  if (g == 0) {
    c.column_need = 0, c.column_top = 0, c.column_sag_top = 0, c.column_sag_ratio = 0, c.column_known = false;
  } else {
    // measured again when the pairs changed (a body came or went, woke or fell asleep), the
    // bodies or gravity's direction did, and otherwise every kMeasureEvery steps
    const Vec3 up = -gravity / g;
    const bool same = c.column_known && settled && c.column_bodies == type_.size() && c.column_up == up;
    if (!same || ++c.column_age >= kMeasureEvery) {
      c.column_need = c.measure_columns(*this, up, c.column_top, least < 0, rate(-1), static_rate(-1));
      c.column_bodies = type_.size(), c.column_up = up, c.column_age = 0, c.column_known = true;
    }
  }
  const double need = c.column_need;  // n^3 / s (1/m)
  profile_.column = c.column_top;
  // whether the columns fit 2^shift times the substeps with `margin` of the bounds: their load
  // n^3 g / (w^2 s), and below the setting's substeps the sag predicted at half of them, within
  // each budget that is set (a fraction of the bodies' sizes, metres)
  auto fits = [&](int shift, double margin) {
    const double w = rate(shift);
    if (need * g / (w * w) > margin * kColumnLoad) return false;
    return shift >= 0 || ((budget <= 0 || c.column_sag_top <= margin * budget) &&
                          (fraction <= 0 || c.column_sag_ratio <= margin * fraction));
  };
  // every awake dynamic body slower than the sleep tolerances this step: the sag is predicted
  // for bodies at rest, and a body moving on its contacts (a column rocking on its edges, a
  // pile's bodies settling) carries loads that are not its rest's
  auto still = [&] {
    const double v2 = settings_.sleep_linear * settings_.sleep_linear, w2 = settings_.sleep_angular * settings_.sleep_angular;
    for (std::size_t i = 0; i < type_.size(); ++i)
      if (type_[i] == BodyType::Dynamic && !asleep_[i] && (glm::dot(v_[i], v_[i]) >= v2 || glm::dot(w_[i], w_[i]) >= w2))
        return false;
    return true;
  };
  int most = 0;
  while (most < kMostShift && (base << (most + 1)) <= 64) ++most;
  int shift = least;
  while (shift < most && !fits(shift, 1)) ++shift;
  // raised at once; lowered a halving at a time, once the columns have fitted half the bounds
  // at half the factor (each 0.79 of the height that would raise it) for kCalmTime; below the
  // setting's substeps also only once the pairs have stayed the same and every body has been
  // still that long, so that neither a pile still landing (its contacts' loads not yet those of
  // its rest) nor a body moving on its contacts is halved: the Jolt pyramid halved while its
  // upper levels landed settled with its top 3.6 cm aside, against 1.0 cm at 8 substeps (and
  // halved at rest its top stays where it was), and a column of five cubes halved while it
  // rocked on its edges rocked on with the springs' 82 J more (docs/rigid-bodies.md, "Why rest")
  if (shift >= auto_shift_ || !fits(auto_shift_ - 1, 0.5) || (auto_shift_ == 0 && (!settled || !still()))) {
    auto_shift_ = std::max(shift, auto_shift_);
    auto_calm_ = 0;
  } else if ((auto_calm_ += dt) >= kCalmTime) {
    --auto_shift_;
    auto_calm_ = 0;
  }
  auto_shift_ = std::clamp(auto_shift_, least, most);  // (the settings may have changed)
  c.hertz_scale = std::ldexp(1.0, auto_shift_);
  return auto_shift_ >= 0 ? base << auto_shift_ : base >> 1;
}

}  // namespace pba
