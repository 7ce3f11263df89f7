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
//
// Below the halving, a ladder (2026-12-05): each rung three quarters of the last, rounded down
// (8 -> 4 -> 3 -> 2 -> 1), none under ContactSettings::auto_substeps_least (3 by default), with
// contact_hertz at the same fraction of the setting's (45 Hz at 3), so the springs' sag and the
// columns' load go as 1 / count^2: (4/3)^2 = 1.78 times the halving's at 3. Each rung is taken on
// the same three conditions judged at its own rate (the load and the sag measured at the
// halving's springs, scaled by the springs' squared ratio), after kCalmTime at the rung above,
// and back up at once to the fewest substeps whose whole bounds fit. At 3 the contact passes
// cost 3/4 of the halving's. The floor is the issue's: at 2 the Jolt pyramid of 2 m cubes sags
// 8.5 mm, past Bullet's 8.0, and at 3 4.8 mm (docs/rigid-bodies.md, "A ladder below the halving").
//
// Braced piles (measure_braced; with the halving's budgets). The column model counts a
// pile's height in bodies, but a cube in a square pyramid rests on four and carries four: its
// level is braced by the lattice, not a free column (the 20-level pyramid is 20 cubes high,
// load 0.55 at the halved rate, and stood 1000 steps at 4 substeps with its top sagging 4.3 mm).
// The halving is judged by a tilt chain of the pile's levels instead: bodies carrying a common body
// on face pairs (those above) move together as a level (union-find), where that body's springs on
// each are the stiffest the body has between moving bodies: the tie makes the path through the
// common body rigid, as stiff as a joint of the body's own chain made rigid, which the margin
// carries; a lighter or softer common body barely holds them, and tied through it a light plank
// over a column's top and a tall box would clamp the column's tilt to the box's footing (a column
// of 26 so tied was called 0.53, where alone it carries 1.2 and falls at 4 substeps, as it did).
// Bodies that only rest on a common body are not tied (what would tilt them alike is its own tilt,
// held by its own supports: a column's foot on a slab beside short cubes was clamped by their
// springs). Columns side by side, touching or not, stay apart: side contacts carry no load, and
// friction ties nothing. In each horizontal direction a level has three unknowns: its bodies' tilt
// t, each about its own centre; its turn psi, lifting each body by psi (x_body - x_level); and its
// lift z. Each point p of a face pair is a spring k_p = m_eff w^2 / points (the sag's springs),
// stretched by a . (t, psi, z) of the upper body's level less b . (t, psi, z) of the lower's, a =
// (x_p - x_upper, x_upper - x_level, 1) (b the same of the lower; none for a support that does not
// move). Gravity is the chain's geometric stiffness: a body tilted by t about its supports (their
// centroid at height z0, weighted by their loads) carries each load F on it at height z sideways by
// (z - z0) t and lowers it by (z - z0) t^2 / 2, its own weight so from its centre: G = sum F (z -
// z0) + m g (z_centre - z0) on its level's tilt, with the loads the contacts carried: every
// touching pair's on it, the vertical part of a pair's that is no face pair (a heavy ball's point,
// an edge, a steep face) at its points' height. The pile stands gravity times f when K - f G is
// positive definite; with each level on one level at most (a tree) a block LDL^T from the tips down
// decides it in O(levels). The load is kGreenhill / f at the least f it does not stand (bisected),
// which for a free column of n cubes is the column's own chain: n^3 g / (w^2 s) times 1.24 at 10
// cubes, 1.115 at 20 (the discrete chain and the softer foot carry less than Greenhill's clamped
// beam, by a part first order in 1 / n; the tallest measured to stand, 37, had 0.87 of the bound
// and is at 0.93 here), and by the same bound (kColumnLoad / 2). Braced, a cube cannot lean with
// its level below it: tilting alone it stretches its springs to its supports by their offset (half
// a cube in the pyramid), so the tilts do not add up the way a column's do, and a level tilting
// whole (t = psi) stands on the springs of a footing as wide as itself. The 20-level pyramid's load
// is 1.4e-3 and it halves at rest; 3 x 3 free columns of 20 touching keep their 0.62 (as one
// column), and a pyramid carrying a column of 20 keeps that column's (0.65). It is a Ritz estimate
// (every body of a level tilting alike), as the column model is (every cube alike): where bodies
// would tilt unlike each other it overstates what the pile carries; it is held to the same margin.
// What is not a tree takes the column model for the whole measure: a level resting on two levels (a
// plank bridging two columns: the columns under it sway as free columns, which a level joined
// through the plank would not; a common body not stiff enough to tie what it rests on), or resting
// on itself. Its cost is a union-find, the face points twice (two directions), and a pass over each
// tree of levels per factor tried: one for a tree that carries less than the most found so far,
// about 20 for one whose load is found. It is made only when the halving can use it (halved, or
// with the same pairs as the last step): a pile whose pairs change every step (the rain landing)
// restarts its calm every step whatever the load. Halved, a measure made because pairs changed
// elsewhere (a ball bouncing beside the pile) keeps the braced load of the same face pairs up to
// kMeasureEvery steps old, the cadence at rest; a face pair gained or lost, or a body made or
// destroyed, has it made again at once.
#include <algorithm>
#include <array>
#include <cmath>

#include "contacts.h"

namespace pba {

namespace {

// the largest n^3 g / (w^2 s) a column may carry on the soft step's substeps (above)
constexpr double kColumnLoad = 0.5;
// Greenhill's load of a free column of cubes in the column model's measure, 7.837 / 8: the
// braced model's load is this over the factor on gravity its chain stands (a free column of
// n cubes: n^3 g / (w^2 s), less the discrete chain's difference, 1.1 / n)
constexpr double kGreenhill = 7.837 / 8;
// the braced model's loads are found between these (below the first, the pile is far from
// any bound; above the second, far past them)
constexpr double kLeastLoad = 1e-5, kMostLoad = 1e3;
// the cosine of the steepest face that still counts as carrying the body above (45 degrees)
constexpr double kFaceCosine = 0.7071067811865476;
// the substeps (and contact_hertz) are raised by up to 2^this (8 -> 32 at the defaults:
// columns up to 4^(2/3) = 2.5 times as tall, at up to four times the solver's cost)
constexpr int kMostShift = 2;
// the most rungs below the setting's substeps (64 -> 32 -> 24 -> 18 -> 13 -> 9 -> 6 -> 4 -> 3
// -> 2 -> 1 is the longest ladder: the setting's floor, auto_substeps_least, ends it sooner)
constexpr int kMostRungs = 10;
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
    brace_face.reserve(pairs.capacity()), brace_load.reserve(pairs.capacity()), brace_key.reserve(pairs.capacity());
    brace_load_key.reserve(pairs.capacity());
    brace_face.clear(), brace_load.clear();
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
    // (a pair counts touching: its deepest point within its linear slop, and with a moving
    // body; what each body is, which is under, read once)
    if (c.count == 0) continue;
    const bool moves_a = moving(c.a), moves_b = moving(c.b);
    if (!moves_a && !moves_b) continue;
    double deepest = c.depth[0];
    for (int p = 1; p < c.count; ++p) deepest = std::max(deepest, c.depth[p]);
    if (deepest < -slop_of(s, c.a, c.b)) continue;
    const double d = glm::dot(c.normal, up);
    const std::uint32_t lower = d > 0 ? c.a : c.b, upper = d > 0 ? c.b : c.a;
    const bool moves_lower = d > 0 ? moves_a : moves_b, moves_upper = d > 0 ? moves_b : moves_a;
    // a face pair of the columns: three points or more (one or two are a hinge), within 45
    // degrees of the vertical, carrying a moving body
    const bool is_face = c.count >= 3 && std::abs(d) >= kFaceCosine && moves_upper;
    if (give) {
      // every touching contact's own deflection under its load, over the size of the smaller
      // moving body on it: a ball's one point on the ground is no column, yet its springs sink
      // it g / w^2 (0.17 mm at 4 substeps, a sixth of a 1 mm ball's radius)
      const double inv_a = moves_a ? s.inv_mass_[c.a] : 0, inv_b = moves_b ? s.inv_mass_[c.b] : 0;
      const bool fixed = inv_a == 0 || inv_b == 0;
      const ColumnSpring k = spring_of(c, inv_a + inv_b, fixed ? w_static : w_dynamic);
      double side = INFINITY;
      if (moves_a) side = 2 * s.min_extent_[c.a];
      if (moves_b) side = std::min(side, 2 * s.min_extent_[c.b]);
      if (k.stiffness > 0 && side > 0) ratio = std::max(ratio, k.load / (k.stiffness * side));
      // a touching pair that is no face pair of the columns (a ball's point, an edge, a steep
      // face, a body that does not move pressing from above) still loads the body under it:
      // the vertical part of its load, at its points' height, for the braced model's G
      if (!is_face && moves_lower && d != 0 && impulse_h > 0) {
        double load = 0, z = 0;
        for (int p = 0; p < c.count; ++p) load += c.normal_impulse[p], z += glm::dot(c.points[p].at, up);
        if (load > 0) brace_load.push_back({lower, load / impulse_h * std::abs(d), z / c.count});
      }
    }
    if (!is_face) continue;
    // (with `give`) the face pair for the braced model: its spring and its points' height
    auto face = [&](const ColumnSpring& k, bool moves) {
      double z = 0;
      for (int p = 0; p < c.count; ++p) z += glm::dot(c.points[p].at, up);
      brace_face.push_back({static_cast<std::uint32_t>(&c - pairs.data()), lower, upper, k.load, k.stiffness,
                            z / c.count, moves});
    };
    if (!moves_lower) {
      if (column_level[upper] == 0) column_level[upper] = 1, column_queue.push_back(upper);
      if (give) {
        const ColumnSpring k = spring_of(c, s.inv_mass_[upper], w_static);
        column_sink[upper].load += k.load, column_sink[upper].stiffness += k.stiffness;
        face(k, false);
      }
    } else {
      column_pairs.push_back(std::uint64_t{lower} << 32 | upper);
      if (give) {
        column_pair_spring.push_back(spring_of(c, s.inv_mass_[lower] + s.inv_mass_[upper], w_dynamic));
        face(column_pair_spring.back(), true);
      }
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

namespace {

// the lower Cholesky factor of a symmetric 3x3 block (row major) in place; false when it is
// not positive definite
bool cholesky3(std::array<double, 9>& a) {
  if (!(a[0] > 0)) return false;
  const double l00 = std::sqrt(a[0]), l10 = a[3] / l00, l20 = a[6] / l00;
  const double d1 = a[4] - l10 * l10;
  if (!(d1 > 0)) return false;
  const double l11 = std::sqrt(d1), l21 = (a[7] - l20 * l10) / l11;
  const double d2 = a[8] - l20 * l20 - l21 * l21;
  if (!(d2 > 0)) return false;
  a = {l00, 0, 0, l10, l11, 0, l20, l21, std::sqrt(d2)};
  return true;
}

}  // namespace

double RigidContacts::measure_braced(const RigidBodySystem& s, const Vec3& up, double g) {
  const std::size_t n = s.type_.size();
  brace_body.reserve(n), brace_level.reserve(n), brace_order.reserve(n), brace_tree.reserve(n), brace_s.reserve(n);
  brace_count.reserve(n + 1);
  brace_body.assign(n, {kNoIndex, kNoIndex, kNoIndex, 0, 0, 0, 0, 0});
  for (std::size_t i = 0; i < n; ++i) brace_body[i].root = static_cast<std::uint32_t>(i);
  brace_level.clear(), brace_order.clear();
  auto find = [&](std::uint32_t x) {
    while (brace_body[x].root != x) x = brace_body[x].root = brace_body[brace_body[x].root].root;
    return x;
  };
  // (the smaller index as root: the levels do not depend on the pair order)
  auto unite = [&](std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) brace_body[std::max(a, b)].root = std::min(a, b);
  };
  // a face pair between bodies on the columns (an upper body reached from the ground, on a
  // support that does not move or that was reached too)
  // (the face pairs it was made from, for brace_faces_same)
  brace_key.resize(brace_face.size());
  for (std::size_t i = 0; i < brace_face.size(); ++i) brace_key[i] = face_key(brace_face[i]);
  brace_load_key.resize(brace_load.size());
  for (std::size_t i = 0; i < brace_load.size(); ++i) brace_load_key[i] = brace_load[i].lower;
  // (the others are dropped here, once: what follows reads only these)
  brace_face.erase(std::remove_if(brace_face.begin(), brace_face.end(),
                                  [&](const BraceFace& f) {
                                    return column_level[f.upper] == 0 || (f.moving && column_level[f.lower] == 0);
                                  }),
                   brace_face.end());
  // the levels: bodies carrying a common body move together, where its springs on each are
  // the stiffest that body has (as support or as load). A tie makes the path through the
  // common body rigid: where that body's springs are each body's stiffest, the tie is as stiff
  // as a joint of the body's own chain made rigid, which the chain's margin carries (the
  // common body rests on both and tilts them alike); a lighter or softer common body barely
  // holds them, and tied it would clamp a column's top to whatever it also rests on (a light
  // plank over a column's top and a tall box: the box's footing would hold the column's tilt).
  // Untied, it rests on two levels: no tree, and the column model judges. Bodies that only rest
  // on a common body are not tied: what holds their tilts alike is that body's own tilt, held
  // by its own supports (a column's foot on a slab beside short cubes tilts alone).
  // (Springs between moving bodies only: a spring to a support that does not move runs at the
  // static rate, min(2 w, 1 / h), whose ratio to the dynamic one changes with dt and
  // contact_hertz, and a foot held fast is what the chain's clamped limit, Greenhill's, already
  // takes. Counted, at dt = 1/120 the ground's springs were the bottom row's stiffest, no cube
  // above tied that row, and a pyramid was judged a free column.)
  for (const BraceFace& f : brace_face) {
    if (!f.moving) continue;
    brace_body[f.upper].stiffest = std::max(brace_body[f.upper].stiffest, f.stiffness);
    brace_body[f.lower].stiffest = std::max(brace_body[f.lower].stiffest, f.stiffness);
  }
  for (const BraceFace& f : brace_face) {
    if (!f.moving || f.stiffness < brace_body[f.lower].stiffest) continue;
    BraceBody& upper = brace_body[f.upper];
    if (upper.down == kNoIndex) upper.down = f.lower; else unite(upper.down, f.lower);
  }
  // the horizontal directions the chain is tilted in
  const Vec3 pick = std::abs(up.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
  const Vec3 e0 = glm::normalize(pick - up * glm::dot(pick, up)), dir[2] = {e0, glm::cross(up, e0)};
  for (const std::uint32_t x : column_queue) {
    const std::uint32_t r = find(x);
    if (brace_body[r].level == kNoIndex) {
      brace_body[r].level = static_cast<std::uint32_t>(brace_level.size());
      BraceLevel& l = brace_level.emplace_back();
      l.parent = kNoIndex, l.depth = kNoIndex, l.count = 0, l.gravity = 0, l.size = INFINITY;
      for (int d = 0; d < 2; ++d) {
        l.sum[d] = 0, l.lo[d] = INFINITY, l.hi[d] = -INFINITY;
        std::fill(std::begin(l.d[d]), std::end(l.d[d]), 0.0), std::fill(std::begin(l.c[d]), std::end(l.c[d]), 0.0);
      }
    }
    BraceLevel& l = brace_level[brace_body[x].level = brace_body[r].level];
    ++l.count, l.size = std::min(l.size, 2 * s.min_extent_[x]);
    for (int d = 0; d < 2; ++d) {
      const double at = glm::dot(s.com_[x], dir[d]);
      l.sum[d] += at, l.lo[d] = std::min(l.lo[d], at), l.hi[d] = std::max(l.hi[d], at);
    }
  }
  // (a spread under a thousandth of its smallest body's size is a level in line along the
  // direction: it does not turn as a level, and its turn would be a zero pivot)
  // (and from here on sum is the level's centre, the turn's axis)
  for (BraceLevel& l : brace_level)
    for (int d = 0; d < 2; ++d) l.psi[d] = l.hi[d] - l.lo[d] > 1e-3 * l.size, l.sum[d] /= l.count;
  // each level rests on one level at most (or on bodies that do not move): the chain is a
  // tree. Otherwise (a level bridging two, a level resting on itself) the column model rules
  const auto levels = static_cast<std::uint32_t>(brace_level.size());
  for (const BraceFace& f : brace_face) {
    if (!f.moving) continue;
    const std::uint32_t lu = brace_body[f.upper].level, ll = brace_body[f.lower].level;
    BraceLevel& u = brace_level[lu];
    if (lu == ll || (u.parent != kNoIndex && u.parent != ll)) return -1;
    u.parent = ll;
  }
  // the depths from the ground and the tree's root (a walk longer than the levels is a cycle:
  // not a tree)
  for (std::uint32_t l = 0; l < levels; ++l) {
    std::uint32_t x = l, walk = 0;
    while (brace_level[x].depth == kNoIndex && brace_level[x].parent != kNoIndex) {
      x = brace_level[x].parent;
      if (++walk > levels) return -1;
    }
    if (brace_level[x].depth == kNoIndex) brace_level[x].depth = 0, brace_level[x].root = x;
    // down the walk again, numbering
    std::uint32_t depth = brace_level[x].depth + walk;
    for (std::uint32_t y = l; y != x; y = brace_level[y].parent)
      brace_level[y].depth = depth--, brace_level[y].root = brace_level[x].root;
  }
  // the order the elimination takes them in: by tree, each tree's deepest first (so a level
  // after those resting on it). Two counting sorts: by depth down, then (stable) by root
  brace_count.assign(levels + 1, 0);
  for (const BraceLevel& l : brace_level) ++brace_count[levels - l.depth];
  for (std::uint32_t i = 1; i <= levels; ++i) brace_count[i] += brace_count[i - 1];
  brace_order.resize(levels), brace_tree.resize(levels);
  for (std::uint32_t l = levels; l-- > 0;) brace_tree[--brace_count[levels - brace_level[l].depth]] = l;
  brace_count.assign(levels + 1, 0);
  for (const BraceLevel& l : brace_level) ++brace_count[l.root + 1];
  for (std::uint32_t i = 1; i <= levels; ++i) brace_count[i] += brace_count[i - 1];
  for (const std::uint32_t l : brace_tree) brace_order[brace_count[brace_level[l].root]++] = l;
  // gravity: a body tilted by t about its supports (the height of their centroid weighted by
  // their loads, z0) carries each load F on it at height z sideways by (z - z0) t and lowers
  // it by (z - z0) t^2 / 2, and its own weight so from its centre: the chain's geometric
  // stiffness, G = sum F (z - z0) + m g (z_c - z0) over the level's bodies (P-delta)
  for (const BraceFace& f : brace_face) {
    BraceBody& b = brace_body[f.upper];
    b.fz += f.load * f.z, b.f += f.load, b.z += f.z, ++b.supports;
  }
  auto base = [&](std::uint32_t x) {
    const BraceBody& b = brace_body[x];
    return b.f > 0 ? b.fz / b.f : b.z / b.supports;
  };
  for (const std::uint32_t x : column_queue)
    brace_level[brace_body[x].level].gravity += std::max(0.0, g / s.inv_mass_[x] * (glm::dot(s.com_[x], up) - base(x)));
  for (const BraceFace& f : brace_face)
    if (f.moving) brace_level[brace_body[f.lower].level].gravity += std::max(0.0, f.load * (f.z - base(f.lower)));
  // (and the loads of the pairs that are no face pairs: a heavy ball on a column's top)
  for (const BraceLoad& f : brace_load)
    if (column_level[f.lower] != 0 && brace_body[f.lower].supports > 0)
      brace_level[brace_body[f.lower].level].gravity += std::max(0.0, f.load * (f.z - base(f.lower)));
  // the springs: each point of a face pair a spring k_p of the pair's m_eff w^2 over its
  // points. A level's bodies tilt by t each (the lever x_p - x_body), the level turns by psi
  // (each body lifted by psi (x_body - x_level)) and lifts by z: the point's spring is
  // stretched by a . (t, psi, z) of the upper level less b . (t, psi, z) of the lower, a =
  // (du, a1, 1), b = (dl, b1, 1) with du = x_p - x_upper, dl = x_p - x_lower. The pair adds
  // k sum a a^T to the upper level's D, k sum b b^T to the lower's, -k sum a b^T to the
  // upper's C: made of the points' sums of du, dl, du^2, dl^2, du dl
  for (const BraceFace& f : brace_face) {
    const ContactPair& c = pairs[f.pair];
    // (made a step after the measure, a pair may have lost points since: no longer a face,
    // the model does not describe it, and the column model judges the pile)
    if (c.count < 3) return -1;
    const double k = f.stiffness / c.count, n = c.count;
    BraceLevel& u = brace_level[brace_body[f.upper].level];
    BraceLevel* l = f.moving ? &brace_level[brace_body[f.lower].level] : nullptr;
    for (int d = 0; d < 2; ++d) {
      const double xu = glm::dot(s.com_[f.upper], dir[d]), xl = f.moving ? glm::dot(s.com_[f.lower], dir[d]) : 0;
      const double a1 = u.psi[d] ? xu - u.sum[d] : 0, b1 = l && l->psi[d] ? xl - l->sum[d] : 0;
      double su = 0, sl = 0, suu = 0, sll = 0, sul = 0;
      for (int p = 0; p < c.count; ++p) {
        const double x = glm::dot(c.points[p].at, dir[d]), du = x - xu, dl = x - xl;
        su += du, sl += dl, suu += du * du, sll += dl * dl, sul += du * dl;
      }
      // (the blocks are symmetric: both triangles written)
      auto add = [](double* m, double s2, double s1, double one, double nn, double kk) {
        const double m01 = kk * (one * s1), m02 = kk * s1, m12 = kk * (one * nn);
        m[0] += kk * s2, m[1] += m01, m[2] += m02, m[3] += m01, m[4] += kk * (one * one * nn), m[5] += m12;
        m[6] += m02, m[7] += m12, m[8] += kk * nn;
      };
      add(u.d[d], suu, su, a1, n, k);
      if (!l) continue;
      add(l->d[d], sll, sl, b1, n, k);
      const double cross[9] = {sul, b1 * su, su, a1 * sl, a1 * b1 * n, a1 * n, sl, b1 * n, n};
      for (int i = 0; i < 9; ++i) u.c[d][i] -= k * cross[i];
    }
  }
  // (a level that does not turn: its turn is no unknown)
  for (BraceLevel& l : brace_level)
    for (int d = 0; d < 2; ++d)
      if (!l.psi[d]) l.d[d][4] = 1;
  brace_s.resize(levels);
  // the load: kGreenhill over the least factor on gravity the chain does not stand, to within
  // 2e-5 between kLeastLoad and kMostLoad (beyond them, those). Tree by tree: one that stands
  // the factor of the most found so far carries less and is passed over (one pass of it), so
  // only the trees that raise the most are bisected (a rain of small piles: one pass each)
  double most = kLeastLoad;
  for (std::uint32_t begin = 0, end = 0; begin < levels; begin = end) {
    while (end < levels && brace_level[brace_order[end]].root == brace_level[brace_order[begin]].root) ++end;
    if (braced_stands(kGreenhill / most, begin, end)) continue;
    if (!braced_stands(kGreenhill / kMostLoad, begin, end)) return kMostLoad;
    double stands = most, falls = kMostLoad;
    while (falls > stands * (1 + 2e-5)) {
      const double mid = std::sqrt(stands * falls);
      (braced_stands(kGreenhill / mid, begin, end) ? falls : stands) = mid;
    }
    most = falls;
  }
  return most;
}

bool RigidContacts::brace_faces_same() const {
  if (brace_key.size() != brace_face.size() || brace_load_key.size() != brace_load.size()) return false;
  for (std::size_t i = 0; i < brace_face.size(); ++i)
    if (brace_key[i] != face_key(brace_face[i])) return false;
  for (std::size_t i = 0; i < brace_load.size(); ++i)
    if (brace_load_key[i] != brace_load[i].lower) return false;
  return true;
}

bool RigidContacts::braced_stands(double factor, std::uint32_t begin, std::uint32_t end) {
  for (int d = 0; d < 2; ++d) {
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t l = brace_order[i];
      std::copy(std::begin(brace_level[l].d[d]), std::end(brace_level[l].d[d]), brace_s[l].begin());
      brace_s[l][0] -= factor * brace_level[l].gravity;
    }
    // block LDL^T of the tree, from its tips down: S_parent -= C^T S^-1 C
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t l = brace_order[i];
      std::array<double, 9>& f = brace_s[l];
      if (!cholesky3(f)) return false;
      const BraceLevel& v = brace_level[l];
      if (v.parent == kNoIndex) continue;
      // y = L^-1 C, column by column; then C^T S^-1 C = y^T y
      double y[9];
      for (int j = 0; j < 3; ++j) {
        y[j] = v.c[d][j] / f[0];
        y[3 + j] = (v.c[d][3 + j] - f[3] * y[j]) / f[4];
        y[6 + j] = (v.c[d][6 + j] - f[6] * y[j] - f[7] * y[3 + j]) / f[8];
      }
      std::array<double, 9>& p = brace_s[v.parent];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) p[3 * i + j] -= y[i] * y[j] + y[3 + i] * y[3 + j] + y[6 + i] * y[6 + j];
    }
  }
  return true;
}

}  // namespace detail

int RigidBodySystem::step_substeps(double dt, const Vec3& gravity) {
  detail::RigidContacts& c = *contacts_;
  c.hertz_scale = 1;
  profile_.column = 0, profile_.half_load = 0;
  const int base = settings_.substeps;
  if (settings_.solver != RigidSolverType::SoftStep || !settings_.auto_substeps) {
    auto_shift_ = 0, auto_calm_ = 0;
    c.column_known = false;
    return settings_.solver == RigidSolverType::SequentialImpulse ? 1 : base;
  }
  // the counts below the setting's (with a sag budget: relative to the bodies' sizes,
  // auto_substeps_sag_fraction, and in metres, auto_substeps_sag), the ladder's rungs: half of
  // an even `substeps` (8 -> 4), then three quarters of the last, rounded down (4 -> 3 -> 2 ->
  // 1), none under auto_substeps_least (3 by default: 8 -> 4 -> 3). Shift -k is the k-th rung
  const double budget = settings_.auto_substeps_sag, fraction = settings_.auto_substeps_sag_fraction;
  std::array<int, kMostRungs> rung{};
  int rungs = 0;
  if ((budget > 0 || fraction > 0) && base % 2 == 0)
    for (int n = base / 2; n >= std::max(settings_.auto_substeps_least, 1) && rungs < kMostRungs; n = 3 * n / 4)
      rung[static_cast<std::size_t>(rungs++)] = n;
  const int least = -rungs;
  // the substeps at `shift` (2^shift times `substeps`, or a rung below it), and the factor on
  // the substeps and contact_hertz there (exactly 2^shift for the powers of two)
  auto count = [&](int shift) { return shift >= 0 ? base << shift : rung[static_cast<std::size_t>(-shift - 1)]; };
  auto scale = [&](int shift) {
    return shift >= 0 ? std::ldexp(1.0, shift) : static_cast<double>(count(shift)) / base;
  };
  // the contacts' angular rate (rad/s) at `shift` (the stiffness capped at a quarter of the
  // substep rate, as the passes take it), and a static contact's (twice that, at most one
  // radian a substep)
  auto rate = [&](int shift) { return 2 * kPi * (std::min(settings_.contact_hertz, 0.25 * base / dt) * scale(shift)); };
  auto static_rate = [&](int shift) {
    return std::min(2 * rate(shift), detail::kStaticStepAngle * (base / dt * scale(shift)));
  };
  const double g = glm::length(gravity);
  // the same contact pairs as the last step
  const bool settled = c.pairs_same && c.pairs.size() == c.last_count;
  if (g == 0) {
    c.column_need = 0, c.column_top = 0, c.column_sag_top = 0, c.column_sag_ratio = 0, c.column_known = false;
    c.column_braced = -1, c.brace_due = false;
  } else {
    // measured again when the pairs changed (a body came or went, woke or fell asleep), the
    // bodies or gravity's direction did, and otherwise every kMeasureEvery steps
    const Vec3 up = -gravity / g;
    // (the same bodies and up as the last measure's: no body was made or destroyed since)
    const bool same_bodies = c.column_known && c.column_bodies == type_.size() && c.column_up == up;
    const bool same = same_bodies && settled;
    c.brace_age = std::min(c.brace_age + 1, kMeasureEvery);  // (what it is compared with, never past)
    if (!same || ++c.column_age >= kMeasureEvery) {
      // (the springs and sag of the first rung, the halving's: a lower rung's are scaled from
      // them below; with no rung, those of half the substeps, which go unused)
      const double w = least < 0 ? rate(-1) : 0.5 * rate(0), ws = least < 0 ? static_rate(-1) : 0.5 * static_rate(0);
      c.column_need = c.measure_columns(*this, up, c.column_top, least < 0, w, ws);
      c.column_rate = w, c.column_static_rate = ws, c.column_g = g;
      c.column_bodies = type_.size(), c.column_up = up, c.column_age = 0, c.column_known = true;
      // (before a step has carried loads, as in the first, the springs are not known: the
      // column model judges that measure.) The braced model is owed for it, unless this
      // measure comes of pairs that changed and its face pairs are those of the last braced
      // model's, made fewer than kMeasureEvery steps ago: the pairs changed elsewhere (a body
      // bouncing beside a halved pile), and the braced load is kept as at rest, where it is
      // made again every kMeasureEvery steps (the measures of that cadence always make it)
      const bool kept = !same && same_bodies && c.column_braced >= 0 && c.brace_age < kMeasureEvery && c.brace_faces_same();
      if (!kept) c.column_braced = -1, c.brace_due = least < 0 && c.impulse_h > 0;
    }
    // the braced model of that measure, once the halving can use it: halved (the way back),
    // or with the same pairs as the last step (the calm before halving). While the pairs
    // change the calm starts again every step whatever the load, so a pile still landing (the
    // rain) does not pay for it; made later from the same face pairs, their points now
    if (c.brace_due && (settled || auto_shift_ < 0)) {
      c.column_braced = c.measure_braced(*this, up, g), c.column_braced_g = g, c.brace_due = false;
      c.brace_rate = c.column_rate, c.brace_static_rate = c.column_static_rate, c.brace_age = 0;
    }
  }
  const double need = c.column_need;  // n^3 / s (1/m)
  profile_.column = c.column_top;
  // the load at half the substeps: the braced model's where the pile's levels make a tree,
  // the column model's otherwise. The braced load was made on the springs of its measure's
  // rates and the gravity then (G goes with g, K with the rates squared), so it is scaled to
  // this step's by `softened`: the larger of the dynamic and the static springs' squared
  // ratios, which never lowers it for springs that did not soften alike; exactly 1 at a fixed
  // dt and settings
  const double w_half = least < 0 ? rate(-1) : 0.5 * rate(0),
               ws_half = least < 0 ? static_rate(-1) : 0.5 * static_rate(0);
  auto softened = [&](double w, double ws) {
    return w > 0 && ws > 0 && w_half > 0 && ws_half > 0 ? std::max(w * w / (w_half * w_half), ws * ws / (ws_half * ws_half))
                                                        : 1.0;
  };
  const bool rated = c.brace_rate > 0 && c.brace_static_rate > 0 && w_half > 0 && ws_half > 0;
  const double soften = softened(c.column_rate, c.column_static_rate);
  // and from the first rung's springs to a lower rung's: the load and the sag go as 1 / w^2
  // (K with w^2, G and the loads with g), the larger of the two ratios for springs that do not
  // go alike (both go with the count at the defaults: (4/3)^2 = 1.78 from 4 to 3 substeps);
  // exactly 1 at the first rung, whose bits are the halving's
  auto lowered = [&](int shift) {
    if (shift >= -1) return 1.0;
    const double w = rate(shift), ws = static_rate(shift);
    return std::max(w_half * w_half / (w * w), ws_half * ws_half / (ws * ws));
  };
  auto load = [&](int shift) {
    const double w = rate(shift);
    if (shift < 0 && c.column_braced >= 0 && rated && c.column_braced_g > 0)
      return c.column_braced * (g / c.column_braced_g) * softened(c.brace_rate, c.brace_static_rate) * lowered(shift);
    return need * g / (w * w);
  };
  // the sag predicted likewise (made at the measure's springs, whose loads went with its
  // gravity): each spring gives with its rate squared, so a halved pile whose springs softened
  // since (a longer step, a lowered contact_hertz) is judged on them before the next measure,
  // up to 8 steps on; exactly 1 at a fixed dt and settings
  const double sag_scale = c.column_g > 0 ? g / c.column_g * soften : soften;
  profile_.half_load = least < 0 ? load(-1) : 0;
  // whether the columns fit the substeps at `shift` with `margin` of the bounds: their load
  // n^3 g / (w^2 s), and below the setting's substeps the sag predicted at that rung, within
  // each budget that is set (a fraction of the bodies' sizes, metres); nothing fits under the
  // last rung
  auto fits = [&](int shift, double margin) {
    if (shift < least || load(shift) > margin * kColumnLoad) return false;
    if (shift >= 0) return true;
    const double give = sag_scale * lowered(shift);
    return (budget <= 0 || c.column_sag_top * give <= margin * budget) &&
           (fraction <= 0 || c.column_sag_ratio * give <= margin * fraction);
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
  // raised at once (to the fewest substeps that fit the whole bounds); lowered a step at a
  // time, once the columns have fitted half the bounds at the next count down (a halving above
  // the setting's: each 0.79 of the height that would raise it) for kCalmTime; to each rung
  // below the setting's substeps also only once the pairs have stayed the same and every body
  // has been still that long, so that neither a pile still landing (its contacts' loads not yet
  // those of its rest) nor a body moving on its contacts is lowered: the Jolt pyramid halved
  // while its upper levels landed settled with its top 3.6 cm aside, against 1.0 cm at 8
  // substeps (and halved at rest its top stays where it was), and a column of five cubes halved
  // while it rocked on its edges rocked on with the springs' 82 J more (docs/rigid-bodies.md,
  // "Why rest")
  if (shift >= auto_shift_ || !fits(auto_shift_ - 1, 0.5) || (auto_shift_ <= 0 && (!settled || !still()))) {
    auto_shift_ = std::max(shift, auto_shift_);
    auto_calm_ = 0;
  } else if ((auto_calm_ += dt) >= kCalmTime) {
    --auto_shift_;
    auto_calm_ = 0;
  }
  auto_shift_ = std::clamp(auto_shift_, least, most);  // (the settings may have changed)
  c.hertz_scale = scale(auto_shift_);
  return count(auto_shift_);
}

}  // namespace pba
