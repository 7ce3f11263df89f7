// Rigid-body tests, shared: thin square rods dropped tilted on a static ground with
// restitution, their drop height moved by k 1e-7 m (other trajectories of the same physics),
// measured step by step: the largest mechanical energy and the largest displacement of the
// centre of mass in one step beyond what the step's start and end speeds allow
// (test_rigid_contact.cpp's slice, soak_rigid.cpp's full sweep; docs/rigid-bodies.md, "The
// elastic bound").
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "pba/rigid.h"

namespace pba::test {

/// One drop's measures.
struct RodDrop {
  double start = 0;   ///< mechanical energy at the start (kinetic + m g y, the ground at y = 0) (J)
  double most = 0;    ///< the largest after it (J)
  double allowance = 0;  ///< the bound's allowance above the start (J; rod_drop())
  double excess = 0;  ///< the largest |dx| - bound of a step's centre displacement (m; <= 0: none beyond)
  int excess_step = -1;  ///< the step of it
};

/// A square rod t thick and `length` long (m), its long axis `angle` degrees from upright
/// about z, dropped from rest with its lowest corner 0.5 m + `raise` above the ground plane
/// (both of restitution e and friction 0.5), stepped `steps` steps of 1/60 s at the defaults
/// (8 substeps), no sleeping.
///
/// The energy bound, start + allowance: contacts with a body that does not move and
/// restitution e <= 1 cannot add energy; what the integration adds is the bounce's
/// discretisation (test_rigid_contact.cpp, ThinRodsBouncingOnTheGroundGainNoEnergy): the
/// restitution gives back the approach speed v of the substep h in which the rod meets the
/// ground, having fallen less than v h in it, m g v h (v = sqrt(2 g 0.5 m), the landing's
/// speed; h the substep, a step for sequential impulses), and symplectic Euler's flight loses
/// m g^2 h^2 / 2 a substep, so at e = 1 the next flight takes back what the last bounce gave
/// (a flight of 2 v / g loses m g v h). The float passes round at 2^-24 relative, far below it.
///
/// The displacement bound: in a step of dt the centre moves at most max(|v0|, |v1|) dt +
/// g dt^2 (v0, v1 the velocities at the step's start and end; gravity changes the velocity by
/// g dt within the step), plus push_out_speed dt: a biased pass may push an overlapping body
/// apart at up to that speed, and the relax pass takes the velocity back before the step
/// ends; plus the linear slop, as far as the soft step's position pass may lift a body out of
/// an overlap without a velocity. Anything beyond is a body moved at speeds the step's ends
/// do not show (docs/rigid-bodies.md).
inline RodDrop rod_drop(RigidSolverType solver, double t, double length, double e, double angle, double raise,
                        int steps = 600) {
  constexpr double g = 9.81, dt = 1.0 / 60, drop = 0.5;
  RigidBodySystem s({.contacts = {.solver = solver, .sleep = false}});
  s.create({.name = "ground", .type = BodyType::Static,
            .shapes = {{.shape = ColliderShape::plane({0, 1, 0}, 0), .material = {.restitution = e, .friction = 0.5}}}});
  const Quat q = glm::angleAxis(angle * kPi / 180, Vec3(0, 0, 1));
  const Vec3 half{t / 2, length / 2, t / 2};
  double lowest = 0;
  for (int i = 0; i < 8; ++i)
    lowest = std::min(lowest, (q * Vec3((i & 1 ? 1 : -1) * half.x, (i & 2 ? 1 : -1) * half.y, (i & 4 ? 1 : -1) * half.z)).y);
  const auto body = s.create({.pose = {{0, drop + raise - lowest, 0}, q},
                              .shapes = {{.shape = ColliderShape::box(half), .material = {.restitution = e, .friction = 0.5}}}});
  const double m = s.mass(body);
  auto energy = [&] { return s.kinetic_energy(body) + m * g * s.center_of_mass(body).y; };
  RodDrop r;
  r.start = r.most = energy();
  const double h = solver == RigidSolverType::SequentialImpulse ? dt : dt / s.settings().substeps;
  r.allowance = m * g * std::sqrt(2 * g * drop) * h;
  const double slack = s.settings().push_out_speed * dt + s.settings().linear_slop;
  r.excess = -1e300;
  for (int i = 0; i < steps; ++i) {
    const Vec3 x0 = s.center_of_mass(body), v0 = s.linear_velocity(body);
    s.step(dt, {0, -g, 0});
    const Vec3 x1 = s.center_of_mass(body), v1 = s.linear_velocity(body);
    const double beyond =
        glm::length(x1 - x0) - (std::max(glm::length(v0), glm::length(v1)) * dt + g * dt * dt + slack);
    if (beyond > r.excess) r.excess = beyond, r.excess_step = i;
    r.most = std::max(r.most, energy());
  }
  return r;
}

/// The drop's name for a failure message.
inline std::string rod_drop_case(RigidSolverType solver, double t, double length, double e, double angle, int k) {
  return std::string(to_string(solver)) + " t = " + std::to_string(t) + " L = " + std::to_string(length) +
         " e = " + std::to_string(e) + " angle = " + std::to_string(angle) + " raise = " + std::to_string(k) + "e-7";
}

}  // namespace pba::test
