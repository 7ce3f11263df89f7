// Helpers shared by the soft-body samples (app/samples/soft_*.cpp): drawing a pba::SoftBody
// as a smooth-shaded two-sided surface (with strain tint, edges and pins), grabbing its
// particles with the mouse, the usual panel rows (solver, compliance, view toggles,
// readouts) and the stability estimate of a mass-spring network.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pba/soft.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {

/// Colours shared by the soft-body samples.
namespace soft_colors {
inline constexpr Color cloth = Color::hex(0x3e7bd6);    ///< blue fabric
inline constexpr Color fabric = Color::hex(0xd9763a);   ///< orange fabric (tearable cloth)
inline constexpr Color jelly = Color::hex(0x5cc46a);    ///< green jelly
inline constexpr Color pole = Color::hex(0x9aa0a9);     ///< poles, bars and anchors
inline constexpr Color strain = colors::red;            ///< fully strained
inline constexpr Color grab = colors::yellow;           ///< the grabbed particle and its pull
inline constexpr Color mass_spring = Color::hex(0xe5484d);  ///< the mass-spring lane
inline constexpr Color xpbd = Color::hex(0x46a758);         ///< the XPBD lane
}  // namespace soft_colors

/// What SoftPainter::Draw shows (the panel's view toggles edit it).
struct SoftView {
  bool surface = true;         ///< smooth-shaded triangles, both sides lit
  bool edges = false;          ///< stretch constraints as lines
  bool all_edges = false;      ///< also shear and bend constraints
  bool strain = true;          ///< tint surface and edges from the base colour to red by strain
  double strain_scale = 0.05;  ///< strain (dimensionless, > 0) drawn fully red
  bool pins = true;            ///< pinned particles (orange) and the grabbed one (yellow)
};

/// Draws soft bodies; keeps its scratch buffers between frames (no allocation once warm).
class SoftPainter {
 public:
  /// Draws `body` in `color`, or per particle from `particle_colors` (size() entries) when
  /// given, as `view` says.
  void Draw(Renderer& r, const SoftBody& body, const SoftView& view, Color color,
            std::span<const Color> particle_colors = {});
  /// Draws a surface of `positions` (a copy of a body's, e.g. its last finite state) over
  /// `triangles`, smooth-shaded, tinted by `strain` per particle (same size, or empty).
  void DrawSurface(Renderer& r, std::span<const Vec3f> positions, std::span<const SoftTriangle> triangles,
                   Color color, std::span<const Color> particle_colors, std::span<const float> strain,
                   double strain_scale);
  /// The largest strain |l - l0| / l0 of the intact stretch constraints at each particle
  /// of `body` (computed into the painter's buffer, valid until the next call).
  std::span<const float> ParticleStrain(const SoftBody& body);

 private:
  std::vector<Vec3f> pos_, nrm_;
  std::vector<float> strain_;
};

/// Mouse grabbing of soft-body particles: a left press grabs the particle under the cursor
/// (the nearest to the eye within ~14 pixels of the ray) on any of the bodies, dragging
/// moves it on a camera-facing plane through it, release lets go.
class SoftGrab {
 public:
  /// A left press with the world ray (o, d): tries each body; true when one was grabbed.
  bool Press(std::span<SoftBody* const> bodies, const Camera& camera, const Vec3& o, const Vec3& d);
  /// The cursor moved: the grabbed particle's target follows the ray on the drag plane.
  /// Lets go if the button is no longer down (a release over a panel).
  void Move(std::span<SoftBody* const> bodies, const Vec3& o, const Vec3& d);
  /// Lets go (the particle keeps its velocity).
  void Release(std::span<SoftBody* const> bodies);
  /// Forgets the grab without touching the bodies (they were rebuilt).
  void Reset() { body_ = -1; }
  /// True while a particle is held.
  bool held() const { return body_ >= 0; }
  /// Index of the body held (into the span given to Press), -1 for none.
  int body() const { return body_; }
  /// Where the held particle is pulled to (m).
  const Vec3& target() const { return target_; }
  /// Draws the pull: a line from the particle to the cursor's point and a small sphere.
  void Draw(Renderer& r, std::span<SoftBody* const> bodies) const;

 private:
  int body_ = -1;
  Vec3 target_{0}, plane_n_{0, 0, 1}, offset_{0};
};

/// The solver rows of a soft-body panel: a solver switch, then for XPBD the substeps,
/// iterations and compliances, for a mass-spring network the integrator, substeps,
/// stiffnesses and damping with the explicit stability check omega_max h against the
/// method's limit. Keeps omega_max between frames (recomputed when a stiffness changes).
class SolverPanel {
 public:
  /// Draws the rows for `def` (edited in place), the settings of `body`, stepped every
  /// `dt` seconds. Switching to mass-spring raises the substeps so that omega_max h stays
  /// under 80 % of the integrator's limit. True when something changed.
  bool Draw(SoftBodyDef& def, const SoftBody& body, double dt);

 private:
  double omega_ = -1;               // omega_max for the stiffnesses below, < 0 when stale
  double k_[4] = {-1, -1, -1, -1};  // stretch, shear, bend, volume stiffness it was computed for
  const SoftBody* body_ = nullptr;  // and the body
  std::size_t size_ = 0;            // and its particle count
  void refresh(const SoftBodyDef& def, const SoftBody& body);
};

/// Switches `def` (the settings of `body`, stepped every `dt` s) to a mass-spring network,
/// raising the substeps so that omega_max h stays under 80 % of the integrator's limit
/// (implicit Euler falls back to semi-implicit Euler above 512 particles).
void UseMassSpring(SoftBodyDef& def, const SoftBody& body, double dt);
/// The solver named by --option solver=xpbd|mass-spring, or `fallback`; throws Error
/// naming the option for any other value.
SoftSolver SolverOption(const SampleContext& ctx, SoftSolver fallback);

/// The XPBD settings the cloth samples start from: `substeps` substeps of one iteration,
/// rigid stretch and shear, bend compliance 1e-3 m/N, velocity damping `damping` (1/s).
SoftBodyDef XpbdCloth(int substeps, double damping);

/// A time history for a panel plot: times and `columns` value series over the last `keep`
/// seconds (the oldest quarter is dropped at a time, so trimming is rare).
class PlotHistory {
 public:
  /// `columns` >= 1 series kept for `keep` seconds (> 0).
  explicit PlotHistory(int columns = 1, double keep = 10) : y_(static_cast<std::size_t>(columns)), keep_(keep) {}
  /// Forgets everything.
  void Clear();
  /// Appends the values of every column at time t (s); extra values are ignored.
  void Push(double t, std::initializer_list<double> values);
  /// The times (s).
  const std::vector<float>& t() const { return t_; }
  /// Column k's values.
  const std::vector<float>& column(std::size_t k) const { return y_.at(k); }
  /// Plots every column in its colour of `colors` (same count) with LinePlot.
  void Plot(const char* id, std::span<const Color> colors, const PlotAxes& axes, float height) const;

 private:
  std::vector<float> t_;
  std::vector<std::vector<float>> y_;
  double keep_;
};

/// Base of the soft-body samples that let the mouse grab particles: a left press grabs the
/// particle under the cursor on any of Bodies(), dragging moves it, release lets go.
class SoftSample : public Sample {
 public:
  using Sample::Sample;
  void Mouse(int button, bool down, const Vec3& o, const Vec3& d) override;
  void MouseMove(const Vec3& o, const Vec3& d) override { grab_.Move(Bodies(), o, d); }
  bool MouseCaptured() const override { return grab_.held(); }

 protected:
  /// The bodies the mouse may grab (null entries are skipped).
  virtual std::span<SoftBody* const> Bodies() = 0;
  /// Called after a press grabbed a particle (e.g. the user takes over from a script).
  virtual void Grabbed() {}

  SoftGrab grab_;  ///< the mouse grab
};

/// XPBD substeps and iterations sliders; true when one changed.
bool SubstepControls(SoftBodyDef& def, int max_substeps = 60, int max_iterations = 30);
/// A logarithmic compliance slider from `lo` to `hi` (in `unit`), with a box for 0 (rigid).
bool ComplianceSlider(const char* label, double* alpha, double lo, double hi, const char* unit = "m/N");
/// The view toggles: surface, edges (all), strain colours, pins; with `scale_slider`
/// also the strain drawn fully red.
void ViewControls(SoftView& view, bool scale_slider = true);
/// Readout rows: ms per step by phase, mean and maximum strain, kinetic and potential energy.
void SoftReadout(const SoftBody& body);
/// A line of text centred at the bottom of the 3D view (e.g. help, or a red warning).
void DrawBanner(const SampleContext& ctx, const std::string& text, Color color = colors::white);

/// Base of the samples built around one soft body (the flag, the draped and the tearable
/// cloth, the jelly): the body and its settings, the painter and view, the solver rows and
/// the sample's clock; the mouse grabs that body.
class OneBodySample : public SoftSample {
 public:
  using SoftSample::SoftSample;

 protected:
  std::span<SoftBody* const> Bodies() override {
    one_ = &body_;
    return std::span<SoftBody* const>(&one_, 1);
  }
  /// Honours --option solver=mass-spring (call once the body is built): def_ becomes the
  /// mass-spring settings of body_ (UseMassSpring) and the body takes them.
  void SolverFromOption();
  /// The start of a rebuild: lets go of the grab and restarts the clock.
  void Restart() {
    grab_.Reset();
    t_ = 0;
  }
  /// The solver rows of the panel (SolverPanel) for def_ and body_ at the app's step.
  void SolverRows() { solver_.Draw(def_, body_, ctx_.settings.stepper.fixed_dt); }
  /// The view toggles (with the strain scale slider if `scale_slider`) and the readouts.
  void ViewRows(bool scale_slider = true) {
    ViewControls(view_, scale_slider);
    SoftReadout(body_);
  }

  /// The body's nodes, for the self-test's check that what is simulated is drawn.
  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    const std::size_t step = std::max<std::size_t>(1, body_.size() / std::max<std::size_t>(max_points, 1));
    for (std::size_t k = 0; k < body_.size(); k += step) out.push_back(body_.position(k));
  }

  SoftBodyDef def_;     ///< the settings the panel edits (the body takes them each step)
  SoftBody body_;       ///< the body
  SoftPainter painter_; ///< draws it
  SoftView view_;       ///< what is drawn
  SolverPanel solver_;  ///< the solver rows' state
  double t_ = 0;        ///< time since the last rebuild (s)

 private:
  SoftBody* one_ = nullptr;
};

/// omega h below which an undamped linear spring stays bounded under `m` (Hairer, Lubich &
/// Wanner 2006, ch. I.1; Butcher 2016, sec. 238 for RK4): 0 for explicit Euler (it grows
/// at every h), 2 for semi-implicit Euler and both Verlets, 2 sqrt(2) for RK4, infinity
/// for implicit Euler.
double StabilityLimit(Method m);

/// The highest angular frequency omega_max (rad/s) of `body`'s mass-spring network about
/// its current shape: sqrt of the largest eigenvalue of M^-1 K with K = sum k n n^T over
/// the intact springs (the tension terms dropped) plus k_v g g^T over the tets when the
/// volume stiffness k_v > 0 (g the gradient of a tet's volume), by power iteration from a fixed start
/// vector, so a lower estimate converging from below. Pinned particles are excluded.
/// Explicit integrators need h omega_max below their limit (2 for semi-implicit Euler).
double MaxAngularFrequency(const SoftBody& body, int iterations = 200);
/// The same with the stiffnesses of `def` instead of the body's settings.
double MaxAngularFrequency(const SoftBody& body, const SoftBodyDef& def, int iterations = 200);

}  // namespace pba::app
