// Rigid bodies: mass properties from the collide module's shapes (its own file so that
// code using only given masses does not pull the shape geometry in).
#include "pba/rigid.h"

namespace pba {

RigidMass RigidMass::of_shape(const ColliderShape& s, double density, const Pose& local, std::string_view where) {
  const MassProperties p = mass_properties(s, density, where);
  const Mat3 r = glm::mat3_cast(local.rotation);
  return {p.mass, apply(local, p.center), r * p.inertia * glm::transpose(r)};
}

}  // namespace pba
