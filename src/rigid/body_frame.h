// Private to the library: a rigid body's frame and a shape's world pose, with the products by
// identities left out where they give the same bits (most bodies are a centred ball or box made
// alone, whose principal frame is the body frame, and most shapes sit at their body's origin).
// RigidBodySystem::body_pose is defined here, inline, for update_proxies (contact_pairs.cpp),
// which makes one for each awake body every step, and RigidContacts::shape_pose (contacts.h).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

#include "pba/rigid.h"

namespace pba {
namespace detail {

// (the tests below read bits, without branches: update_proxies makes them for each awake body and
// shape every step; compared as doubles, with branches, they cost it 3.5% more instructions)

/// Whether `v` is (+0, +0, +0) to the bit: a -0 compares equal to 0 but changes the signs of
/// sums, so only this zero may be left out of one.
inline bool positive_zero(const Vec3& v) {
  return (std::bit_cast<std::uint64_t>(v.x) | std::bit_cast<std::uint64_t>(v.y) |
          std::bit_cast<std::uint64_t>(v.z)) == 0;
}

/// Whether q is the identity (1, +-0, +-0, +-0), as q == Quat(1, 0, 0, 0) says.
inline bool is_identity(const Quat& q) {
  return std::bit_cast<std::uint64_t>(q.w) == std::bit_cast<std::uint64_t>(1.0) &&
         ((std::bit_cast<std::uint64_t>(q.x) | std::bit_cast<std::uint64_t>(q.y) | std::bit_cast<std::uint64_t>(q.z))
          << 1) == 0;
}

/// Whether q times a unit quaternion (1, +-0, +-0, +-0), either way round, is q to the bit:
/// each component of the product is one of q's plus signed zeros, which leave a finite
/// non-zero number as it is (a zero component could come out with the other sign). Read from
/// the exponents: none is 0 (a zero; a subnormal too, which then takes the full product) or
/// all ones (an infinity or a NaN).
inline bool exact_times_identity(const Quat& q) {
  auto plain = [](double x) { return ((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7ff) - 1 < 0x7fe; };
  return plain(q.w) & plain(q.x) & plain(q.y) & plain(q.z);
}

/// The world pose of a body frame: its principal frame is at `com` (world centre of mass, m)
/// turned by `q`, and sits in the body frame at `com_local` (m) turned by `principal`:
/// r = normalize(q conjugate(principal)) placed at com - r com_local. A body whose principal
/// frame is its own, centred (a ball or a box made alone), skips the products by those
/// identities where they give the same bits: q conjugate(identity) is q when
/// exact_times_identity(q), and com - r (+0, +0, +0) is com (r turns +0 into +0 in glm; a -0 in
/// `com_local` takes the full product, which would turn a -0 coordinate of com into +0).
inline Pose body_frame(const Vec3& com, const Quat& q, const Vec3& com_local, const Quat& principal) {
  if (is_identity(principal) & positive_zero(com_local) & exact_times_identity(q))
    return {com, glm::normalize(q)};
  const Quat r = glm::normalize(q * glm::conjugate(principal));
  return {com - r * com_local, r};
}

/// compose(body, local) (a shape's world pose from its body's and its pose in the body frame),
/// skipping the products by an identity `local` where they give compose()'s bits: at
/// (+0, +0, +0) and unturned, with every component of body.rotation finite and non-zero
/// (exact_times_identity); the position is body.position plus +0, which turns a -0 coordinate
/// into +0 as compose()'s sum does.
inline Pose shape_frame(const Pose& body, const Pose& local) {
  if (positive_zero(local.position) & is_identity(local.rotation) & exact_times_identity(body.rotation))
    return {body.position + Vec3(0), glm::normalize(body.rotation)};
  return compose(body, local);
}
}  // namespace detail

inline Pose RigidBodySystem::body_pose(std::size_t i) const {
  return detail::body_frame(com_[i], q_[i], com_local_[i], principal_[i]);
}

}  // namespace pba
