// The samples application's frame loop, sample switching and headless capture.
#include "app.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <thread>

#include <GLFW/glfw3.h>
#include <glm/gtc/matrix_transform.hpp>
#include <imgui.h>
#include <imgui_internal.h>

#include "gl.h"
#include "image_check.h"
#include "progress.h"

namespace pba::app {

namespace fs = std::filesystem;

App::App(const Options& options) : options_(options) {
  headless_ = options.headless || options.selftest;
}

App::~App() {
  // the physics thread must stop before the sample, and GL objects go before the context
  if (physics_) physics_->attach(nullptr);
  sample_.reset();
  physics_.reset();
  target_.reset();
  renderer_.reset();
}

bool App::init() {
  // window and GL context: hidden for headless capture
  WindowConfig wc;
  wc.width = options_.width;
  wc.height = options_.height;
  wc.visible = !headless_;
  std::string error;
  if (!window_.open(wc, &error)) {
    std::fprintf(stderr, "pba_samples: %s\n", error.c_str());
    return false;
  }
  renderer_ = std::make_unique<Renderer>();
  if (!renderer_->init(&error)) {
    std::fprintf(stderr, "pba_samples: renderer: %s\n", error.c_str());
    return false;
  }
  target_ = std::make_unique<FrameTarget>();
  // anti-aliasing: 4x, except live on a software rasteriser, where it would cost the frame rate
  if (options_.msaa <= 0) {
    const char* gl_renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const bool software = gl_renderer && (std::strstr(gl_renderer, "llvmpipe") || std::strstr(gl_renderer, "softpipe"));
    options_.msaa = (software && !headless_) ? 1 : 4;
  }
  physics_ = std::make_unique<PhysicsLoop>(ctx_.settings, headless_);
  ctx_.renderer = renderer_.get();
  ctx_.camera = &camera_;
  ctx_.physics = physics_.get();
  ctx_.virtual_time = headless_;
  ctx_.settings.show_ui = !options_.hide_ui;
  ctx_.options = options_.sample_options;
  ctx_.draw = options_.view;
  last_frame_start_ = std::chrono::steady_clock::now();
  return true;
}

void App::apply_options_to_settings() {
  // command-line choices win over a sample's preferences
  Settings& s = ctx_.settings;
  if (options_.dt) s.stepper.fixed_dt = *options_.dt;
  if (options_.strategy) s.stepper.strategy = *options_.strategy;
  if (options_.method) s.method = *options_.method;
  if (options_.substeps) s.substeps = *options_.substeps;
}

void App::load_sample(int index) {
  const bool restart = sample_ && index == sample_index_;
  // stop the physics before the sample goes away
  physics_->attach(nullptr);
  sample_.reset();
  const Camera keep = camera_;
  if (!restart) {
    // a new sample starts from the app's defaults, then the command line
    const Settings old = ctx_.settings;
    ctx_.settings = Settings{};
    ctx_.settings.show_ui = old.show_ui;
    ctx_.settings.show_labels = old.show_labels;
    ctx_.settings.show_grid = old.show_grid;
    ctx_.settings.show_profiler = old.show_profiler;
    ctx_.settings.paused = old.paused;
    apply_options_to_settings();
    camera_ = Camera{};
  }
  // samples frame the camera in their constructor: tell it the region the panels leave
  update_view_region();
  renderer_->style = SceneStyle{};
  ctx_.settings.single_step = false;
  ctx_.virtual_charge = 0;
  diverged_.clear();
  stop_expected_ = false;
  sample_index_ = index;
  ctx_.option_keys.clear();
  // a restart keeps the step rate, strategy, substeps and integrator the user has (the
  // command line's or the panel's): a sample's constructor sets its preferences, which
  // before overrode --dt and the panel's choices at every R
  const Settings kept = ctx_.settings;
  sample_ = Samples()[index].create(ctx_);
  if (restart) camera_ = keep, ctx_.settings = kept;
  else apply_options_to_settings();
  physics_->attach(sample_.get());
}

void App::handle_input() {
  const ImGuiIO& io = ImGui::GetIO();
  Settings& s = ctx_.settings;
  const int n = static_cast<int>(Samples().size());
  // key presses the UI does not want (queued, so short taps at low frame rates count)
  const auto keys = window_.take_key_presses();
  // Esc closes an open menu first (also while its search box has the keyboard), leaves a
  // text field to ImGui, and quits otherwise
  const bool menu_open = ImGui::IsPopupOpen("", ImGuiPopupFlags_AnyPopupId | ImGuiPopupFlags_AnyPopupLevel);
  for (const auto& [key, mods] : keys) {
    if (key != GLFW_KEY_ESCAPE) continue;
    // every open popup (menus, submenus, combo boxes) closes before this frame draws them
    // (imgui_internal.h: Dear ImGui 1.86 has no public call that closes them all)
    if (menu_open) ImGui::ClosePopupToLevel(0, true);
    else if (!io.WantTextInput) quit_ = true;
  }
  if (!io.WantCaptureKeyboard) {
    for (const auto& [key, mods] : keys) {
      switch (key) {
        case GLFW_KEY_P:
        case GLFW_KEY_SPACE: s.paused = !s.paused; break;
        case GLFW_KEY_O: s.paused = true, s.single_step = true; break;
        case GLFW_KEY_R: s.restart = true; break;
        case GLFW_KEY_F1: s.show_ui = !s.show_ui; break;
        case GLFW_KEY_F12: screenshot_ = true; break;
        case GLFW_KEY_ESCAPE: break;
        case GLFW_KEY_LEFT_BRACKET:
        case GLFW_KEY_PAGE_UP: load_sample((sample_index_ + n - 1) % n); break;
        case GLFW_KEY_RIGHT_BRACKET:
        case GLFW_KEY_PAGE_DOWN: load_sample((sample_index_ + 1) % n); break;
        default: {
          auto lock = physics_->lock_state();
          sample_->Keyboard(key, mods);
          break;
        }
      }
    }
  }
  // a file dropped on the window: the sample may take it, else a scene file opens in the
  // "Scene file" sample
  for (const std::string& path : window_.take_dropped_files()) open_file(path);
  // the world-space ray under the cursor
  const float w = std::max(io.DisplaySize.x, 1.0f), h = std::max(io.DisplaySize.y, 1.0f);
  const glm::mat4 inv = glm::inverse(camera_.projection(w / h) * camera_.view());
  const float nx = 2 * io.MousePos.x / w - 1, ny = 1 - 2 * io.MousePos.y / h;
  glm::vec4 a = inv * glm::vec4(nx, ny, -1, 1), c = inv * glm::vec4(nx, ny, 1, 1);
  a /= a.w, c /= c.w;
  const Vec3 ray_origin{glm::vec3(a)}, ray_dir{glm::normalize(glm::vec3(c - a))};
  const bool captured = sample_->MouseCaptured();
  if (!io.WantCaptureMouse || captured) {
    auto lock = physics_->lock_state();
    // clicks go to the sample first, so a press that grabs something does not orbit
    for (int b = 0; b < 3; ++b) {
      if (!ImGui::IsMouseClicked(b) && !ImGui::IsMouseReleased(b)) continue;
      if (io.WantCaptureMouse && !sample_->MouseCaptured()) continue;
      sample_->Mouse(b, ImGui::IsMouseClicked(b), ray_origin, ray_dir);
    }
    const ImVec2 d = io.MouseDelta;
    if (d.x != 0 || d.y != 0 || sample_->MouseCaptured()) sample_->MouseMove(ray_origin, ray_dir);
  }
  // camera: left-drag orbits, right/middle-drag or shift+left pans, wheel zooms
  if (!io.WantCaptureMouse) {
    const ImVec2 d = io.MouseDelta;
    const bool held = sample_->MouseCaptured();
    const bool pan = io.MouseDown[1] || io.MouseDown[2] || (io.MouseDown[0] && io.KeyShift && !held);
    if (pan && (d.x != 0 || d.y != 0)) camera_.pan(d.x, d.y, io.DisplaySize.y);
    else if (io.MouseDown[0] && !held && (d.x != 0 || d.y != 0)) camera_.orbit(d.x, d.y);
    if (io.MouseWheel != 0) camera_.zoom(io.MouseWheel);
  }
}

double App::next_frame_dt() {
  const Settings& s = ctx_.settings;
  if (headless_) {
    // virtual time: the frame lasts its nominal length, or longer when the render delay
    // and the work a sample charged do not fit in it
    double base = 1.0 / options_.fps;
    if (s.frame_limit_hz > 0) base = std::max(base, 1.0 / s.frame_limit_hz);
    const double work = s.render_delay_ms / 1000.0 + ctx_.virtual_charge;
    ctx_.virtual_charge = 0;
    return std::max(base, work);
  }
  const auto now = std::chrono::steady_clock::now();
  const double dt = std::chrono::duration<double>(now - last_frame_start_).count();
  last_frame_start_ = now;
  return std::clamp(dt, 0.0, 10.0);
}

void App::update_view_region() {
  // ImGui's display size, or the window's before the first frame
  const ImGuiIO& io = ImGui::GetIO();
  float w = io.DisplaySize.x, h = io.DisplaySize.y;
  if (w < 1 || h < 1) {
    int fw = 0, fh = 0;
    window_.framebuffer_size(&fw, &fh);
    w = static_cast<float>(std::max(fw, 1)), h = static_cast<float>(std::max(fh, 1));
  }
  ctx_.view = ViewRegion(ui_, ctx_.settings, w, h);
  // the view's centre moves to the region's (in normalised device units), and framing fits
  // the region's width at the window's vertical field of view
  camera_.shift_x = (ctx_.view.x0 + ctx_.view.x1 - w) / w;
  camera_.view_aspect = ctx_.view.width() / h;
}

void App::open_file(const std::string& path) {
  // the current sample first (the "Scene file" sample opens it in place)
  {
    auto lock = physics_->lock_state();
    if (sample_->OpenFile(path)) return;
  }
  if (fs::path(path).extension() != ".json") {
    std::fprintf(stderr, "pba_samples: %s: drop a scene file (.json) to open it\n", path.c_str());
    return;
  }
  std::string error;
  const int index = FindSample("Particles/Scene file", &error);
  if (index < 0) return;
  load_sample(index);
  auto lock = physics_->lock_state();
  sample_->OpenFile(path);
}

void App::save_screenshot() {
  screenshot_ = false;
  // screenshots/<sample>_NNN.png in the working directory, numbered after the last one
  std::error_code ec;
  fs::create_directories("screenshots", ec);
  const std::string slug = SampleSlug(Samples()[sample_index_]);
  std::string path;
  for (int k = 0; k < 10000; ++k) {
    char name[160];
    std::snprintf(name, sizeof name, "%s_%03d.png", slug.c_str(), k);
    path = (fs::path("screenshots") / name).string();
    if (!fs::exists(path, ec)) break;
  }
  std::vector<std::uint8_t> rgb;
  target_->read_rgb(&rgb);
  if (write_png_file(path, target_->width(), target_->height(), rgb)) {
    ui_.status = "saved " + path;
    std::printf("pba_samples: screenshot %s\n", fs::absolute(path).lexically_normal().c_str());
    std::fflush(stdout);
  } else {
    ui_.status = "could not write " + path;
    std::fprintf(stderr, "pba_samples: could not write %s\n", path.c_str());
  }
  ui_.status_until = ImGui::GetTime() + 4.0;
}

std::string App::check_drawn(const std::vector<std::uint8_t>& rgb, int w, int h) {
  // the simulated points, projected with this frame's camera
  points_.clear();
  {
    auto lock = physics_->lock_state();
    sample_->SimulatedPoints(points_, 4000);
  }
  if (points_.empty()) return {};
  pixels_.clear();
  for (const Vec3& p : points_) {
    glm::vec2 px;
    if (renderer_->project(p, &px) && px.x >= 1 && px.y >= 1 && px.x < w - 1 && px.y < h - 1 &&
        ctx_.view.contains(px.x, px.y))
      pixels_.push_back(px);
  }
  // the empty scene (background and ground only) through the same camera
  renderer_->begin_frame();
  const bool ground = renderer_->style.ground;
  renderer_->style.ground = ground && ctx_.settings.show_grid;
  target_->bind_scene();
  renderer_->render(camera_, w, h);
  renderer_->style.ground = ground;
  target_->resolve();
  target_->read_rgb(&empty_);
  // a point is drawn when a pixel of its 3x3 neighbourhood differs from the empty scene by
  // more than 12/255 in a channel (MSAA edges and dithering stay below that; a drawn
  // surface or particle is far above it on every background of the app)
  int drawn = 0;
  for (const glm::vec2& px : pixels_) {
    const int cx = static_cast<int>(px.x), cy = static_cast<int>(px.y);
    bool hit = false;
    for (int dy = -1; dy <= 1 && !hit; ++dy)
      for (int dx = -1; dx <= 1 && !hit; ++dx) {
        const std::size_t i = (static_cast<std::size_t>(cy + dy) * w + (cx + dx)) * 3;
        for (int c = 0; c < 3; ++c) hit = hit || std::abs(int(rgb[i + c]) - int(empty_[i + c])) > 12;
      }
    drawn += hit;
  }
  // most of what is simulated is in view, and nearly all of that is drawn
  const std::size_t n = points_.size(), inside = pixels_.size();
  char msg[200];
  if (2 * inside < n) {
    std::snprintf(msg, sizeof msg, "only %zu of %zu simulated points are inside the region the panels leave visible",
                  inside, n);
    return msg;
  }
  if (10 * drawn < 9 * static_cast<int>(inside)) {
    std::snprintf(msg, sizeof msg, "%d of the %zu simulated points in view are drawn (at least 90%% must be)", drawn,
                  inside);
    return msg;
  }
  return {};
}

void App::check_frame(int frame_index, const std::vector<std::uint8_t>& rgb, int w, int h) {
  // the first frames may still show an empty scene; then check every 4th and the last
  const bool last = frame_index + 1 >= options_.frames;
  if (frame_index < 2 || (frame_index % 4 != 0 && !last)) return;
  const std::vector<Color> expected = sample_->ExpectedColors();
  ImageRules rules;
  // a sample's colours count only in the 3D viewport: the region the side panels and the
  // menu bar leave, less every ImGui window drawn this frame (a panel's plot line in a
  // body's colour passed the check while the body it stood for was 1-3 pixels)
  const int tw = target_->width(), th = target_->height();
  viewport_.assign(static_cast<std::size_t>(tw) * static_cast<std::size_t>(th), 0);
  auto mark = [&](float x0, float y0, float x1, float y1, std::uint8_t value) {
    const int ax = std::clamp(static_cast<int>(std::floor(x0)), 0, tw), bx = std::clamp(static_cast<int>(std::ceil(x1)), 0, tw);
    const int ay = std::clamp(static_cast<int>(std::floor(y0)), 0, th), by = std::clamp(static_cast<int>(std::ceil(y1)), 0, th);
    for (int y = ay; y < by; ++y)
      std::fill(viewport_.begin() + static_cast<std::ptrdiff_t>(y) * tw + ax, viewport_.begin() + static_cast<std::ptrdiff_t>(y) * tw + bx, value);
  };
  mark(ctx_.view.x0, ctx_.view.y0, ctx_.view.x1, ctx_.view.y1, 1);
  // (imgui_internal.h: Dear ImGui 1.86 lists its windows only there; the unused implicit
  // "Debug" window is inactive by the end of the frame)
  for (const ImGuiWindow* win : ImGui::GetCurrentContext()->Windows)
    if (win->Active && !win->Hidden) mark(win->Pos.x, win->Pos.y, win->Pos.x + win->Size.x, win->Pos.y + win->Size.y, 0);
  const ImageStats st = MeasureImage(
      rgb, tw, th, [&](int y) { return renderer_->background_at_row(y); }, expected, rules.color_tolerance, &viewport_);
  const std::string err = CheckImage(st, rules, expected);
  if (!err.empty()) failures_.push_back("frame " + std::to_string(frame_index) + ": " + err);
  // what the sample simulates is drawn (checked last: it renders the empty scene over the frame)
  const std::string drawn = check_drawn(rgb, w, h);
  if (!drawn.empty()) failures_.push_back("frame " + std::to_string(frame_index) + ": " + drawn);
  if (first_checked_.empty()) first_checked_ = rgb;
  // the frame changed: 0.2% of it, or at least 8 pixels of the 3D view the panels leave
  // (a small subject moving far off, like the ballistic scene's 5 cm ball at 640x360, changes
  // a few dozen; the whole-frame share alone then hung on the panels' wall-clock readouts)
  else if (last && ImageDifference(first_checked_, rgb) < 0.002 && ChangedPixels(first_checked_, rgb, w, static_cast<int>(ctx_.view.x0), static_cast<int>(ctx_.view.y0),
                                 static_cast<int>(ctx_.view.x1), static_cast<int>(ctx_.view.y1)) < 8)
    failures_.push_back("frames do not change over time (frame 2 and frame " + std::to_string(frame_index) +
                        " are the same)");
}

bool App::frame() {
  window_.poll();
  if (window_.should_close() || quit_) return false;
  const double frame_dt = next_frame_dt();
  last_frame_dt_ = frame_dt;
  const auto frame_start = std::chrono::steady_clock::now();
  Settings& s = ctx_.settings;

  window_.begin_ui_frame();
  if (!headless_) handle_input();
  if (s.restart) {
    s.restart = false;
    load_sample(sample_index_);
  }

  // keep the orbit target centred in the part of the window the panels leave free
  int w = 0, h = 0;
  window_.framebuffer_size(&w, &h);
  update_view_region();

  // physics: the sample advances one frame (through the app's time stepper by default)
  ctx_.frame_dt = frame_dt;
  if (diverged_.empty()) {
    try {
      sample_->Update(frame_dt);
    } catch (const std::exception& e) {
      diverged_ = e.what();
    }
    const std::string thread_error = physics_->take_thread_error();
    if (!thread_error.empty()) diverged_ = thread_error;
    if (diverged_.empty()) {
      auto lock = physics_->lock_state();
      const FiniteCheck fc = sample_->CheckFinite();
      if (!fc.ok) diverged_ = fc.message;
      else diverged_ = sample_->ExpectedStop(), stop_expected_ = !diverged_.empty();
    }
    if (!diverged_.empty()) {
      s.paused = true;
      std::fprintf(stderr, "pba_samples: %s: %s\n", Samples()[sample_index_].full_name().c_str(), diverged_.c_str());
    }
  }
  const PhysicsReadout& pr = physics_->readout();
  ui_.frame_ms.push(static_cast<float>(frame_dt * 1000));
  ui_.physics_ms.push(static_cast<float>(pr.frame_tick_wall * 1000));
  ui_.ticks.push(static_cast<float>(pr.ticks));
  ui_.dropped_ms.push(static_cast<float>(pr.dropped * 1000));

  // the 3D scene: the sample queues shapes, the renderer draws them off-screen
  renderer_->begin_frame();
  if (diverged_.empty() || stop_expected_) {
    auto lock = physics_->lock_state();
    sample_->Draw(*renderer_, physics_->alpha());
  }
  const bool ground = renderer_->style.ground;
  renderer_->style.ground = ground && s.show_grid;
  target_->resize(w, h, options_.msaa);
  target_->bind_scene();
  renderer_->render(camera_, w, h);
  renderer_->style.ground = ground;
  target_->resolve();

  // labels and panels over it
  if (s.show_labels) renderer_->draw_labels(ImGui::GetBackgroundDrawList());
  UiActions act;
  if (s.show_ui) {
    UiFrame uf;
    uf.sample_index = sample_index_;
    uf.sample = sample_.get();
    uf.physics = &pr;
    uf.draw = &renderer_->stats();
    uf.frame_dt = frame_dt;
    uf.diverged = &diverged_;
    uf.headless = headless_;
    // the sample's panel reads (and may reset) its state: keep the physics thread out
    auto lock = physics_->lock_state();
    act = DrawUi(ui_, ctx_, uf);
  }
  if (!diverged_.empty() && !stop_expected_) {
    const UiActions d = DrawDiverged(diverged_, headless_, ctx_.view);
    act.restart = act.restart || d.restart;
  }
  window_.end_ui_frame();

  // the workbook's doWork(): an artificial render cost
  if (!headless_ && s.render_delay_ms > 0)
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(s.render_delay_ms));

  // a screenshot asked for by key or menu: the finished frame, panels included
  if (act.screenshot) screenshot_ = true;
  if (screenshot_) save_screenshot();

  // capture and self-test read the finished frame back
  if (capture_ || options_.selftest) {
    target_->read_rgb(&rgb_);
    if (capture_) {
      capture_->write_video(rgb_);
      const int k = options_.screenshot_every;
      const bool last = frame_index_ + 1 >= options_.frames;
      if (k > 0 && (frame_index_ % k == 0 || last)) {
        std::string error;
        if (!capture_->write_png(frame_index_, rgb_, &error)) failures_.push_back(error);
      }
    }
    if (options_.selftest) check_frame(frame_index_, rgb_, w, h);
  }

  // show it
  if (!headless_) {
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_.handle(), &fw, &fh);
    target_->present(fw, fh);
    window_.swap();
  }

  // frame-rate limit
  if (!headless_ && s.frame_limit_hz > 0) {
    const auto until = frame_start + std::chrono::duration<double>(1.0 / s.frame_limit_hz);
    std::this_thread::sleep_until(until);
  }

  // what the panels asked for takes effect next frame
  if (act.quit) quit_ = true;
  if (act.select >= 0) load_sample(act.select);
  else if (act.restart) load_sample(sample_index_);
  return !quit_;
}

int App::run_headless(int sample_index, const std::string& out_dir) {
  const SampleEntry& e = Samples()[sample_index];
  failures_.clear();
  first_checked_.clear();
  frame_index_ = 0;
  ctx_.settings.paused = false;
  // run() created the first sample already (to check its options): not twice
  if (!fresh_ || sample_index != sample_index_) load_sample(sample_index);
  fresh_ = false;

  // capture set-up: PNGs and the MP4 go to out_dir
  Capture capture;
  capture_ = nullptr;
  if (!out_dir.empty()) {
    std::string error;
    const std::string video = options_.video ? SampleSlug(e) + ".mp4" : "";
    if (!capture.open(out_dir, options_.width, options_.height, options_.fps, video, &error)) {
      std::fprintf(stderr, "pba_samples: %s\n", error.c_str());
      return 1;
    }
    capture_ = &capture;
  }

  // fixed number of frames of fixed virtual length
  const auto t0 = std::chrono::steady_clock::now();
  tools::Progress progress(e.full_name(), "frames", options_.frames,
                           options_.quiet ? tools::ProgressMode::Quiet : tools::ProgressMode::Auto);
  for (frame_index_ = 0; frame_index_ < options_.frames; ++frame_index_) {
    frame();
    progress.update(frame_index_ + 1);
  }
  progress.finish();
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  capture_ = nullptr;
  const bool video_ok = capture.close();

  // report where things went
  std::printf("%s: rendered %d frames (%dx%d) in %.1f s\n", e.full_name().c_str(), options_.frames, options_.width,
              options_.height, secs);
  const DrawStats& drawn = renderer_->stats();
  std::printf("  last frame: %d solids, %d triangles, %d lines, %d points, %d labels\n", drawn.solids, drawn.triangles,
              drawn.lines, drawn.points, drawn.labels);
  if (!out_dir.empty()) {
    const auto& pngs = capture.pngs();
    const std::string where = fs::absolute(out_dir).lexically_normal().string();
    if (!pngs.empty())
      std::printf("  images: %zu PNG files in %s/ (%s ... %s)\n", pngs.size(), where.c_str(),
                  fs::path(pngs.front()).filename().c_str(), fs::path(pngs.back()).filename().c_str());
    if (!capture.video_path().empty() && video_ok)
      std::printf("  video:  %s\n", fs::absolute(capture.video_path()).lexically_normal().c_str());
    else if (!capture.video_note().empty()) std::printf("  %s\n", capture.video_note().c_str());
  }
  std::fflush(stdout);
  if (!diverged_.empty() && !stop_expected_) failures_.push_back("simulation stopped: " + diverged_);
  if (!sample_->LoadError().empty()) failures_.push_back(e.full_name() + ": nothing to show (the error is above)");
  if (options_.selftest) {
    for (const std::string& f : failures_) std::fprintf(stderr, "SELFTEST FAIL %s: %s\n", e.full_name().c_str(), f.c_str());
    if (failures_.empty()) std::printf("SELFTEST PASS %s\n", e.full_name().c_str());
  } else {
    for (const std::string& f : failures_) std::fprintf(stderr, "pba_samples: %s\n", f.c_str());
  }
  return failures_.empty() ? 0 : 1;
}

int App::run() {
  if (!init()) return 1;
  const auto all = Samples();
  if (all.empty()) {
    std::fprintf(stderr, "pba_samples: no samples registered\n");
    return 1;
  }
  // the starting sample: the one asked for, else the default
  int index = 0;
  std::string error;
  if (!options_.sample.empty()) index = FindSample(options_.sample, &error);
  else {
    const int d = FindSample("Dynamics/Integrators", &error);
    index = d >= 0 ? d : 0;
  }
  if (index < 0) {
    std::fprintf(stderr, "pba_samples: %s\n", error.c_str());
    return 2;
  }

  // a sample rejects a bad --option in its constructor: a usage error
  try {
    load_sample(index);
    fresh_ = true;
    // a key the sample never asked for is a typo or belongs to another sample
    const std::string unknown = options_.all ? std::string() : UnknownOptions(ctx_, all[index]);
    if (!unknown.empty()) throw Error(unknown);
  } catch (const Error& e) {
    std::fprintf(stderr, "pba_samples: %s\n", e.what());
    return 2;
  }
  if (!headless_) {
    // interactive
    while (frame()) {
    }
    return 0;
  }

  // headless: one sample or all of them, each into its own directory
  if (options_.frames < 0) options_.frames = options_.selftest ? 60 : 300;
  std::vector<int> indices;
  if (options_.all)
    for (int i = 0; i < static_cast<int>(all.size()); ++i) indices.push_back(i);
  else
    indices.push_back(index);
  int rc = 0;
  for (int i : indices) {
    std::string dir;
    const std::string slug = SampleSlug(all[i]);
    if (!options_.out.empty()) dir = options_.all ? (fs::path(options_.out) / slug).string() : options_.out;
    else if (!options_.selftest) dir = (fs::path("captures") / slug).string();
    rc |= run_headless(i, dir);
  }
  return rc;
}

}  // namespace pba::app
