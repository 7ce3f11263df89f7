// Off-screen render targets for the scene and the final image.
#include "frame_target.h"

#include <algorithm>
#include <cstring>

#include "gl.h"

namespace pba::app {

FrameTarget::~FrameTarget() { release(); }

void FrameTarget::release() {
  if (scene_fbo_) glDeleteFramebuffers(1, &scene_fbo_);
  if (final_fbo_) glDeleteFramebuffers(1, &final_fbo_);
  const unsigned rbs[3] = {scene_color_, scene_depth_, final_color_};
  for (unsigned rb : rbs)
    if (rb) glDeleteRenderbuffers(1, &rb);
  scene_fbo_ = scene_color_ = scene_depth_ = final_fbo_ = final_color_ = 0;
}

void FrameTarget::resize(int width, int height, int samples) {
  width = std::max(width, 1);
  height = std::max(height, 1);
  GLint max_samples = 1;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples = std::clamp(samples, 1, std::max(1, static_cast<int>(max_samples)));
  if (width == width_ && height == height_ && samples == samples_) return;
  release();
  width_ = width, height_ = height, samples_ = samples;

  // multisampled colour + depth for the scene
  glGenRenderbuffers(1, &scene_color_);
  glBindRenderbuffer(GL_RENDERBUFFER, scene_color_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_ > 1 ? samples_ : 0, GL_RGBA8, width_, height_);
  glGenRenderbuffers(1, &scene_depth_);
  glBindRenderbuffer(GL_RENDERBUFFER, scene_depth_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_ > 1 ? samples_ : 0, GL_DEPTH_COMPONENT24, width_,
                                   height_);
  glGenFramebuffers(1, &scene_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, scene_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, scene_color_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, scene_depth_);

  // single-sample colour for the final image
  glGenRenderbuffers(1, &final_color_);
  glBindRenderbuffer(GL_RENDERBUFFER, final_color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width_, height_);
  glGenFramebuffers(1, &final_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, final_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, final_color_);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void FrameTarget::bind_scene() const {
  glBindFramebuffer(GL_FRAMEBUFFER, scene_fbo_);
  glViewport(0, 0, width_, height_);
}

void FrameTarget::resolve() const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, scene_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, final_fbo_);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, final_fbo_);
  glViewport(0, 0, width_, height_);
}

void FrameTarget::read_rgb(std::vector<std::uint8_t>* rgb) const {
  const std::size_t row = static_cast<std::size_t>(width_) * 3;
  std::vector<std::uint8_t> raw(row * height_);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, final_fbo_);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGB, GL_UNSIGNED_BYTE, raw.data());
  // OpenGL rows run bottom-up; images run top-down
  rgb->resize(raw.size());
  for (int y = 0; y < height_; ++y)
    std::memcpy(rgb->data() + y * row, raw.data() + (height_ - 1 - y) * row, row);
}

void FrameTarget::present(int w, int h) const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, final_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_LINEAR);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

}  // namespace pba::app
