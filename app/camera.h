// Orbit camera for the samples app: turns around a target point, pans and zooms.
#pragma once

#include <glm/glm.hpp>

namespace pba::app {

/// A camera that orbits a target. Angles in radians, distances in metres.
/// Mouse: left-drag orbits, right- or middle-drag (or shift+left) pans, wheel zooms.
struct Camera {
  glm::vec3 target{0.0f, 1.0f, 0.0f};  ///< point the camera looks at and orbits around
  float yaw = 0.6f;                    ///< rotation about world +Y, 0 looks along -Z
  float pitch = 0.35f;                 ///< elevation above the horizon, in (-pi/2, pi/2)
  float distance = 10.0f;              ///< metres from target to eye, > 0
  float fov_y = 0.785398f;             ///< vertical field of view (45 degrees)
  float near_plane = 0.05f;            ///< near clip distance, m
  float far_plane = 500.0f;            ///< far clip distance, m
  /// Horizontal shift of the view centre in normalised device units (-1..1), so the target
  /// sits in the middle of the part of the window that panels leave free.
  float shift_x = 0.0f;
  /// Width / height of the part of the window that panels leave free (set by the app):
  /// frame() fits its sphere into that region, not into the whole window.
  float view_aspect = 16.0f / 9.0f;

  /// Puts the camera back at a framing that shows `center` with about `radius` metres around
  /// it, within the vertical field of view and the horizontal one of the free region.
  void frame(const glm::vec3& center, float radius, float yaw_rad = 0.0f, float pitch_rad = 0.25f);
  /// Eye position in world space.
  glm::vec3 eye() const;
  /// World-to-view transform.
  glm::mat4 view() const;
  /// View-to-clip transform for a viewport aspect ratio width/height.
  glm::mat4 projection(float aspect) const;

  /// Orbits by a mouse delta in pixels.
  void orbit(float dx_px, float dy_px);
  /// Pans the target parallel to the screen by a mouse delta in pixels for a viewport `height_px` tall.
  void pan(float dx_px, float dy_px, float height_px);
  /// Zooms by wheel clicks (positive moves closer).
  void zoom(float clicks);
};

}  // namespace pba::app
