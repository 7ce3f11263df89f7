// Samples: the base class, the shared context and the self-registering catalogue.
//
// A sample lives in one .cpp under app/samples/ and registers itself:
//
//   static int reg = pba::app::RegisterSample("Dynamics", "Integrators", Integrators::Create);
//
// The app constructs it with a SampleContext, drives its physics through the time-stepping
// module (Step() once per tick and substep), then calls Draw() and DrawUI() every frame.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "pba/core.h"
#include "pba/draw.h"
#include "settings.h"

namespace pba::app {

class Renderer;
class PhysicsLoop;
struct Camera;

/// A rectangle of the window in pixels (x right, y down from the top-left corner).
struct ScreenRect {
  float x0 = 0, y0 = 0;  ///< top-left corner (px)
  float x1 = 1, y1 = 1;  ///< bottom-right corner (px), > x0 and > y0
  float width() const { return x1 - x0; }   ///< px
  float height() const { return y1 - y0; }  ///< px
  float center_x() const { return 0.5f * (x0 + x1); }  ///< px
  /// True when (x, y) lies inside.
  bool contains(float x, float y) const { return x >= x0 && x < x1 && y >= y0 && y < y1; }
};

/// What a sample may use from the app. Owned by the app; outlives every sample.
struct SampleContext {
  Settings settings;              ///< shared settings (the UI and command line edit them)
  Renderer* renderer = nullptr;   ///< the 3D renderer (a pba::DebugDraw with extras)
  Camera* camera = nullptr;       ///< the view; samples frame it in their constructor
  /// The part of the window the panels and the menu bar leave for the 3D view (px), set
  /// by the app every frame: overlays (banners, messages) go inside it.
  ScreenRect view{};
  PhysicsLoop* physics = nullptr; ///< the app's time stepper for Step()-driven samples
  /// True when frames advance by a fixed virtual frame time (headless capture): samples
  /// must then not measure wall-clock time, so images are reproducible.
  bool virtual_time = false;
  /// Virtual seconds of work the current frame pretends to have cost (a sample's simulated
  /// physics load); added to the next virtual frame time. Ignored with real time.
  double virtual_charge = 0;
  /// Real time (s) of the frame being advanced, as handed to Sample::Update.
  double frame_dt = 0;
  /// What the library's draw functions and the samples show (the View menu's debug-draw
  /// toggles). Samples read it every frame in Draw().
  pba::DrawFlags draw{};
  /// Sample-specific settings from --option KEY=VALUE. A sample reads the keys it knows
  /// in its constructor and throws pba::Error naming a bad value.
  std::map<std::string, std::string> options;
  /// The keys the current sample asked for through option() (the app clears it before
  /// creating a sample): a given key it never asked for is an unknown key (UnknownOptions).
  mutable std::set<std::string> option_keys;

  /// The option `key`, or `fallback` when it was not given.
  std::string option(const std::string& key, const std::string& fallback) const {
    option_keys.insert(key);
    const auto it = options.find(key);
    return it == options.end() ? fallback : it->second;
  }
};

/// Base class of every sample: override what you need.
class Sample {
 public:
  explicit Sample(SampleContext& ctx) : ctx_(ctx) {}
  virtual ~Sample() = default;
  Sample(const Sample&) = delete;
  Sample& operator=(const Sample&) = delete;

  /// One physics step of `dt` seconds starting at simulated time `t`. Called by the app's
  /// time stepper (on the physics thread with the "threaded" strategy).
  virtual void Step(double t, double dt) { (void)t, (void)dt; }
  /// Advances one rendered frame of `frame_dt` seconds of real time. The default hands
  /// the frame to the app's time stepper, which calls Step(); samples that run their own
  /// steppers (e.g. "Time stepping") override this.
  virtual void Update(double frame_dt);
  /// Draws the state. `alpha` in [0, 1] is how far real time has moved from the previous
  /// tick towards the latest one (for interpolated drawing; 1 draws the latest state).
  virtual void Draw(Renderer& r, double alpha) { (void)r, (void)alpha; }
  /// Adds the sample's own controls to its panel (called inside an ImGui window).
  virtual void DrawUI() {}
  /// A key press that the UI did not take (GLFW key code and modifier bits).
  virtual void Keyboard(int key, int mods) { (void)key, (void)mods; }
  /// A mouse button press or release at world ray origin/direction (no UI over it).
  virtual void Mouse(int button, bool down, const Vec3& ray_origin, const Vec3& ray_dir) {
    (void)button, (void)down, (void)ray_origin, (void)ray_dir;
  }
  /// The cursor moved (no UI over it, or the sample holds the mouse): its world ray.
  virtual void MouseMove(const Vec3& ray_origin, const Vec3& ray_dir) { (void)ray_origin, (void)ray_dir; }
  /// True while the sample drags something with the left button: the camera then does not
  /// orbit, and MouseMove keeps coming even over the panels.
  virtual bool MouseCaptured() const { return false; }
  /// Scans the state for NaN or infinity (pba::check_finite); the app pauses and shows
  /// the message when it fails.
  virtual FiniteCheck CheckFinite() const { return {}; }
  /// A stop the sample is designed to show (e.g. a spring integrated past its method's
  /// stability limit): the message, naming what stopped, when and why; empty while it runs.
  /// The app reports it like a divergence (printed to stderr, app paused) but keeps drawing
  /// the sample, and the self-test does not fail on it: it is an expected outcome.
  virtual std::string ExpectedStop() const { return {}; }
  /// Why the sample cannot show its subject (e.g. its scene file did not load), already
  /// reported by the sample; empty when it can. A headless run then exits with code 1.
  virtual std::string LoadError() const { return {}; }
  /// Colours that must be visible in a rendered frame (the self-test looks for them).
  virtual std::vector<Color> ExpectedColors() const { return {}; }
  /// Appends to `out` world points (m) where the current state has simulated matter
  /// (particles, soft-body nodes), at most about `max_points` of them. The self-test checks
  /// that what is simulated is drawn: most of these points must lie in the part of the
  /// window the panels leave visible, and the frame must differ there from the empty scene.
  /// Appending nothing skips the check.
  virtual void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const {
    (void)out, (void)max_points;
  }
  /// A file dropped on the window (or opened through the app): true when the sample took
  /// it (the "Scene file" sample opens a scene file), false to let the app decide.
  virtual bool OpenFile(const std::string& path) { (void)path; return false; }
  /// True when the sample runs its own time steppers and ignores the app's strategy.
  virtual bool OwnsTime() const { return false; }
  /// Whether the Simulation panel's integrator (Settings::method) drives this sample; the rigid
  /// body samples integrate with their solver (its settings in their own panel), so the panel
  /// leaves the choice out for them.
  virtual bool UsesIntegrator() const { return true; }

 protected:
  SampleContext& ctx_;
};

/// Creates a sample for the app's context.
using SampleFactory = std::unique_ptr<Sample> (*)(SampleContext& ctx);

/// One registered sample.
struct SampleEntry {
  std::string category;  ///< menu group, e.g. "Dynamics"
  std::string name;      ///< title, e.g. "Integrators"
  SampleFactory create;  ///< factory
  /// "Category/Name", the unique full name used by --sample and --list.
  std::string full_name() const { return category + "/" + name; }
};

/// Adds a sample to the catalogue; returns its registration number. Call from a static
/// initialiser in the sample's .cpp.
int RegisterSample(const char* category, const char* name, SampleFactory create);
/// Every registered sample, sorted by category then name.
std::span<const SampleEntry> Samples();
/// Index of the sample matching `query`: its full name "Category/Name" or its name
/// (case-insensitive, exact), else a unique case-insensitive substring of the full name.
/// Returns -1 and sets `error` (listing the valid names) when none or several match.
int FindSample(std::string_view query, std::string* error);
/// After sample `e` was created from `ctx`: a message naming every --option key it did not
/// ask for and listing the keys it reads, or empty when every key was read.
std::string UnknownOptions(const SampleContext& ctx, const SampleEntry& e);
/// A file-system friendly name, e.g. "dynamics_integrators".
std::string SampleSlug(const SampleEntry& e);

}  // namespace pba::app
