// Rigid bodies: the contact solver passes shared by the soft-step, sequential-impulse and TGS
// solvers (src/rigid/tgs.cpp; XPBD has its own passes, src/rigid/xpbd_rigid.cpp). The pairs
// and their manifolds come from contact_pairs.cpp.
//
// The soft step follows Catto's Solver2D / Box2D v3 (contact_solver.c) in 3D: per substep
// the bodies' velocities are integrated, the carried impulses applied, the contacts solved
// as soft constraints (implicit springs of contact_hertz, pushing out no faster than
// push_out_speed), the positions integrated, and the contacts solved again without
// position bias (the relax pass) so no push-out velocity survives into the next substep.
// Restitution is one pass after the substeps. Sequential impulses (Catto 2005; Bullet and
// Jolt's baseline) are the same passes at one substep, with rigid constraints and a
// Baumgarte bias, iterated.
#include "contacts.h"

#include <algorithm>
#include <cmath>

namespace pba::detail {

Softness make_soft(double hertz, double zeta, double h) {
  if (hertz == 0) return {0, 1, 0};
  const double omega = 2 * kPi * hertz;
  const double a1 = 2 * zeta + h * omega, a2 = h * omega * a1, a3 = 1 / (1 + a2);
  return {omega / a1, a2 * a3, a3};
}

// ---------------------------------------------------------------------------------------
// solver passes

void RigidContacts::prepare(RigidBodySystem& s) {
  const std::size_t n = s.type_.size();
  inv_inertia.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Mat3 r = glm::mat3_cast(s.q_[i]);
    Mat3 d(0.0);
    d[0][0] = s.inv_inertia_[i].x, d[1][1] = s.inv_inertia_[i].y, d[2][2] = s.inv_inertia_[i].z;
    // a sleeping body holds still like a static one until something wakes it
    inv_inertia[i] = s.asleep_[i] ? Mat3(0.0) : r * d * glm::transpose(r);
  }
  for (ContactPair& c : pairs) {
    const double ma = s.asleep_[c.a] ? 0 : s.inv_mass_[c.a], mb = s.asleep_[c.b] ? 0 : s.inv_mass_[c.b];
    const Mat3& ia = inv_inertia[c.a];
    const Mat3& ib = inv_inertia[c.b];
    for (int k = 0; k < c.count; ++k) {
      SolverPoint& p = c.points[k];
      p.normal_mass = effective_mass(ma, mb, ia, ib, p.ra, p.rb, c.normal);
      p.rna = glm::cross(p.ra, c.normal), p.rnb = glm::cross(p.rb, c.normal);
      p.ina = ia * p.rna, p.inb = ib * p.rnb;
      const Vec3 dv = s.v_[c.b] + glm::cross(s.w_[c.b], p.rb) - s.v_[c.a] - glm::cross(s.w_[c.a], p.ra);
      p.approach = glm::dot(dv, c.normal);
      p.max_normal_impulse = 0;
    }
    c.tangent_mass[0] = effective_mass(ma, mb, ia, ib, c.ca, c.cb, c.t1);
    c.tangent_mass[1] = effective_mass(ma, mb, ia, ib, c.ca, c.cb, c.t2);
    const double kt = glm::dot(c.normal, (ia + ib) * c.normal);
    c.twist_mass = kt > 0 ? 1 / kt : 0;
    // rolling resistance acts on the relative angular velocity
    if (c.rolling > 0) {
      const Mat3 k = ia + ib;
      c.rolling_mass = glm::determinant(k) > 0 ? glm::inverse(k) : Mat3(0.0);
    }
  }
}

void RigidContacts::warm_start(RigidBodySystem& s) {
  for (ContactPair& c : pairs) {
    auto a = view(s, c.a), b = view(s, c.b);
    // the normal impulses through their precomputed angular parts (as solve() applies them)
    for (int k = 0; k < c.count; ++k) {
      const SolverPoint& p = c.points[k];
      const double j = p.normal_impulse;
      *a.v -= (a.inv_mass * j) * c.normal;
      *a.w -= j * p.ina;
      *b.v += (b.inv_mass * j) * c.normal;
      *b.w += j * p.inb;
    }
    apply(a, b, inv_inertia[c.a], inv_inertia[c.b], c.ca, c.cb, c.tangent_impulse[0] * c.t1 + c.tangent_impulse[1] * c.t2);
    const Vec3 spin = c.rolling_impulse + c.twist_impulse * c.normal;
    *a.w -= inv_inertia[c.a] * spin;
    *b.w += inv_inertia[c.b] * spin;
  }
}

void RigidContacts::solve(RigidBodySystem& s, double h, bool bias, bool soft) {
  const ContactSettings& cs = s.settings_;
  // stiffness at most a quarter of the substep rate (stiffer contacts rock a stack: measured
  // with 120 Hz at 240 Hz substeps); a contact with a body that cannot move gets twice the
  // stiffness within the same limit (Box2D's static softness)
  const double hertz = std::min(cs.contact_hertz, 0.25 / h);
  const Softness dynamic_soft = make_soft(hertz, cs.damping_ratio, h);
  const Softness static_soft = make_soft(std::min(2 * hertz, 0.25 / h), cs.damping_ratio, h);
  for (ContactPair& c : pairs) {
    auto a = view(s, c.a), b = view(s, c.b);
    const Mat3& ia = inv_inertia[c.a];
    const Mat3& ib = inv_inertia[c.b];
    const Softness& sft = (a.inv_mass == 0 || b.inv_mass == 0) ? static_soft : dynamic_soft;
    // how far each body has moved and turned since the start of the step
    const Quat turn_a = *a.q * glm::conjugate(s.q0_[c.a]);
    const Quat turn_b = *b.q * glm::conjugate(s.q0_[c.b]);
    double total_normal = 0;
    // non-penetration, swept over the manifold's points `manifold_iterations` times: Gauss-
    // Seidel on the manifold's small problem, toward the block solution (one sweep leaves a
    // torque imbalance between the points that rocks tall stacks)
    // the separations: positions do not move within a pass
    double separation[Manifold::kMaxPoints];
    for (int k = 0; k < c.count; ++k) {
      const SolverPoint& p = c.points[k];
      separation[k] = glm::dot((*b.com + turn_b * p.sb) - (*a.com + turn_a * p.sa), c.normal) + p.offset;
    }
    for (int it = 0; it < cs.manifold_iterations; ++it) {
    total_normal = 0;
    for (int k = 0; k < c.count; ++k) {
      SolverPoint& p = c.points[k];
      const double sep = separation[k];
      double velocity_bias = 0, mass_scale = 1, impulse_scale = 0;
      if (sep > 0) {
        // speculative: close the gap in this substep, no more. The relax pass leaves such
        // points alone: the next substep's biased pass stops the approach before positions
        // move, and a body slowed here would reach the contact slower than it falls, which
        // the restitution pass would then bounce too weakly
        if (!bias) {
          total_normal += p.normal_impulse;
          continue;
        }
        velocity_bias = sep / h;
      } else if (bias) {
        if (soft) {
          velocity_bias = std::max(sft.bias_rate * sep, -cs.push_out_speed);
          mass_scale = sft.mass_scale;
          impulse_scale = sft.impulse_scale;
        } else {
          velocity_bias = std::max(cs.baumgarte / h * std::min(0.0, sep + cs.linear_slop), -cs.push_out_speed);
        }
      }
      // normal relative velocity: (vb + wb x rb - va - wa x ra) . n, with (w x r) . n = w . (r x n)
      const double vn = glm::dot(*b.v - *a.v, c.normal) + glm::dot(*b.w, p.rnb) - glm::dot(*a.w, p.rna);
      // the fastest approach seen, gravity of the substeps before the impact included
      if (bias) p.approach = std::min(p.approach, vn);
      double impulse = -p.normal_mass * mass_scale * (vn + velocity_bias) - impulse_scale * p.normal_impulse;
      const double total = std::max(p.normal_impulse + impulse, 0.0);
      impulse = total - p.normal_impulse;
      p.normal_impulse = total;
      p.max_normal_impulse = std::max(p.max_normal_impulse, impulse);
      total_normal += total;
      *a.v -= (a.inv_mass * impulse) * c.normal;
      *a.w -= impulse * p.ina;
      *b.v += (b.inv_mass * impulse) * c.normal;
      *b.w += impulse * p.inb;
    }
    }
    // Coulomb friction at the centroid: the tangential impulse stays inside the disc of
    // radius mu * (total normal impulse)
    {
      const Vec3 dv = *b.v + glm::cross(*b.w, c.cb) - *a.v - glm::cross(*a.w, c.ca);
      const double old0 = c.tangent_impulse[0], old1 = c.tangent_impulse[1];
      double t0 = old0 - c.tangent_mass[0] * glm::dot(dv, c.t1);
      double t1 = old1 - c.tangent_mass[1] * glm::dot(dv, c.t2);
      const double limit = c.friction * total_normal, len = std::sqrt(t0 * t0 + t1 * t1);
      if (len > limit) {
        const double scale = len > 0 ? limit / len : 0;
        t0 *= scale, t1 *= scale;
      }
      c.tangent_impulse[0] = t0, c.tangent_impulse[1] = t1;
      apply(a, b, ia, ib, c.ca, c.cb, (t0 - old0) * c.t1 + (t1 - old1) * c.t2);
    }
    // twist friction about the normal, up to mu * total normal * mean lever arm
    if (c.twist_radius > 0) {
      const double old = c.twist_impulse, limit = c.friction * total_normal * c.twist_radius;
      const double j = std::clamp(old - c.twist_mass * glm::dot(*b.w - *a.w, c.normal), -limit, limit);
      c.twist_impulse = j;
      *a.w -= ia * ((j - old) * c.normal);
      *b.w += ib * ((j - old) * c.normal);
    }
    // rolling resistance: an angular impulse against the relative spin, up to rolling * normal
    if (c.rolling > 0) {
      const Vec3 old = c.rolling_impulse;
      Vec3 j = old - c.rolling_mass * (*b.w - *a.w);
      const double limit = c.rolling * total_normal, len = glm::length(j);
      if (len > limit) j *= limit / len;
      c.rolling_impulse = j;
      *a.w -= ia * (j - old);
      *b.w += ib * (j - old);
    }
  }
}

void RigidContacts::restitution(RigidBodySystem& s) {
  const double threshold = s.settings_.restitution_threshold;
  for (ContactPair& c : pairs) {
    if (c.restitution == 0) continue;
    auto a = view(s, c.a), b = view(s, c.b);
    for (int k = 0; k < c.count; ++k) {
      SolverPoint& p = c.points[k];
      // only points that approached fast enough and actually pushed
      if (p.approach > -threshold || p.max_normal_impulse == 0) continue;
      const Vec3 dv = *b.v + glm::cross(*b.w, p.rb) - *a.v - glm::cross(*a.w, p.ra);
      const double vn = glm::dot(dv, c.normal);
      double impulse = -p.normal_mass * (vn + c.restitution * p.approach);
      const double total = std::max(p.normal_impulse + impulse, 0.0);
      impulse = total - p.normal_impulse;
      p.normal_impulse = total;
      apply(a, b, inv_inertia[c.a], inv_inertia[c.b], p.ra, p.rb, impulse * c.normal);
    }
  }
}

void RigidContacts::carry_impulses(double h) {
  // an impulse per step of impulse_h is a force times impulse_h: the same force over h
  if (impulse_h > 0 && impulse_h != h) {
    const double k = h / impulse_h;
    for (ContactPair& c : pairs) {
      for (int j = 0; j < c.count; ++j) c.points[j].normal_impulse *= k;
      c.tangent_impulse[0] *= k, c.tangent_impulse[1] *= k;
      c.twist_impulse *= k;
      c.rolling_impulse *= k;
    }
  }
  impulse_h = h;
}

void RigidContacts::store() {
  for (ContactPair& c : pairs) c.friction_old = c.tangent_impulse[0] * c.t1 + c.tangent_impulse[1] * c.t2;
}

}  // namespace pba::detail
