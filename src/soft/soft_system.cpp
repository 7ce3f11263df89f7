// Soft bodies as World components: stepped each tick at WorldStage::Soft with the world's
// collision world and gravity.
#include <string>

#include "pba/soft.h"

namespace pba {

std::size_t SoftSystem::index_of(EntityId e, std::string_view where) const {
  for (std::size_t i = 0; i < owners_.size(); ++i)
    if (owners_[i] == e) return i;
  throw Error(std::string(where) + ": entity (index " + std::to_string(e.index) + ", generation " +
              std::to_string(e.generation) + ") has no soft body");
}

std::size_t SoftSystem::add(const World& world, EntityId e, SoftBody body) {
  // a live entity without a soft body yet
  if (!world.valid(e))
    throw Error("SoftSystem::add: entity (index " + std::to_string(e.index) + ", generation " +
                std::to_string(e.generation) + ") is not a live entity of this world");
  if (has(e)) throw Error("SoftSystem::add: entity '" + world.name(e) + "' already has a soft body");
  bodies_.push_back(std::move(body));
  owners_.push_back(e);
  return bodies_.size() - 1;
}

bool SoftSystem::has(EntityId e) const {
  for (const EntityId& o : owners_)
    if (o == e) return true;
  return false;
}

SoftBody& SoftSystem::body(EntityId e) { return bodies_[index_of(e, "SoftSystem::body")]; }
const SoftBody& SoftSystem::body(EntityId e) const { return bodies_[index_of(e, "SoftSystem::body")]; }

void SoftSystem::step(World& world, double t, double dt) {
  // every body under the world's gravity, against the collision world of this tick;
  // failures name the entity
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    try {
      bodies_[i].settings().forces.gravity = world.gravity();
      bodies_[i].step(t, dt, world.collision());
    } catch (const Error& err) {
      throw Error("soft body of entity '" + world.name(owners_[i]) + "': " + err.what());
    }
  }
}

void SoftSystem::on_destroy(EntityId e) {
  // swap-remove (the last body takes the gap)
  for (std::size_t i = 0; i < owners_.size(); ++i) {
    if (owners_[i] != e) continue;
    if (i + 1 != owners_.size()) {
      bodies_[i] = std::move(bodies_.back());
      owners_[i] = owners_.back();
    }
    bodies_.pop_back();
    owners_.pop_back();
    return;
  }
}

void SoftSystem::draw(const World&, DebugDraw& draw, const DrawFlags& flags) const {
  for (const SoftBody& b : bodies_) b.draw(draw, flags, options_);
}

std::uint64_t SoftSystem::hash(std::uint64_t seed) const {
  std::uint64_t h = seed;
  for (const SoftBody& b : bodies_) h = b.hash(h);
  return h;
}

SoftSystem& soft_system(World& world) {
  // the one registered under SoftSystem::kName, or a new one
  if (WorldSystem* s = world.find_system(SoftSystem::kName)) return static_cast<SoftSystem&>(*s);
  auto sys = std::make_unique<SoftSystem>();
  SoftSystem& ref = *sys;
  world.add_system(std::move(sys));
  return ref;
}

}  // namespace pba
