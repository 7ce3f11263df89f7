// The rigid-body samples' shared base: a RigidBodySystem stepped once per tick, drawn through
// the library (sleeping bodies faded, View menu flags), the mouse grab (press on a body and
// drag it; release throws it), the solver controls and the profile readout.
#pragma once

#include <string>
#include <vector>

#include "pba/rigid.h"
#include "sample.h"

namespace pba::app {

/// The solver named by --option solver=soft|si|tgs|xpbd, or by its library name
/// (soft-step, sequential-impulse...); the default: soft. Throws Error for another value.
RigidSolverType RigidSolverOption(const SampleContext& ctx);

/// The solver combo and the chosen solver's own knobs (substeps, contact Hz, iterations,
/// relax, compliance, manifold sweeps, warm starting, the soft step's auto substeps and its
/// halving's sag budget), editing
/// `s` live; `in_use` (when > 0) is shown as the substeps the last step took
/// (RigidProfile::substeps). Moving the substeps slider turns auto_substeps off.
void RigidSolverKnobs(ContactSettings& s, int in_use = 0);

/// The mouse on rigid bodies: a press grabs the dynamic body whose shape the cursor's ray
/// hits first, a 3 Hz critically damped spring (Box2D's mouse joint as a force, scaled by
/// the body's mass and capped at 50 times its weight) pulls the grabbed point toward the
/// cursor at the grabbed depth, a release lets go (the body keeps its velocity: thrown).
class RigidGrab {
 public:
  /// A left press with the world ray (o, d): grabs and wakes the body of `bodies` whose shape
  /// the ray hits first, closer than `max_distance` (m), when it is dynamic (a static or
  /// kinematic shape in front hides the bodies behind it); true when one was grabbed.
  bool Press(RigidBodySystem& bodies, const Vec3& o, const Vec3& d, double max_distance = 1000);
  /// Lets go.
  void Release() { grab_ = {}; }
  /// The cursor moved: the target follows the ray at the grabbed depth.
  void Move(const RigidBodySystem& bodies, const Vec3& o, const Vec3& d);
  /// Applies the spring's force for the next step.
  void Apply(RigidBodySystem& bodies) const;
  /// The spring as a yellow line to the cursor's point.
  void Draw(Renderer& r, const RigidBodySystem& bodies) const;
  /// True while a body of `bodies` is held.
  bool held(const RigidBodySystem& bodies) const { return bodies.valid(grab_.body); }
  /// Presses that grabbed a body so far.
  int grabs() const { return grabs_; }

 private:
  struct Grab {
    RigidBodyId body{};
    Vec3 local{0, 0, 0};   // anchor in the body frame (m)
    Vec3 target{0, 0, 0};  // where the cursor holds it (m)
    double depth = 0;      // distance along the view ray (m)
  } grab_;
  int grabs_ = 0;
};

/// The test hook of the rigid samples (--option report=FILE): writes "frame F grabs G held H
/// body X Y Z pixel PX PY velocity VX VY VZ" for the centre and velocity of body `id` (its
/// pixel from the renderer's last view), then `extra`, as one line, whole (a reader never
/// sees half a line). Nothing when `path` is empty or `id` is not a body of `bodies`.
void WriteRigidReport(const std::string& path, const Renderer& r, long long frame, const RigidBodySystem& bodies,
                      RigidBodyId id, const RigidGrab& grab, const std::string& extra = {});

/// Base of the rigid-body samples: override Build() to fill bodies_ (Restart calls it again).
class RigidSample : public Sample {
 public:
  explicit RigidSample(SampleContext& ctx);

  /// The mouse spring, then one step of the bodies, then AfterStep().
  void Step(double t, double dt) override;
  /// False: the bodies integrate with their solver, not the panel's integrator.
  bool UsesIntegrator() const override { return false; }
  /// The bodies (library drawing) and the mouse spring.
  void Draw(Renderer& r, double alpha) override;
  /// Left press: grabs the dynamic body under the cursor; release: lets it go (thrown).
  void Mouse(int button, bool down, const Vec3& ray_origin, const Vec3& ray_dir) override;
  /// Moves the grab target along the view ray, at the grabbed depth.
  void MouseMove(const Vec3& ray_origin, const Vec3& ray_dir) override;
  /// True while a body is held.
  bool MouseCaptured() const override { return grab_.held(bodies_); }
  /// A dynamic body whose centre is not finite.
  FiniteCheck CheckFinite() const override;
  /// The dynamic bodies' centres.
  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override;

 protected:
  /// Fills bodies_ (already reset, with settings_) and frames the camera.
  virtual void Build() = 0;
  /// Called after each step (measurements, spawning).
  virtual void AfterStep(double t, double dt) { (void)t, (void)dt; }
  /// Clears the bodies and calls Build().
  void Restart();
  /// Solver, substeps or iterations, sleeping and a Restart button; true when Restart was pressed.
  bool SolverControls();
  /// Bodies, awake, manifolds and the step's time split.
  void Readout() const;
  /// The body --option report=FILE describes (default: the first dynamic body).
  virtual RigidBodyId ReportBody() const;
  /// Text appended to the report line (default: none).
  virtual std::string ReportExtra() const { return {}; }

  RigidBodySystem bodies_;
  ContactSettings settings_{};       ///< applied before every step (the controls edit it)
  Vec3 gravity_{0, -9.81, 0};        ///< m/s^2
  RigidDrawOptions draw_options_{};  ///< colours (palette_ is attached each frame)
  std::vector<Color> palette_;       ///< dynamic bodies' colours, cycled by index

 private:
  RigidGrab grab_;
  // the test hook (--option report=FILE): every 5 frames the frame, the grabs so far, the
  // report body's centre (world and pixels) and velocity, and the tick length (dt, s)
  std::string report_path_;
  long long frames_ = 0;
};

}  // namespace pba::app
