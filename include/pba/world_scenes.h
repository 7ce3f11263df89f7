// pba world scenes: builders of World scenes that mix components (rigid bodies, soft bodies,
// colliders), shared by the samples and the tests so both run the same scene (as
// rigid_scenes.h does for a RigidBodySystem).
#pragma once

#include "pba/soft.h"
#include "pba/world.h"

namespace pba::world_scenes {

/// Settings of cloth_on_falling_box.
struct ClothOnBoxDef {
  double box_half = 0.5;    ///< the box's half size (m)
  double box_height = 1.5;  ///< the box's centre at the start (m), at rest
  double cloth_size = 2;    ///< the cloth's side (m)
  double cloth_height = 2.5;  ///< the cloth's height at the start (m), flat and at rest
  int cloth_particles = 21; ///< particles per side
  double cloth_mass = 0.2;  ///< the cloth's mass (kg)
  double friction = 0.6;    ///< the ground's friction
  /// The cloth's solver settings; its thickness (m) is the gap it keeps from surfaces.
  SoftBodyDef cloth{.thickness = 0.01};
};

/// The entities cloth_on_falling_box made.
struct ClothOnBox {
  EntityId ground{};  ///< the ground plane y = 0 (a World collider)
  EntityId box{};     ///< the box (a dynamic rigid body of 1000 kg/m^3)
  EntityId cloth{};   ///< the cloth (a soft body of the world's SoftSystem, no pins)
};

/// A box falling onto the ground and a square cloth, centred over it and higher, falling flat
/// onto it: the rigid stage moves the box first in each tick, so the cloth lands on the box
/// where it is in that tick, and drapes over it once both rest.
inline ClothOnBox cloth_on_falling_box(World& w, const ClothOnBoxDef& def = {}) {
  ClothOnBox out;
  out.ground = w.create_entity({.name = "ground"});
  w.add_collider(out.ground, {.shape = ColliderShape::plane({0, 1, 0}, 0),
                              .material = {.restitution = 0, .friction = def.friction}});
  out.box = w.create_entity({.name = "box", .pose = {{0, def.box_height, 0}, Quat(1, 0, 0, 0)}});
  w.add_rigid_body(out.box, {.shapes = {{.shape = ColliderShape::box(Vec3(def.box_half))}}});
  out.cloth = w.create_entity({.name = "cloth"});
  const double h = 0.5 * def.cloth_size;
  soft_system(w).add(w, out.cloth,
                     SoftBody::cloth_grid({.origin = {-h, def.cloth_height, -h}, .edge_u = {def.cloth_size, 0, 0},
                                           .edge_v = {0, 0, def.cloth_size}, .nx = def.cloth_particles,
                                           .ny = def.cloth_particles, .mass = def.cloth_mass, .pins = ClothPins::None},
                                          def.cloth));
  return out;
}

}  // namespace pba::world_scenes
