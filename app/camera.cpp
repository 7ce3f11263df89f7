// Orbit camera: spherical coordinates around a target point.
#include "camera.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace pba::app {

void Camera::frame(const glm::vec3& center, float radius, float yaw_rad, float pitch_rad) {
  target = center;
  yaw = yaw_rad;
  pitch = pitch_rad;
  // distance at which a sphere of `radius` fits the narrower of the vertical field of view
  // and the horizontal one of the free region (tan of half of it = aspect tan(fov_y / 2)),
  // with a margin
  const float half_y = 0.5f * fov_y;
  const float half_x = std::atan(std::max(view_aspect, 0.05f) * std::tan(half_y));
  distance = std::max(0.5f, 1.1f * radius / std::sin(std::min(half_y, half_x)));
}

glm::vec3 Camera::eye() const {
  const float cp = std::cos(pitch);
  const glm::vec3 dir{cp * std::sin(yaw), std::sin(pitch), cp * std::cos(yaw)};
  return target + distance * dir;
}

glm::mat4 Camera::view() const { return glm::lookAt(eye(), target, glm::vec3(0, 1, 0)); }

glm::mat4 Camera::projection(float aspect) const {
  glm::mat4 p = glm::perspective(fov_y, std::max(aspect, 1e-3f), near_plane, far_plane);
  // off-centre projection: x_ndc += shift_x (clip.x += shift_x * w, with w = -z_view)
  p[2][0] -= shift_x;
  return p;
}

void Camera::orbit(float dx_px, float dy_px) {
  // 0.5 degrees per pixel; keep pitch away from the poles so lookAt stays defined
  const float k = 0.0087f;
  yaw -= dx_px * k;
  pitch = std::clamp(pitch + dy_px * k, -1.5f, 1.5f);
}

void Camera::pan(float dx_px, float dy_px, float height_px) {
  // move the target so the point under the cursor follows it at the target's depth
  const float metres_per_px = 2.0f * distance * std::tan(0.5f * fov_y) / std::max(height_px, 1.0f);
  const glm::mat4 v = view();
  const glm::vec3 right{v[0][0], v[1][0], v[2][0]};
  const glm::vec3 up{v[0][1], v[1][1], v[2][1]};
  target += (-dx_px * right + dy_px * up) * metres_per_px;
}

void Camera::zoom(float clicks) {
  distance = std::clamp(distance * std::pow(0.88f, clicks), 0.2f, 400.0f);
}

}  // namespace pba::app
