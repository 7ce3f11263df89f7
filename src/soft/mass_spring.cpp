// The mass-spring solver: Hooke springs with damping, gravity, drag toward the wind, the
// held aerodynamic accelerations and a velocity-proportional damping force, integrated
// by pba::Integrator<Vec3> with any pba::Method (double precision), then velocity-level
// collisions. The float columns mirror the double state after each step.
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <string_view>

#include "soft_impl.h"

namespace pba {

namespace {

// The accelerations of every particle: gravity on free particles, springs
//   f_b = -(k (l - l0) + c (v_b - v_a) . n) n = -f_a,  n = (x_b - x_a)/l   (Hooke + dashpot)
// drag a = -(b + c_q |u|) u w with u = v - wind, damping a = -damping v, volume forces
//   F_i = -k_v (V - V0) grad_i V, and the held external accelerations.
void accelerations(const SoftBody::Impl& s, double t, std::span<const Vec3> x, std::span<const Vec3> v,
                   std::span<Vec3> a) {
  const SoftBodyDef& d = s.def;
  const Vec3 g = d.forces.gravity;
  const Vec3 wind = d.forces.wind.at(t);
  const double b = d.forces.linear_drag, cq = d.forces.quadratic_drag;
  const bool drag = b > 0 || cq > 0;
  // per-particle forces
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double w = s.w[i];
    if (w == 0) {
      a[i] = Vec3(0, 0, 0);
      continue;
    }
    Vec3 ai = g - d.damping * v[i];
    if (s.has_aext) ai += Vec3(s.ax[i], s.ay[i], s.az[i]);
    if (drag) {
      const Vec3 u = v[i] - wind;
      ai -= (b + cq * glm::length(u)) * w * u;
    }
    a[i] = ai;
  }
  // springs
  const double c = d.spring_damping;
  for (std::size_t k = 0; k < s.ca.size(); ++k) {
    if (s.broken[k]) continue;
    const std::uint32_t ia = s.ca[k], ib = s.cb[k];
    const Vec3 dd = x[ib] - x[ia];
    const double l = glm::length(dd);
    if (!(l > 0)) continue;
    const Vec3 n = dd / l;
    const double kk = detail::kind_stiffness(d, static_cast<SoftConstraintKind>(s.kind[k]));
    const Vec3 fb = -(kk * (l - s.rest0[k]) + c * glm::dot(v[ib] - v[ia], n)) * n;
    a[ib] += double(s.w[ib]) * fb;
    a[ia] -= double(s.w[ia]) * fb;
  }
  // volume forces
  if (d.volume_stiffness > 0) {
    for (std::size_t k = 0; k < s.tets.size(); ++k) {
      const SoftTet& tt = s.tets[k];
      const std::uint32_t id[4] = {tt.a, tt.b, tt.c, tt.d};
      const Vec3 e1 = x[tt.b] - x[tt.a], e2 = x[tt.c] - x[tt.a], e3 = x[tt.d] - x[tt.a];
      Vec3 gr[4];
      gr[1] = glm::cross(e2, e3) / 6.0;
      gr[2] = glm::cross(e3, e1) / 6.0;
      gr[3] = glm::cross(e1, e2) / 6.0;
      gr[0] = -(gr[1] + gr[2] + gr[3]);
      const double C = glm::dot(e3, gr[3]) - s.tet_rest[k];
      for (int j = 0; j < 4; ++j) a[id[j]] -= d.volume_stiffness * C * double(s.w[id[j]]) * gr[j];
    }
  }
}

// The analytic Jacobian for implicit Euler (springs, drag, damping; volume forces use the
// integrator's finite differences instead). With K = df_b/dd (d = x_b - x_a, P = I - n n^T,
// s = k (l - l0) + c v_rel . n):  K = -(k n n^T + (c/l) n v_rel^T P + (s/l) P), and
// df_b/dv_b = -c n n^T; the blocks for a are the negatives (Baraff & Witkin 1998, sec. 4.5).
void jacobian(const SoftBody::Impl& s, double t, std::span<const Vec3> x, std::span<const Vec3> v,
              std::span<double> dadx, std::span<double> dadv) {
  const SoftBodyDef& d = s.def;
  const std::size_t N = x.size() * 3;
  auto add = [N](std::span<double> m, std::size_t r, std::size_t cc, const Mat3& blk, double scale) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[(r * 3 + i) * N + cc * 3 + j] += scale * blk[j][i];  // glm: [column][row]
  };
  // drag and damping (diagonal blocks)
  const Vec3 wind = d.forces.wind.at(t);
  const double b = d.forces.linear_drag, cq = d.forces.quadratic_drag;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double w = s.w[i];
    if (w == 0) continue;
    Mat3 m(-d.damping);
    const Vec3 u = v[i] - wind;
    const double su = glm::length(u);
    m += Mat3(-(b + cq * su) * w);
    if (cq > 0 && su > 0) m -= (cq * w / su) * glm::outerProduct(u, u);
    add(dadv, i, i, m, 1.0);
  }
  // springs
  const double c = d.spring_damping;
  for (std::size_t k = 0; k < s.ca.size(); ++k) {
    if (s.broken[k]) continue;
    const std::uint32_t ia = s.ca[k], ib = s.cb[k];
    const Vec3 dd = x[ib] - x[ia];
    const double l = glm::length(dd);
    if (!(l > 0)) continue;
    const Vec3 n = dd / l, vr = v[ib] - v[ia];
    const Mat3 P = Mat3(1.0) - glm::outerProduct(n, n);
    const double kk = detail::kind_stiffness(d, static_cast<SoftConstraintKind>(s.kind[k]));
    const double sf = kk * (l - s.rest0[k]) + c * glm::dot(vr, n);
    const Mat3 K = -(kk * glm::outerProduct(n, n) + (c / l) * glm::outerProduct(n, P * vr) + (sf / l) * P);
    const Mat3 D = -c * glm::outerProduct(n, n);
    const double wa = s.w[ia], wb = s.w[ib];
    add(dadx, ib, ib, K, wb), add(dadx, ib, ia, K, -wb), add(dadx, ia, ib, K, -wa), add(dadx, ia, ia, K, wa);
    add(dadv, ib, ib, D, wb), add(dadv, ib, ia, D, -wb), add(dadv, ia, ib, D, -wa), add(dadv, ia, ia, D, wa);
  }
}

}  // namespace

// One damped spring's amplification under each explicit method: the kernels of
// include/pba/integrate.h on x'' = -omega^2 x - (z / h) x', written in x and u = h v (and,
// for position Verlet, its history D = x_n - x_{n-1} and cached A = a_n h^2) so that p =
// (omega h)^2 and z are all that is left. Applying the step to each unit state gives the
// matrix's columns; ||M^(2^j)||^(1/2^j) then gives its spectral radius.
double detail::mass_spring_radius(Method m, double p, double z) {
  if (m == Method::ImplicitEuler) return 0;
  if (!(std::isfinite(p) && std::isfinite(z))) return std::numeric_limits<double>::infinity();
  using State = std::array<double, 3>;
  const auto acc = [p, z](double x, double u) { return -p * x - z * u; };  // a h^2
  const auto step = [&](State s) -> State {
    const double x = s[0], u = s[1];
    switch (m) {
      case Method::ExplicitEuler: return {x + u, u + acc(x, u), 0};
      case Method::SemiImplicitEuler: {
        const double un = u + acc(x, u);
        return {x + un, un, 0};
      }
      case Method::PositionVerlet: {  // s = (x_n, D_n, A_n); the predictor D_{n+1} + A_n / 2
        const double xn = x + u + s[2], dn = u + s[2];
        return {xn, dn, acc(xn, dn + s[2] / 2)};
      }
      case Method::VelocityVerlet: {
        const double a0 = acc(x, u), xn = x + u + a0 / 2, a1 = acc(xn, u + a0);
        return {xn, u + (a0 + a1) / 2, 0};
      }
      default: {  // RK4: the four stages as the kernel takes them
        const double a1 = acc(x, u), x2 = x + u / 2, u2 = u + a1 / 2, a2 = acc(x2, u2);
        const double x3 = x + u2 / 2, u3 = u + a2 / 2, a3 = acc(x3, u3);
        const double x4 = x + u3, u4 = u + a3, a4 = acc(x4, u4);
        return {x + (u + 2 * u2 + 2 * u3 + u4) / 6, u + (a1 + 2 * a2 + 2 * a3 + a4) / 6, 0};
      }
    }
  };
  double M[3][3];
  for (int c = 0; c < 3; ++c) {
    State e{0, 0, 0};
    e[c] = 1;
    const State col = step(e);
    for (int r = 0; r < 3; ++r) M[r][c] = col[r];
  }
  // repeated squaring with the norm taken out each time: log ||M^(2^j)|| / 2^j
  double logr = 0, scale = 1;
  for (int j = 0; j < 48; ++j) {
    double norm = 0;
    for (auto& row : M)
      for (double e : row) norm = std::isfinite(e) ? std::max(norm, std::abs(e)) : std::abs(e) + e;  // nan stays
    if (!std::isfinite(norm)) return std::numeric_limits<double>::infinity();  // a huge p or z overflowed
    if (norm == 0) return 0;
    logr += std::log(norm) * scale;
    double S[3][3] = {};
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) S[r][c] += (M[r][k] / norm) * (M[k][c] / norm);
    std::copy(&S[0][0], &S[0][0] + 9, &M[0][0]);
    scale /= 2;
  }
  return std::exp(logr);
}

namespace {

// The stiffest elements the diagnoses look at: the largest w_a + w_b among the intact
// springs of each kind, the lightest free particle's w and the largest sum of w |grad V|^2
// over a tetrahedron's corners in the rest shape (the volume force -k_v (V - V0) grad V is
// then a spring of (omega h)^2 = k_v sum w |grad V|^2 h^2: the one non-zero eigenvalue of
// M^-1 k_v g g^T). The failure path only.
struct Stiffest {
  double spring_w[3] = {0, 0, 0};  // 1/kg
  double particle_w = 0;           // 1/kg
  double tet_g = 0;                // m^4/kg
};
Stiffest stiffest(const SoftBody::Impl& s) {
  Stiffest st;
  for (std::size_t k = 0; k < s.ca.size(); ++k)
    if (!s.broken[k])
      st.spring_w[s.kind[k]] = std::max(st.spring_w[s.kind[k]], double(s.w[s.ca[k]]) + double(s.w[s.cb[k]]));
  for (std::size_t i = 0; i < s.n; ++i) st.particle_w = std::max(st.particle_w, double(s.w[i]));
  for (const SoftTet& t : s.tets) {
    const std::uint32_t id[4] = {t.a, t.b, t.c, t.d};
    Vec3 p[4];
    for (int j = 0; j < 4; ++j) p[j] = Vec3(s.rx[id[j]], s.ry[id[j]], s.rz[id[j]]);
    const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0], e3 = p[3] - p[0];
    Vec3 g[4];
    g[1] = glm::cross(e2, e3) / 6.0, g[2] = glm::cross(e3, e1) / 6.0, g[3] = glm::cross(e1, e2) / 6.0;
    g[0] = -(g[1] + g[2] + g[3]);
    double sum = 0;
    for (int j = 0; j < 4; ++j) sum += double(s.w[id[j]]) * glm::dot(g[j], g[j]);
    st.tet_g = std::max(st.tet_g, sum);
  }
  return st;
}

// The per-particle dampers: the damping rate d (a = -d v), linear drag b w and quadratic
// drag c |u| w (a = -(b + c |u|) w u, u relative to the wind) on the lightest free
// particle, each x'' = -(z / h) x' with z = rate h; quadratic drag's rate at the fastest
// particle's air speed at the step's start (the last state check_finite passed) plus
// gravity's g h over one substep (a body at rest in still air takes that much before its
// drag acts) plus, with colliders, thickness / h: a contact moves a particle out and takes
// only its velocity into the surface (collide_velocities), so the push itself gives no
// speed, but a thick curved collider pushes neighbours out by different amounts, up to the
// thickness apart, and the springs pull them back at speeds of that order (a 4 x 4 cloth on
// a 0.3 m sphere at h = 1/600 s, no drag: 1.6e5 m/s at 1e3 m of thickness, 0.27 thickness
// / h; with c = 1e-3 kg/m and 1e6 m it blew up at step 1 naming nothing). The failure path
// only: it builds strings.
struct Rate {
  const char* field;  // in SoftBodyDef
  double value;
  const char* unit;
  std::string what;
  double rate;  // 1/s
};
constexpr int kQuadraticDrag = 2;  // its index in particle_rates
std::array<Rate, 3> particle_rates(const SoftBody::Impl& s, double wfree, double h) {
  const SoftBodyDef& d = s.def;
  const double push = s.colliders.empty() ? 0.0 : d.thickness / h;
  const double speed = s.ms_air_speed + glm::length(d.forces.gravity) * h + push;
  return {Rate{"damping", d.damping, "1/s", "its rate d", d.damping},
          Rate{"forces.linear_drag", d.forces.linear_drag, "kg/s", "its lightest particle's rate b w",
               d.forces.linear_drag * wfree},
          Rate{"forces.quadratic_drag", d.forces.quadratic_drag, "kg/m",
               "its lightest particle's rate c |u| w (|u| = the fastest air speed at the step's start + g h" +
                   std::string(push > 0 ? " + thickness / h (springs a thick collider stretched pulling back)" : "") + " = " + format_value(speed) +
                   " m/s)",
               d.forces.quadratic_drag * speed * wfree}};
}

}  // namespace

// Why an explicit integrator blew up, in the settings' terms: for each kind's stiffest
// spring (the largest w_a + w_b) the method's amplification of the spring and its damper
// together (detail::mass_spring_radius; docs/soft-bodies.md, "Why stiff springs are hard"),
// then the dampers on single particles (damping and drag, on the lightest particle) and
// the stiffest tetrahedron's volume force, and quadratic drag when none of these is named.
// Above 1 the settings are named: the stiffness, the damping, or both when neither alone
// is past the bound. A network's fastest mode is
// faster than its stiffest spring, so an empty answer does not make it stable. The
// failure path only: it builds strings.
std::string SoftBody::Impl::mass_spring_instability(double h) const {
  if (def.solver != SoftSolver::MassSpring || def.method == Method::ImplicitEuler) return {};
  constexpr double kGrows = 1 + 1e-9;  // round-off in a radius of exactly 1
  const Stiffest st = stiffest(*this);
  const double* wmax = st.spring_w;
  std::string why;
  const char* names[3] = {"stretch_stiffness", "shear_stiffness", "bend_stiffness"};
  const double c = def.spring_damping;
  for (int k = 0; k < 3; ++k) {
    const double stiff = detail::kind_stiffness(def, static_cast<SoftConstraintKind>(k));
    const double wh = std::sqrt(stiff * wmax[k]) * h, z = c * wmax[k] * h;
    if (!(wmax[k] > 0 && (stiff > 0 || c > 0))) continue;
    const double r = detail::mass_spring_radius(def.method, wh * wh, z);
    if (!(r > kGrows)) continue;
    // the spring alone or the damper alone past the bound names that one; else both
    const bool spring = detail::mass_spring_radius(def.method, wh * wh, 0) > kGrows;
    const bool damper = detail::mass_spring_radius(def.method, 0, z) > kGrows;
    const bool say_k = stiff > 0 && (spring || !damper), say_c = c > 0 && (damper || !spring);
    why += std::string(why.empty() ? "" : "; ");
    if (say_k) why += "SoftBodyDef." + std::string(names[k]) + " = " + format_value(stiff) + " N/m";
    if (say_k && say_c) why += " with ";
    if (say_c) why += "SoftBodyDef.spring_damping = " + format_value(c) + " N s/m";
    why += std::string(say_k && say_c ? " give" : " gives") + " its stiffest spring omega h = sqrt(k (w_a + w_b)) h = " +
           format_value(wh) + " and c (w_a + w_b) h = " + format_value(z) + ": an amplification of " + format_value(r) +
           " per substep, past " + std::string(name(def.method)) + "'s stability bound 1";
  }
  // the per-particle dampers, together and each alone; quadratic drag only when nothing
  // else is named: its rate follows the air speed, which a blow-up of anything grows (a
  // cloth of springs past their bound reached 1e30 m/s over a few steps, and a quadratic
  // drag of 1e-9 kg/m then read as a rate of 6e22 /s)
  const auto dampers = [&](bool quadratic) {
    if (!(st.particle_w > 0)) return;
    std::array<Rate, 3> rates = particle_rates(*this, st.particle_w, h);
    if (!quadratic) rates[kQuadraticDrag].rate = 0, rates[kQuadraticDrag].value = 0;
    double total = 0;
    for (const Rate& r : rates) total += r.rate;
    const double r_all = total > 0 ? detail::mass_spring_radius(def.method, 0, total * h) : 0;
    if (!(r_all > kGrows)) return;
    // each one past the bound alone, or all of them when none is
    bool alone[3], any = false;
    for (int k = 0; k < 3; ++k) {
      alone[k] = detail::mass_spring_radius(def.method, 0, rates[k].rate * h) > kGrows;
      any = any || alone[k];
    }
    std::string list;
    int named = 0;
    for (int k = 0; k < 3; ++k) {
      if (!(rates[k].value > 0) || (any && !alone[k])) continue;
      list += std::string(list.empty() ? "" : " with ") + "SoftBodyDef." + rates[k].field + " = " +
              format_value(rates[k].value) + " " + rates[k].unit + " (" + rates[k].what + " = " +
              format_value(rates[k].rate) + " /s)";
      ++named;
    }
    why += std::string(why.empty() ? "" : "; ") + list + (named > 1 ? " damp" : " damps") +
           " the velocity at z = rate h = " + format_value(total * h) + ": an amplification of " + format_value(r_all) +
           " per substep, past " + std::string(name(def.method)) + "'s stability bound 1";
  };
  dampers(false);
  // the volume force of the stiffest tetrahedron
  if (def.volume_stiffness > 0 && st.tet_g > 0) {
    const double gmax = st.tet_g;
    const double wh = std::sqrt(def.volume_stiffness * gmax) * h;
    if (const double r = detail::mass_spring_radius(def.method, wh * wh, 0); r > kGrows)
      why += std::string(why.empty() ? "" : "; ") + "SoftBodyDef.volume_stiffness = " +
             format_value(def.volume_stiffness) + " N/m^5 gives its stiffest tetrahedron omega h = sqrt(k_v sum w "
             "|grad V|^2) h = " + format_value(wh) + ": an amplification of " + format_value(r) +
             " per substep, past " + std::string(name(def.method)) + "'s stability bound 1";
  }
  if (why.empty() && def.forces.quadratic_drag > 0) dampers(true);
  if (why.empty()) return why;
  return why + " at the substep h = " + format_value(h) +
         " s: use more substeps, softer springs, less damping or drag, implicit Euler or the XPBD solver";
}

// Why implicit Euler's Newton solve failed, in the settings' terms. Its system J = I - h
// (h da/dx + da/dv) holds, beside the identity, (omega h)^2 = k (w_a + w_b) h^2 and z = c
// (w_a + w_b) h for the stiffest spring of each kind, z = rate h for the per-particle
// dampers and k_v sum w |grad V|^2 h^2 for the stiffest tetrahedron. Implicit Euler is
// stable at any of them, but the solve is not exact: its rounding grows with them. At h =
// 1/600 s, stiffness in half decades, Newton still met its tolerance at (omega h)^2 =
// 1.6e10 and no longer at 5e10 on an 8-segment rope (on a 6 x 6 cloth 6.3e10 and 2e11),
// and the system was singular from k = 1e88 N/m, (omega h)^2 = 5e83. Each term above
// kNewtonTrouble = 1e8, over two decades below that onset, is named with its size (a
// term under it is not what failed), or "" when none is.
std::string SoftBody::Impl::newton_failure_why(double h) const {
  constexpr double kNewtonTrouble = 1e8;
  const Stiffest st = stiffest(*this);
  std::string why;
  const auto add = [&](const std::string& field, double value, const char* unit, const std::string& what, double q) {
    if (!(value > 0) || q <= kNewtonTrouble) return;  // (nan and inf are past it)
    why += std::string(why.empty() ? "" : "; ") + "SoftBodyDef." + field + " = " + format_value(value) + " " + unit +
           " gives " + what + " = " + format_value(q);
  };
  const char* names[3] = {"stretch_stiffness", "shear_stiffness", "bend_stiffness"};
  double wspring = 0;
  for (int k = 0; k < 3; ++k) {
    const double stiff = detail::kind_stiffness(def, static_cast<SoftConstraintKind>(k));
    add(names[k], stiff, "N/m", "its stiffest spring (omega h)^2 = k (w_a + w_b) h^2", stiff * st.spring_w[k] * h * h);
    wspring = std::max(wspring, st.spring_w[k]);
  }
  add("spring_damping", def.spring_damping, "N s/m", "its stiffest spring c (w_a + w_b) h",
      def.spring_damping * wspring * h);
  for (const Rate& r : particle_rates(*this, st.particle_w, h))
    add(r.field, r.value, r.unit, std::string(r.what) + " times h", r.rate * h);
  if (!tets.empty())
    add("volume_stiffness", def.volume_stiffness, "N/m^5",
        "its stiffest tetrahedron (omega h)^2 = k_v sum w |grad V|^2 h^2", def.volume_stiffness * st.tet_g * h * h);
  if (why.empty()) return why;
  return "the Newton system I - h (h da/dx + da/dv) at the substep h = " + format_value(h) +
         " s holds, beside the identity, " + why + " (its rounding grows with them): use softer springs, less "
         "damping or drag, more substeps, or the XPBD solver (whose compliance 0 is a rigid constraint)";
}

void SoftBody::Impl::step_mass_spring(double t, double dt) {
  // implicit Euler's dense solve has a size limit: say so in SoftBody's terms
  if (def.method == Method::ImplicitEuler && n * 3 > integ.newton().max_unknowns)
    throw Error("SoftBodyDef.method: implicit Euler is a dense Newton solve limited to " +
                std::to_string(integ.newton().max_unknowns / 3) + " particles (" +
                std::to_string(integ.newton().max_unknowns) + " unknowns), this body has " + std::to_string(n));
  // method changes and the analytic jacobian (none with volume forces: finite differences)
  if (integ.method() != def.method) integ.set_method(def.method);
  if (def.method == Method::ImplicitEuler) {
    const bool analytic = !(def.volume_stiffness > 0 && !tets.empty());
    if (analytic != static_cast<bool>(jacobian_set)) {
      if (analytic)
        integ.set_jacobian([this](double tt, std::span<const Vec3> xs, std::span<const Vec3> vs, std::span<double> dx,
                                  std::span<double> dv) { jacobian(*this, tt, xs, vs, dx, dv); });
      else
        integ.set_jacobian({});
      jacobian_set = analytic;
    }
  }
  // the double state mirrors the floats unless they were written since the last step
  if (!ms_valid) {
    msx.resize(n), msv.resize(n);
    for (std::size_t i = 0; i < n; ++i) msx[i] = Vec3(x[i], y[i], z[i]), msv[i] = Vec3(vx[i], vy[i], vz[i]);
    integ.reset_history();
    ms_valid = true;
  }
  // quadratic drag's rate depends on the air speed: the fastest free particle's, for the
  // blow-up diagnosis (one pass, with quadratic drag only)
  ms_air_speed = 0;
  if (def.forces.quadratic_drag > 0) {
    const Vec3 wind = def.forces.wind.at(t);
    for (std::size_t i = 0; i < n; ++i)
      if (w[i] > 0) ms_air_speed = std::max(ms_air_speed, glm::length(msv[i] - wind));
  }
  const int S = def.substeps;
  const double h = dt / S;
  auto accel = [this](double tt, std::span<const Vec3> xs, std::span<const Vec3> vs, std::span<Vec3> as) {
    accelerations(*this, tt, xs, vs, as);
  };
  double collide_s = 0;
  for (int sub = 1; sub <= S; ++sub) {
    // integrate, then pins slide to their targets at the pin velocity; a failed Newton
    // solve names the settings that put it past double precision, and the next step
    // starts again from the float columns (this step's earlier substeps are not kept)
    try {
      integ.step(t + (sub - 1) * h, h, std::span<Vec3>(msx), std::span<Vec3>(msv), accel);
    } catch (const NewtonFailure& e) {
      // (without the integrator's advice to raise NewtonSettings.max_iterations, which a
      // soft body does not have)
      ms_valid = false;
      std::string what = e.what();
      constexpr std::string_view kIterations = "; reduce dt or raise NewtonSettings.max_iterations";
      if (what.ends_with(kIterations)) what.resize(what.size() - kIterations.size());
      const std::string why = newton_failure_why(h);
      throw NewtonFailure(what + (why.empty() ? "" : "; " + why));
    }
    const double f = static_cast<double>(sub) / S;
    for (std::size_t k = 0; k < pins.size(); ++k) {
      msx[pins[k]] = sub == S ? pin_to[k] : pin_from[k] + (pin_to[k] - pin_from[k]) * f;
      msv[pins[k]] = (pin_to[k] - pin_from[k]) / dt;
    }
    // collisions (position Verlet restarts its history from the corrected state)
    if (!colliders.empty()) {
      Stopwatch sw;
      if (detail::collide_velocities(*this, msx, msv, f) > 0 && def.method == Method::PositionVerlet)
        integ.reset_history();
      collide_s += sw.seconds();
    }
  }
  profile.collide = collide_s;
  // mirror into the float columns
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = static_cast<float>(msx[i].x), y[i] = static_cast<float>(msx[i].y), z[i] = static_cast<float>(msx[i].z);
    vx[i] = static_cast<float>(msv[i].x), vy[i] = static_cast<float>(msv[i].y), vz[i] = static_cast<float>(msv[i].z);
  }
  px = x;  // same sizes: copies without allocating
  py = y;
  pz = z;
}

}  // namespace pba
