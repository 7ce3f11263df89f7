// pba debug draw: the small interface through which the library shows what it does.
//
// The library calls these functions; an application implements them (the samples
// app renders them with OpenGL, a test may count them, a headless tool may ignore
// them). Modelled on Box2D's b2DebugDraw and Jolt's DebugRendererSimple: physics
// stays independent of graphics. All positions are world-space metres.
#pragma once

#include <cstdint>
#include <string_view>

#include "pba/core.h"

namespace pba {

/// Linear RGBA colour, each channel in [0, 1].
struct Color {
  float r = 1, g = 1, b = 1, a = 1;

  static constexpr Color rgb(float r, float g, float b, float a = 1) { return {r, g, b, a}; }
  /// Colour from 0xRRGGBB.
  static constexpr Color hex(std::uint32_t rgb, float a = 1) {
    return {((rgb >> 16) & 0xff) / 255.0f, ((rgb >> 8) & 0xff) / 255.0f, (rgb & 0xff) / 255.0f, a};
  }
};

/// A few named colours shared by samples so every method has one colour everywhere.
namespace colors {
inline constexpr Color white = Color::hex(0xffffff);
inline constexpr Color grey = Color::hex(0x8a8f98);
inline constexpr Color red = Color::hex(0xe5484d);
inline constexpr Color orange = Color::hex(0xf76b15);
inline constexpr Color yellow = Color::hex(0xffc53d);
inline constexpr Color green = Color::hex(0x46a758);
inline constexpr Color cyan = Color::hex(0x00a2c7);
inline constexpr Color blue = Color::hex(0x3e63dd);
inline constexpr Color purple = Color::hex(0x8e4ec6);
inline constexpr Color pink = Color::hex(0xd6409f);
}  // namespace colors

/// What the library's draw functions show (Box2D's b2DebugDraw flags). Every draw function
/// of the library takes the flags; the app's View menu toggles them.
struct DrawFlags {
  bool shapes = true;      ///< collision shapes, solid
  bool aabbs = false;      ///< world bounds of every shape
  bool tree = false;       ///< the broad phase's tree (or grid) nodes
  bool contacts = false;   ///< contact points, coloured by depth
  bool normals = false;    ///< contact normals
  bool particles = true;   ///< particles and soft-body nodes
  bool forcers = true;     ///< forcer volumes and emitters
  bool constraints = true; ///< springs, tethers, distance constraints
};

/// Interface the library draws through. Every call is immediate: the implementer
/// draws (or queues) the shape for the current frame only.
class DebugDraw {
 public:
  virtual ~DebugDraw() = default;

  /// A screen-facing dot of `size` pixels at `p`.
  virtual void point(const Vec3& p, float size, Color c) = 0;
  /// A line segment from `a` to `b`.
  virtual void line(const Vec3& a, const Vec3& b, Color c) = 0;
  /// A lit solid sphere of `radius` metres centred at `center`.
  virtual void sphere(const Vec3& center, double radius, Color c) = 0;
  /// A lit solid box with half extents `half` (m) posed by `rotation` at `center`.
  virtual void box(const Vec3& center, const Vec3& half, const Quat& rotation, Color c) = 0;
  /// A lit solid capsule: the segment a-b swept by a sphere of `radius` metres.
  virtual void capsule(const Vec3& a, const Vec3& b, double radius, Color c) = 0;
  /// A finite square patch of the plane n.x = offset, `half_size` metres from its centre.
  virtual void plane(const Vec3& normal, double offset, double half_size, Color c) = 0;
  /// An arrow from `from` to `to` with a head `head` metres long.
  virtual void arrow(const Vec3& from, const Vec3& to, double head, Color c) = 0;
  /// Text anchored at a world point, drawn facing the screen.
  virtual void text(const Vec3& p, std::string_view s, Color c) = 0;
  /// A filled triangle a-b-c (counter-clockwise seen from the front). The default draws
  /// its outline with line(); renderers that can fill triangles override it.
  virtual void triangle(const Vec3& a, const Vec3& b, const Vec3& c, Color col) {
    line(a, b, col);
    line(b, c, col);
    line(c, a, col);
  }
};

/// A DebugDraw that draws nothing: for headless stepping and benchmarks.
class NullDraw final : public DebugDraw {
 public:
  void point(const Vec3&, float, Color) override {}
  void line(const Vec3&, const Vec3&, Color) override {}
  void sphere(const Vec3&, double, Color) override {}
  void box(const Vec3&, const Vec3&, const Quat&, Color) override {}
  void capsule(const Vec3&, const Vec3&, double, Color) override {}
  void plane(const Vec3&, double, double, Color) override {}
  void arrow(const Vec3&, const Vec3&, double, Color) override {}
  void text(const Vec3&, std::string_view, Color) override {}
};

}  // namespace pba
