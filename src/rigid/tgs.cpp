// Rigid bodies: the TGS contact solver (temporal Gauss-Seidel).
//
// Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke and Mueller (2019), "Small steps in
// physics simulation": for the same cost, many substeps of one iteration converge faster than
// one step of many iterations, because each substep linearises the constraints again at the
// bodies' current poses. PhysX's TGS solver (and Jolt's, similarly) applies this to rigid
// contacts: the step is cut into substeps, each integrates the velocities, applies the carried
// impulses, runs a few iterations of rigid (not soft) contact constraints whose position bias
// comes from the separation measured at the bodies' poses of that substep, integrates the
// positions and, optionally, runs relax iterations without bias. One restitution pass follows.
//
// Differences to the soft step (same passes, src/rigid/contact_solver.cpp): the contacts are rigid
// (full effective mass, no impulse scale), and overlap beyond the linear slop is removed at
// `baumgarte` of it per substep (capped by push_out_speed) instead of by an implicit spring of
// contact_hertz; the iterations per substep are a setting (substep_iterations,
// relax_iterations) instead of one biased and one relax pass.
#include "contacts.h"

namespace pba::detail {

void RigidContacts::step_tgs(RigidBodySystem& s, double dt, const Vec3& gravity) {
  const ContactSettings& cs = s.settings_;
  const int substeps = cs.substeps;
  const double h = dt / substeps;
  // the free motion's fields in lanes for the substeps, as in the soft step (gathered once,
  // the centres and frames put back after the last): between them the passes, the
  // separations and the warm starts read the velocity, motion and warm rows only, and
  // refresh_inertia the lanes' frames (rigid_body.cpp, RigidContacts::free_lanes)
  const FreeLanesScope lanes(*this, s, h, gravity);
  for (int k = 0; k < substeps; ++k) {
    // velocities with the carried impulses
    s.integrate_velocities(h, gravity, rows.data(), warm.data());
    // rigid contacts, biased by the separation at this substep's poses
    for (int it = 0; it < cs.substep_iterations; ++it) pass(s, h, true, false, false, false);
    // positions, then the relax iterations that leave no push-out velocity behind: the first
    // measures the separations at the new poses, the last carries the impulses to the next
    // substep (without relax iterations, separate passes do both)
    s.integrate_positions(h, rows.data(), motion.data());
    refresh_inertia(s);
    const bool carry = cs.warm_starting && k + 1 < substeps;
    for (int it = 0; it < cs.relax_iterations; ++it)
      pass(s, h, false, false, it == 0, carry && it + 1 == cs.relax_iterations);
    if (cs.relax_iterations == 0) {
      update_separations(s);
      if (carry) accumulate_warm(s);
    }
  }
}

}  // namespace pba::detail
