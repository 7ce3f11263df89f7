// bench_rigid's Bullet peer: the scene copied body by body from the pba system into a
// btDiscreteDynamicsWorld set up as the peer harnesses do (shared/peers/bullet_rigid_*.cpp):
// btDbvtBroadphase, sequential impulses, one 60 Hz step per frame; a ground plane becomes
// their 200 x 2 x 200 static box, a triangle mesh a btBvhTriangleMeshShape; friction,
// restitution and rolling friction per body from its shape's material (Bullet combines them
// by its own rules), inertia from Bullet's calculateLocalInertia.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <vector>

#include <btBulletDynamicsCommon.h>

#include "bench_scenes.h"

namespace pba::bench {

namespace {

using Clock = std::chrono::steady_clock;

btVector3 bt(const Vec3& v) { return {static_cast<btScalar>(v.x), static_cast<btScalar>(v.y), static_cast<btScalar>(v.z)}; }
Vec3 from_bt(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
btTransform bt(const Pose& p) {
  const btQuaternion q(static_cast<btScalar>(p.rotation.x), static_cast<btScalar>(p.rotation.y),
                       static_cast<btScalar>(p.rotation.z), static_cast<btScalar>(p.rotation.w));
  return btTransform(q, bt(p.position));
}

// a Bullet world and everything its bodies point to
struct BulletWorld {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::vector<std::unique_ptr<btTriangleIndexVertexArray>> arrays;
  std::vector<std::vector<btVector3>> vertices;
  std::vector<std::vector<int>> indices;

  ~BulletWorld() {
    // the world's destructor still walks its objects: take them out first
    for (auto& b : bodies) world.removeRigidBody(b.get());
  }

  // Bullet's shape for a pba shape, or null for one it has no counterpart of here
  btCollisionShape* shape(const ColliderShape& c) {
    btCollisionShape* out = nullptr;
    switch (c.type) {
      case ShapeType::Sphere: out = new btSphereShape(static_cast<btScalar>(c.radius)); break;
      case ShapeType::Box: out = new btBoxShape(bt(c.half_extents)); break;
      case ShapeType::Capsule:
        out = new btCapsuleShape(static_cast<btScalar>(c.radius), static_cast<btScalar>(2 * c.half_height));
        break;
      case ShapeType::Hull: {
        auto* h = new btConvexHullShape();
        for (const Vec3& v : c.hull->vertices()) h->addPoint(bt(v), false);
        h->recalcLocalAabb();
        out = h;
        break;
      }
      case ShapeType::Mesh: {
        // the triangles by index into a float vertex array (Bullet's float build)
        const TriangleMesh& m = *c.mesh;
        vertices.emplace_back();
        indices.emplace_back();
        for (const Vec3& v : m.vertices()) vertices.back().push_back(bt(v));
        for (const auto& t : m.triangles())
          for (const std::uint32_t k : t) indices.back().push_back(static_cast<int>(k));
        arrays.push_back(std::make_unique<btTriangleIndexVertexArray>(
            static_cast<int>(m.triangles().size()), indices.back().data(), 3 * static_cast<int>(sizeof(int)),
            static_cast<int>(vertices.back().size()), reinterpret_cast<btScalar*>(vertices.back().data()),
            static_cast<int>(sizeof(btVector3))));
        out = new btBvhTriangleMeshShape(arrays.back().get(), true);
        break;
      }
      default: return nullptr;
    }
    shapes.emplace_back(out);
    return out;
  }
};

// the radius of the largest sphere about the shape's centre inside it (m), 0 if none
double inscribed(const ColliderShape& c) {
  switch (c.type) {
    case ShapeType::Sphere:
    case ShapeType::Capsule: return c.radius;
    case ShapeType::Box: return std::min(c.half_extents.x, std::min(c.half_extents.y, c.half_extents.z));
    default: return 0;
  }
}

}  // namespace

BenchResult run_bullet(const BenchScene& scene, const RigidBodySystem& s, const std::vector<RigidBodyId>& tracked,
                       int steps) {
  BenchResult r;
  BulletWorld w;
  w.world.setGravity({0, -9.81f, 0});
  w.world.getSolverInfo().m_numIterations = scene.bullet_iterations;
  // each pba body, by handle slot
  std::vector<btRigidBody*> by_slot;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const RigidBodyId id = s.id_at(i);
    const auto defs = s.shapes(id);
    const bool dynamic = s.type(id) == BodyType::Dynamic;
    Pose pose = s.pose(id);
    btCollisionShape* shape = nullptr;
    if (defs.size() == 1 && defs[0].shape.type == ShapeType::Plane) {
      // a plane: the peers' ground, a 200 x 2 x 200 box whose top face is the plane
      const Vec3 n = glm::normalize(pose.rotation * defs[0].shape.normal);
      const Vec3 on = apply(pose, defs[0].shape.normal * defs[0].shape.offset);
      const Vec3 c = glm::cross(Vec3(0, 1, 0), n);
      const Quat up = n.y > -0.999999 ? glm::normalize(Quat(1 + n.y, c.x, c.y, c.z)) : Quat(0, 1, 0, 0);
      pose = {on - n, up};
      w.shapes.push_back(std::make_unique<btBoxShape>(btVector3(200, 1, 200)));
      shape = w.shapes.back().get();
    } else if (defs.size() == 1 && defs[0].local.position == Vec3(0) && defs[0].local.rotation == Quat(1, 0, 0, 0)) {
      shape = w.shape(defs[0].shape);
    } else {
      auto* compound = new btCompoundShape();
      w.shapes.emplace_back(compound);
      for (const RigidShapeDef& d : defs)
        if (btCollisionShape* child = w.shape(d.shape)) compound->addChildShape(bt(d.local), child);
      shape = compound;
    }
    if (!shape) {
      r.note = "a shape of body '" + s.name(id) + "' has no counterpart in this copy to Bullet";
      return r;
    }
    const btScalar mass = dynamic ? static_cast<btScalar>(scene.unit_mass ? 1.0 : s.mass(id)) : 0;
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    btRigidBody::btRigidBodyConstructionInfo ci(mass, nullptr, shape, inertia);
    ci.m_startWorldTransform = bt(pose);
    w.bodies.push_back(std::make_unique<btRigidBody>(ci));
    btRigidBody* b = w.bodies.back().get();
    // the material of the body's first shape; rolling resistance times radius is Bullet's
    // rolling friction (a length, as pba's lever arm)
    const RigidShapeDef& d = defs[0];
    b->setFriction(static_cast<btScalar>(d.material.friction));
    b->setRestitution(static_cast<btScalar>(d.material.restitution));
    if (d.rolling_resistance > 0)
      b->setRollingFriction(static_cast<btScalar>(d.rolling_resistance * inscribed(d.shape)));
    if (dynamic) {
      b->setLinearVelocity(bt(s.linear_velocity(id)));
      b->setAngularVelocity(bt(s.angular_velocity(id)));
      if (!scene.sleep) b->setActivationState(DISABLE_DEACTIVATION);
      if (scene.bullet_ccd) {
        // Bullet's CCD demo: swept when a step moves a body farther than its inner radius,
        // by a sphere just inside it
        const double rin = inscribed(d.shape);
        b->setCcdMotionThreshold(static_cast<btScalar>(rin));
        b->setCcdSweptSphereRadius(static_cast<btScalar>(0.9 * rin));
      }
    }
    w.world.addRigidBody(b);
    if (by_slot.size() <= id.index) by_slot.resize(id.index + 1, nullptr);
    by_slot[id.index] = b;
  }
  std::vector<btRigidBody*> bodies;
  for (const RigidBodyId id : tracked) bodies.push_back(by_slot.at(id.index));
  const Vec3 rest = scene.top_rest ? scene.top_rest() : (bodies.empty() ? Vec3(0) : from_bt(bodies.back()->getWorldTransform().getOrigin()));
  // the steps, timed one by one; escapes counted between them
  std::vector<double> ms;
  std::vector<char> out(bodies.size(), 0);
  for (int k = 0; k < steps; ++k) {
    const auto t0 = Clock::now();
    w.world.stepSimulation(1.f / 60.f, 0);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    // (after the clock: not timed) the deepest overlap the step's collision detection found,
    // as pba's row reports it: the manifolds' distances are made before the solve
    btDispatcher* const d = w.world.getDispatcher();
    for (int m = 0, n = d->getNumManifolds(); m < n; ++m) {
      const btPersistentManifold* pm = d->getManifoldByIndexInternal(m);
      for (int c = 0; c < pm->getNumContacts(); ++c)
        if (const double depth = -pm->getContactPoint(c).getDistance(); depth > r.deepest) r.deepest = depth, r.deepest_step = k;
    }
    for (std::size_t j = 0; j < bodies.size(); ++j)
      if (!out[j] && scene.escaped(from_bt(bodies[j]->getWorldTransform().getOrigin()))) out[j] = 1, ++r.escapes;
  }
  r.ran = true;
  summarize_times(ms, r);
  if (!bodies.empty()) sag_and_drift(from_bt(bodies.back()->getWorldTransform().getOrigin()), rest, r);
  r.awake = 0;
  for (btRigidBody* b : bodies) r.awake += b->isActive();
  return r;
}

}  // namespace pba::bench
