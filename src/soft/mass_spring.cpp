// The mass-spring solver: Hooke springs with damping, gravity, drag toward the wind, the
// held aerodynamic accelerations and a velocity-proportional damping force, integrated
// by pba::Integrator<Vec3> with any pba::Method (double precision), then velocity-level
// collisions. The float columns mirror the double state after each step.
#include <cmath>

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

// Why an explicit integrator blew up, in the settings' terms: every stiffness and the
// damping whose stiffest single spring is already past the method's stability bound at
// the substep h (docs/soft-bodies.md, "Why stiff springs are hard": omega h < 2 for
// semi-implicit Euler and both Verlets, 2 sqrt 2 for RK4 on the imaginary axis; a dashpot
// alone, c W h < 2, and 2.78 for RK4 on the real axis; explicit Euler grows every swing).
// A network's fastest mode is faster than its stiffest spring, so an empty answer does not
// make it stable. The failure path only: it builds strings.
std::string SoftBody::Impl::mass_spring_instability(double h) const {
  if (def.solver != SoftSolver::MassSpring || def.method == Method::ImplicitEuler) return {};
  const bool rk4 = def.method == Method::Rk4;
  const double osc = rk4 ? 2 * std::sqrt(2.0) : 2, damp = rk4 ? 2.785 : 2;
  // the largest w_a + w_b among the intact springs of each kind
  double wmax[3] = {0, 0, 0}, wall = 0;
  for (std::size_t k = 0; k < ca.size(); ++k) {
    if (broken[k]) continue;
    const double wsum = double(w[ca[k]]) + double(w[cb[k]]);
    wmax[kind[k]] = std::max(wmax[kind[k]], wsum);
    wall = std::max(wall, wsum);
  }
  std::string why;
  const char* names[3] = {"stretch_stiffness", "shear_stiffness", "bend_stiffness"};
  for (int k = 0; k < 3; ++k) {
    const double stiff = detail::kind_stiffness(def, static_cast<SoftConstraintKind>(k));
    const double wh = std::sqrt(stiff * wmax[k]) * h;
    if (!(stiff > 0 && wmax[k] > 0)) continue;
    if (def.method == Method::ExplicitEuler || !(wh < osc))
      why += std::string(why.empty() ? "" : "; ") + "SoftBodyDef." + names[k] + " = " + format_value(stiff) +
             " N/m gives its stiffest spring omega h = sqrt(k (w_a + w_b)) h = " + format_value(wh) +
             (def.method == Method::ExplicitEuler ? " (explicit Euler is unstable at any omega h > 0)"
                                                  : ", past " + std::string(name(def.method)) +
                                                        "'s stability bound " + format_value(osc));
  }
  if (const double cwh = def.spring_damping * wall * h; !(cwh < damp) && wall > 0 && def.spring_damping > 0)
    why += std::string(why.empty() ? "" : "; ") + "SoftBodyDef.spring_damping = " + format_value(def.spring_damping) +
           " N s/m gives c (w_a + w_b) h = " + format_value(cwh) + ", past the explicit dashpot's stability bound " +
           format_value(damp);
  if (why.empty()) return why;
  return why + " at the substep h = " + format_value(h) +
         " s: use more substeps, softer springs, implicit Euler or the XPBD solver";
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
  const int S = def.substeps;
  const double h = dt / S;
  auto accel = [this](double tt, std::span<const Vec3> xs, std::span<const Vec3> vs, std::span<Vec3> as) {
    accelerations(*this, tt, xs, vs, as);
  };
  double collide_s = 0;
  for (int sub = 1; sub <= S; ++sub) {
    // integrate, then pins slide to their targets at the pin velocity
    integ.step(t + (sub - 1) * h, h, std::span<Vec3>(msx), std::span<Vec3>(msv), accel);
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
