// The collision world: the colliders of a tick, validated once and flattened once for
// every client (the particle kernel in float, the soft bodies in double).
#include <algorithm>
#include <cstring>
#include <string>
#include <type_traits>

#include "pba/collide/collision_world.h"

namespace pba {

namespace detail {

namespace {

// The rotation the flat form uses. Colliders are validated unit to 1e-6; the float form
// renormalises (the particle kernel always did, and float keeps nothing of the last
// bits anyway), the double form takes the quaternion as given (the soft bodies always
// did): each client keeps the bits it had before the two shared this code.
template <class T>
Quat flat_rotation(const Quat& q) {
  if constexpr (std::is_same_v<T, float>)
    return glm::normalize(q);
  else
    return q;
}

// column-major rotation matrix, rounded to T
template <class T>
void rotation_columns(const Quat& q, T* r) {
  const Mat3 m = glm::mat3_cast(flat_rotation<T>(q));
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) r[c * 3 + k] = static_cast<T>(m[c][k]);
}

}  // namespace

template <class T>
FlatShape<T> flatten(const Collider& c) {
  FlatShape<T> p{};
  p.type = c.shape.type;
  p.e = static_cast<T>(c.material.restitution);
  p.mu = static_cast<T>(c.material.friction);
  // planes in world: n = R n_local / |n_local|, d = offset / |n_local| + n . origin
  const double len = glm::length(c.shape.normal);
  const Vec3 nl = c.shape.normal / len;
  const double offset = c.shape.offset / len;
  auto plane = [&](const Pose& pose, T& nx, T& ny, T& nz, T& d) {
    const Vec3 n = glm::normalize(flat_rotation<T>(pose.rotation) * nl);
    nx = static_cast<T>(n.x);
    ny = static_cast<T>(n.y);
    nz = static_cast<T>(n.z);
    d = static_cast<T>(offset + glm::dot(n, pose.position));
  };
  plane(c.begin, p.n0x, p.n0y, p.n0z, p.d0);
  plane(c.end, p.n1x, p.n1y, p.n1z, p.d1);
  // the frame's path and the shape's parameters
  p.c0x = static_cast<T>(c.begin.position.x);
  p.c0y = static_cast<T>(c.begin.position.y);
  p.c0z = static_cast<T>(c.begin.position.z);
  p.c1x = static_cast<T>(c.end.position.x);
  p.c1y = static_cast<T>(c.end.position.y);
  p.c1z = static_cast<T>(c.end.position.z);
  p.radius = static_cast<T>(c.shape.radius);
  p.hh = static_cast<T>(c.shape.half_height);
  p.hx = static_cast<T>(c.shape.half_extents.x);
  p.hy = static_cast<T>(c.shape.half_extents.y);
  p.hz = static_cast<T>(c.shape.half_extents.z);
  rotation_columns(c.begin.rotation, p.r0);
  rotation_columns(c.end.rotation, p.r1);
  // the frame's motion
  p.vx = static_cast<T>(c.velocity.x);
  p.vy = static_cast<T>(c.velocity.y);
  p.vz = static_cast<T>(c.velocity.z);
  p.wx = static_cast<T>(c.angular_velocity.x);
  p.wy = static_cast<T>(c.angular_velocity.y);
  p.wz = static_cast<T>(c.angular_velocity.z);
  p.is_static = p.n0x == p.n1x && p.n0y == p.n1y && p.n0z == p.n1z && p.d0 == p.d1 && p.c0x == p.c1x &&
                p.c0y == p.c1y && p.c0z == p.c1z && c.velocity == Vec3(0) && c.angular_velocity == Vec3(0);
  return p;
}

template FlatShape<float> flatten<float>(const Collider&);
template FlatShape<double> flatten<double>(const Collider&);

}  // namespace detail

namespace {

// same bit patterns in every field (so the same flat forms; -0 and +0 differ here)
template <class V>
bool bits(const V& a, const V& b) {
  return std::memcmp(&a, &b, sizeof(V)) == 0;
}
bool same_bits(const Collider& a, const Collider& b) {
  const ColliderShape &s = a.shape, &t = b.shape;
  return s.type == t.type && bits(s.normal, t.normal) && bits(s.offset, t.offset) && bits(s.radius, t.radius) &&
         bits(s.half_extents, t.half_extents) && bits(s.half_height, t.half_height) && s.hull == t.hull &&
         s.mesh == t.mesh && s.compound == t.compound && bits(a.material.restitution, b.material.restitution) &&
         bits(a.material.friction, b.material.friction) && bits(a.begin.position, b.begin.position) &&
         bits(a.begin.rotation, b.begin.rotation) && bits(a.end.position, b.end.position) &&
         bits(a.end.rotation, b.end.rotation) && bits(a.velocity, b.velocity) &&
         bits(a.angular_velocity, b.angular_velocity);
}

}  // namespace

void CollisionWorld::clear() {
  colliders_.clear();
  owners_.clear();
  flat_f_.clear();
  flat_d_.clear();
  ++revision_;
}

std::size_t CollisionWorld::add(const Collider& c, std::uint32_t owner, std::string_view where) {
  // validate (the message is built only for a bad collider), then flatten once
  if (!c.ok()) c.validate(where);
  return push(c, owner);
}

std::size_t CollisionWorld::push(const Collider& c, std::uint32_t owner) {
  colliders_.push_back(c);
  owners_.push_back(owner);
  flat_f_.push_back(detail::flatten<float>(c));
  flat_d_.push_back(detail::flatten<double>(c));
  ++revision_;
  return colliders_.size() - 1;
}

void CollisionWorld::assign(std::span<const Collider> colliders, std::string_view where) {
  // the same colliders as now, bit for bit (a static scene handed over each step):
  // already validated and flattened
  if (colliders.size() == colliders_.size() &&
      std::equal(colliders.begin(), colliders.end(), colliders_.begin(), same_bits) &&
      std::all_of(owners_.begin(), owners_.end(), [](std::uint32_t o) { return o == kNoOwner; }))
    return;
  clear();
  for (std::size_t i = 0; i < colliders.size(); ++i) {
    if (!colliders[i].ok()) colliders[i].validate(std::string(where) + "[" + std::to_string(i) + "]");
    push(colliders[i], kNoOwner);
  }
}

void CollisionWorld::set(std::size_t i, const Collider& c, std::string_view where) {
  if (i >= colliders_.size())
    throw Error(std::string(where) + ": collider " + std::to_string(i) + " does not exist (the world has " +
                std::to_string(colliders_.size()) + ")");
  if (!c.ok()) c.validate(where);
  colliders_[i] = c;
  flat_f_[i] = detail::flatten<float>(c);
  flat_d_[i] = detail::flatten<double>(c);
  ++revision_;
}

void CollisionWorld::draw(DebugDraw& draw, Color c, const DrawFlags& flags) const {
  for (const Collider& k : colliders_) k.draw(draw, c, flags);
}

}  // namespace pba
