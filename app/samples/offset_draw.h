// A DebugDraw adaptor shared by the samples: every primitive moved by a fixed offset.
#pragma once

#include <string_view>

#include <glm/gtx/quaternion.hpp>

#include "pba/draw.h"

namespace pba::app {

/// Draws through another DebugDraw with everything moved by `offset` (m): for samples that
/// simulate several copies of a scene at the same place and draw them side by side (the
/// Solver lab's compare mode), or that draw a scene away from its own origin (Broad phase).
class OffsetDraw final : public DebugDraw {
 public:
  OffsetDraw(DebugDraw& to, const Vec3& offset) : to_(to), d_(offset) {}
  void point(const Vec3& p, float size, Color c) override { to_.point(p + d_, size, c); }
  void line(const Vec3& a, const Vec3& b, Color c) override { to_.line(a + d_, b + d_, c); }
  void sphere(const Vec3& center, double radius, Color c) override { to_.sphere(center + d_, radius, c); }
  void box(const Vec3& center, const Vec3& half, const Quat& q, Color c) override { to_.box(center + d_, half, q, c); }
  void capsule(const Vec3& a, const Vec3& b, double radius, Color c) override { to_.capsule(a + d_, b + d_, radius, c); }
  // The patch is centred nearest the offset origin: the renderer centres it nearest the world's,
  // where the copies' patches of one plane (the compared ramps, moved along the plane) would fall
  // on one another. Moved along the plane, it is drawn as a slab 1 cm thick.
  void plane(const Vec3& n, double offset, double half_size, Color c) override {
    const Vec3 u = glm::normalize(n);
    const double shift = offset / glm::length(n) + glm::dot(u, d_);
    const Vec3 along = d_ - glm::dot(u, d_) * u;
    if (glm::dot(along, along) < 1e-12) {
      to_.plane(n, offset + glm::dot(n, d_), half_size, c);
      return;
    }
    to_.box(u * (shift - 0.005) + along, Vec3(half_size, 0.005, half_size), glm::rotation(Vec3(0, 1, 0), u), c);
  }
  void arrow(const Vec3& from, const Vec3& to, double head, Color c) override { to_.arrow(from + d_, to + d_, head, c); }
  void text(const Vec3& p, std::string_view s, Color c) override { to_.text(p + d_, s, c); }
  void triangle(const Vec3& a, const Vec3& b, const Vec3& c, Color col) override {
    to_.triangle(a + d_, b + d_, c + d_, col);
  }

 private:
  DebugDraw& to_;
  Vec3 d_;
};

}  // namespace pba::app
