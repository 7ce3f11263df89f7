// The samples application: owns the window, renderer, camera, physics loop and the
// current sample, and runs the frame loop (interactive or headless capture).
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "camera.h"
#include "capture.h"
#include "frame_target.h"
#include "options.h"
#include "physics_loop.h"
#include "renderer.h"
#include "sample.h"
#include "ui.h"
#include "window.h"

namespace pba::app {

/// The application. Construct from parsed options, then run().
class App {
 public:
  explicit App(const Options& options);
  ~App();
  App(const App&) = delete;
  App& operator=(const App&) = delete;

  /// Runs until the window closes (interactive) or the frames are done (headless).
  /// Returns the process exit code: 0 success, 1 failure (GL, capture or self-test).
  int run();

 private:
  bool init();
  void load_sample(int index);
  void apply_options_to_settings();
  void handle_input();
  bool frame();                 // one frame; false when the app should stop
  double next_frame_dt();
  int run_headless(int sample_index, const std::string& out_dir);
  void check_frame(int frame_index, const std::vector<std::uint8_t>& rgb, int w, int h);
  // the sample's simulated points that fall in the free region must show drawn pixels in
  // `rgb` (a w x h frame); returns the failure, empty when they do
  std::string check_drawn(const std::vector<std::uint8_t>& rgb, int w, int h);
  void update_view_region();                 // ctx_.view and the camera's framing region
  void open_file(const std::string& path);   // a dropped file
  void save_screenshot();                    // the finished frame to screenshots/

  Options options_;
  Window window_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<FrameTarget> target_;
  Camera camera_;
  SampleContext ctx_;
  std::unique_ptr<PhysicsLoop> physics_;
  std::unique_ptr<Sample> sample_;
  int sample_index_ = 0;
  UiState ui_;
  std::string diverged_;        // non-empty: the sample stopped with this message
  bool stop_expected_ = false;  // diverged_ is a stop the sample is designed to show
  bool quit_ = false;
  bool fresh_ = false;          // the current sample was created and has not run a frame
  bool headless_ = false;
  double last_frame_dt_ = 1.0 / 60;
  std::chrono::steady_clock::time_point last_frame_start_;
  // capture and self-test of the current headless run
  Capture* capture_ = nullptr;
  int frame_index_ = 0;
  std::vector<std::string> failures_;
  std::vector<std::uint8_t> first_checked_;
  std::vector<std::uint8_t> rgb_;
  std::vector<std::uint8_t> empty_;  // the empty scene, for check_drawn
  std::vector<std::uint8_t> viewport_;  // 1 where a pixel shows the 3D view (no ImGui window over it), for check_frame
  std::vector<Vec3> points_;         // simulated points, for check_drawn
  std::vector<glm::vec2> pixels_;    // and those in view, projected
  bool screenshot_ = false;          // save the next finished frame
};

}  // namespace pba::app
