// Off-screen render targets: a multisampled scene buffer resolved into a plain colour
// buffer that the UI is drawn over, read back for capture and copied to the window.
#pragma once

#include <cstdint>
#include <vector>

namespace pba::app {

/// A multisampled framebuffer for the 3D scene plus a single-sample framebuffer for the
/// final image (scene + UI). Works identically for visible and hidden windows.
class FrameTarget {
 public:
  FrameTarget() = default;
  ~FrameTarget();
  FrameTarget(const FrameTarget&) = delete;
  FrameTarget& operator=(const FrameTarget&) = delete;

  /// (Re)creates the buffers for `width` x `height` pixels with `samples` MSAA samples (1 = off).
  void resize(int width, int height, int samples);
  /// Binds the multisampled scene buffer for drawing.
  void bind_scene() const;
  /// Resolves the scene into the final buffer and leaves the final buffer bound (for the UI).
  void resolve() const;
  /// Reads the final buffer as tightly packed RGB rows, top row first.
  void read_rgb(std::vector<std::uint8_t>* rgb) const;
  /// Copies the final buffer to the window's default framebuffer of `w` x `h` pixels.
  void present(int w, int h) const;

  /// Width of the targets in pixels.
  int width() const { return width_; }
  /// Height of the targets in pixels.
  int height() const { return height_; }

 private:
  void release();
  int width_ = 0, height_ = 0, samples_ = 0;
  unsigned scene_fbo_ = 0, scene_color_ = 0, scene_depth_ = 0;
  unsigned final_fbo_ = 0, final_color_ = 0;
};

}  // namespace pba::app
