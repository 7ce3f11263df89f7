// bench_rigid's ODE peer: the scene copied body by body from the pba system into an ODE 0.16
// world set up as shared/peers/ode_rigid.cpp does: a dHashSpace, dWorldQuickStep with 20
// iterations, ERP 0.2, CFM 1e-5, a contact surface layer of 1 mm, up to 8 contacts a pair
// with the friction pyramid (dContactApprox1); a ground plane becomes its 400 x 2 x 400
// static box. ODE leaves the mixing of materials to the caller: friction as pba mixes it
// (geometric mean), restitution the larger of the two above a 1 m/s approach (pba's
// threshold). Boxes, spheres and capsules; a scene with other shapes is not run.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <vector>

#include <ode/ode.h>

#include "bench_scenes.h"

namespace pba::bench {

namespace {

using Clock = std::chrono::steady_clock;

// a geom's material (dGeomSetData points to it)
struct OdeMaterial {
  double mu = 0.5, e = 0;
};

struct OdeWorld {
  dWorldID world = nullptr;
  dSpaceID space = nullptr;
  dJointGroupID contacts = nullptr;
  std::vector<std::unique_ptr<OdeMaterial>> materials;

  OdeWorld() {
    dInitODE2(0);
    world = dWorldCreate();
    space = dHashSpaceCreate(nullptr);
    contacts = dJointGroupCreate(0);
  }
  ~OdeWorld() {
    dJointGroupDestroy(contacts);
    dSpaceDestroy(space);  // and its geoms (cleanup mode)
    dWorldDestroy(world);  // and its bodies
    dCloseODE();
  }

  // one contact joint per point of each touching pair, as the peer harness makes them
  static void near(void* data, dGeomID a, dGeomID b) {
    auto* w = static_cast<OdeWorld*>(data);
    const dBodyID ba = dGeomGetBody(a), bb = dGeomGetBody(b);
    if (ba && bb && dAreConnected(ba, bb)) return;
    dContact c[8];
    const int n = dCollide(a, b, 8, &c[0].geom, sizeof(dContact));
    const auto* ma = static_cast<const OdeMaterial*>(dGeomGetData(a));
    const auto* mb = static_cast<const OdeMaterial*>(dGeomGetData(b));
    const double mu = std::sqrt(ma->mu * mb->mu), e = std::max(ma->e, mb->e);
    for (int i = 0; i < n; ++i) {
      c[i].surface.mode = dContactApprox1;
      c[i].surface.mu = mu;
      if (e > 0) {
        c[i].surface.mode |= dContactBounce;
        c[i].surface.bounce = e;
        c[i].surface.bounce_vel = 1.0;
      }
      const dJointID j = dJointCreateContact(w->world, w->contacts, &c[i]);
      dJointAttach(j, ba, bb);
    }
  }

  void step() {
    dSpaceCollide(space, this, &near);
    dWorldQuickStep(world, 1.0 / 60);
    dJointGroupEmpty(contacts);
  }
};

void set_rotation(dGeomID g, const Quat& q) {
  const dQuaternion o = {q.w, q.x, q.y, q.z};
  dGeomSetQuaternion(g, o);
}

Vec3 position(dBodyID b) {
  const dReal* p = dBodyGetPosition(b);
  return {p[0], p[1], p[2]};
}

}  // namespace

BenchResult run_ode(const BenchScene& scene, const RigidBodySystem& s, const std::vector<RigidBodyId>& tracked,
                    int steps) {
  BenchResult r;
  OdeWorld w;
  dWorldSetGravity(w.world, 0, -9.81, 0);
  dWorldSetERP(w.world, 0.2);
  dWorldSetCFM(w.world, 1e-5);
  dWorldSetQuickStepNumIterations(w.world, 20);
  dWorldSetContactSurfaceLayer(w.world, 0.001);
  dWorldSetAutoDisableFlag(w.world, scene.sleep ? 1 : 0);
  std::vector<dBodyID> by_slot;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const RigidBodyId id = s.id_at(i);
    const auto defs = s.shapes(id);
    const RigidShapeDef& d = defs[0];
    const bool plain = defs.size() == 1 && d.local.position == Vec3(0) && d.local.rotation == Quat(1, 0, 0, 0);
    const bool known = d.shape.type == ShapeType::Plane || d.shape.type == ShapeType::Box ||
                       d.shape.type == ShapeType::Sphere || d.shape.type == ShapeType::Capsule;
    if (!plain || !known) {
      r.note = "body '" + s.name(id) + "' has a " + std::string(to_string(d.shape.type)) +
               (plain ? " shape" : " or several shapes") + ", which this copy to ODE does not make";
      return r;
    }
    const Pose pose = s.pose(id);
    w.materials.push_back(std::make_unique<OdeMaterial>(OdeMaterial{d.material.friction, d.material.restitution}));
    dGeomID g = nullptr;
    dMass m;
    dMassSetZero(&m);
    const bool dynamic = s.type(id) == BodyType::Dynamic;
    const double mass = scene.unit_mass ? 1.0 : (dynamic ? s.mass(id) : 0.0);
    switch (d.shape.type) {
      case ShapeType::Plane: {
        // the peer's ground: a 400 x 2 x 400 box whose top face is the plane
        const Vec3 n = glm::normalize(pose.rotation * d.shape.normal);
        const Vec3 c = apply(pose, d.shape.normal * d.shape.offset) - n;
        g = dCreateBox(w.space, 400, 2, 400);
        dGeomSetPosition(g, c.x, c.y, c.z);
        const Vec3 axis = glm::cross(Vec3(0, 1, 0), n);
        set_rotation(g, n.y > -0.999999 ? glm::normalize(Quat(1 + n.y, axis.x, axis.y, axis.z)) : Quat(0, 1, 0, 0));
        break;
      }
      case ShapeType::Box: {
        const Vec3 h = d.shape.half_extents;
        g = dCreateBox(w.space, 2 * h.x, 2 * h.y, 2 * h.z);
        if (dynamic) dMassSetBoxTotal(&m, mass, 2 * h.x, 2 * h.y, 2 * h.z);
        break;
      }
      case ShapeType::Sphere:
        g = dCreateSphere(w.space, d.shape.radius);
        if (dynamic) dMassSetSphereTotal(&m, mass, d.shape.radius);
        break;
      default:  // capsule: ODE's lies along z, pba's along y
        g = dCreateCapsule(w.space, d.shape.radius, 2 * d.shape.half_height);
        if (dynamic) dMassSetCapsuleTotal(&m, mass, 2, d.shape.radius, 2 * d.shape.half_height);
        break;
    }
    dGeomSetData(g, w.materials.back().get());
    if (!dynamic) {
      if (d.shape.type != ShapeType::Plane) {
        dGeomSetPosition(g, pose.position.x, pose.position.y, pose.position.z);
        set_rotation(g, pose.rotation);
      }
      continue;
    }
    const dBodyID b = dBodyCreate(w.world);
    dBodySetMass(b, &m);
    dGeomSetBody(g, b);
    if (d.shape.type == ShapeType::Capsule) {
      const Quat z_to_y = glm::angleAxis(-0.5 * kPi, Vec3(1, 0, 0));
      const dQuaternion o = {z_to_y.w, z_to_y.x, z_to_y.y, z_to_y.z};
      dGeomSetOffsetQuaternion(g, o);
    }
    const Vec3 c = s.center_of_mass(id), v = s.linear_velocity(id), om = s.angular_velocity(id);
    dBodySetPosition(b, c.x, c.y, c.z);
    const dQuaternion q = {pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z};
    dBodySetQuaternion(b, q);
    dBodySetLinearVel(b, v.x, v.y, v.z);
    dBodySetAngularVel(b, om.x, om.y, om.z);
    if (by_slot.size() <= id.index) by_slot.resize(id.index + 1, nullptr);
    by_slot[id.index] = b;
  }
  std::vector<dBodyID> bodies;
  for (const RigidBodyId id : tracked) bodies.push_back(by_slot.at(id.index));
  const Vec3 rest = scene.top_rest ? scene.top_rest() : (bodies.empty() ? Vec3(0) : position(bodies.back()));
  // the steps (collision, QuickStep, contact joints emptied), timed one by one
  std::vector<double> ms;
  std::vector<char> out(bodies.size(), 0);
  for (int k = 0; k < steps; ++k) {
    const auto t0 = Clock::now();
    w.step();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    for (std::size_t j = 0; j < bodies.size(); ++j)
      if (!out[j] && scene.escaped(position(bodies[j]))) out[j] = 1, ++r.escapes;
  }
  r.ran = true;
  summarize_times(ms, r);
  if (!bodies.empty()) sag_and_drift(position(bodies.back()), rest, r);
  r.awake = 0;
  for (const dBodyID b : bodies) r.awake += dBodyIsEnabled(b) != 0;
  return r;
}

}  // namespace pba::bench
