// "Rigid bodies/Solver lab" (workbook chapter 6): the shared rigid scenes (vertical stack,
// square pyramid, falling boxes, restitution row, friction ramp) under any of the four contact
// solvers, switched live: the soft step (Box2D v3's substeps, soft contacts, relax and
// restitution passes), sequential impulses, TGS (substeps of rigid contacts, Macklin et al.
// 2019) or XPBD (positional contacts, Mueller et al. 2020). The panel plots the top box's sag
// and drift, the deepest overlap, the kinetic energy and the ms per step, and shows where the
// step's time went. "Compare the four solvers" runs the scene once per solver, side by side at
// an equal budget of contact passes per step, and plots the four together.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "offset_draw.h"
#include "particles_common.h"
#include "pba/rigid_scenes.h"
#include "plot.h"
#include "renderer.h"
#include "rigid_common.h"
#include "sample.h"

namespace pba::app {
namespace {

constexpr Color kBox = colors::blue;
constexpr Color kTop = colors::yellow;
constexpr Color kStatic = colors::grey;
constexpr Color kPalette[] = {colors::blue, colors::cyan, colors::purple, colors::pink, colors::green};

// the friction ramp's slope (rad): tan = 0.40, between the boxes' mu of 0.3 and 0.5
constexpr double kRampAngle = 0.3805;

enum class LabScene : int { Stack, Pyramid, Falling, Restitution, Ramp };
constexpr const char* kSceneNames[] = {"vertical stack", "square pyramid", "falling boxes", "restitution row",
                                       "friction ramp"};

// the colour that stands for each solver in the compare mode's plots and labels
constexpr Color kSolverColor[] = {colors::orange, colors::red, colors::green, colors::purple};
// and its short name above its copy of the scene
constexpr const char* kShortName[] = {"soft", "SI", "TGS", "XPBD"};

class RigidLab final : public Sample {
 public:
  explicit RigidLab(SampleContext& ctx) : Sample(ctx) {
    // --option scene=stack|pyramid|falling|restitution|ramp size=N solver=soft|si|tgs|xpbd
    // (or the solvers' library names: soft-step, sequential-impulse) compare=0|1 (the four
    // solvers side by side) passes=N (their equal budget) sleep=0|1 halve_sag_percent=P and
    // halve_sag_mm=MM (the soft step's halving of the substeps: budgets of 0-100% of a body's
    // size, 2 by default, and 0-20 mm, 0 by default; each 0: none)
    const std::string scene = ctx.option("scene", "stack");
    const char* keys[] = {"stack", "pyramid", "falling", "restitution", "ramp"};
    scene_ = LabScene::Stack;
    bool found = false;
    for (int i = 0; i < 5; ++i)
      if (scene == keys[i]) scene_ = static_cast<LabScene>(i), found = true;
    if (!found) throw Error("--option scene: expected stack, pyramid, falling, restitution or ramp, got '" + scene + "'");
    settings_.solver = RigidSolverOption(ctx);
    // the soft step's halving of the substeps where the bodies allow it: its sag budgets, a
    // percentage of each body's size (ContactSettings::auto_substeps_sag_fraction, 2 by
    // default) and mm (auto_substeps_sag; 0, the default: none); both 0: never halved
    settings_.auto_substeps_sag_fraction =
        0.01 * OptionNumber(ctx, "halve_sag_percent", 100 * ContactSettings{}.auto_substeps_sag_fraction, 0, 100);
    settings_.auto_substeps_sag = 1e-3 * OptionNumber(ctx, "halve_sag_mm", 0, 0, 20);
    size_ = OptionInteger(ctx, "size", 10, 1, 40);
    compare_ = OptionFlag(ctx, "compare", false);
    // compared, the copies stay awake by default (a sleeping stack shows nothing)
    settings_.sleep = OptionFlag(ctx, "sleep", !compare_);
    passes_ = OptionInteger(ctx, "passes", 16, 2, 128);
    // the compare mode runs the four solvers at one budget, the single mode one solver at its
    // own settings: an option of the other mode would be silently ignored, so it is refused
    if (compare_ && ctx.options.count("solver"))
      throw Error("--option solver=" + ctx.options.at("solver") +
                  ": the compare mode (compare=1) runs all four solvers; leave solver out or set compare=0");
    if (!compare_ && ctx.options.count("passes"))
      throw Error("--option passes=" + ctx.options.at("passes") +
                  ": the four solvers' equal budget, used only by the compare mode; add --option compare=1");
    ctx.settings.stepper.fixed_dt = 1.0 / 60.0;
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<RigidLab>(ctx); }
  bool UsesIntegrator() const override { return false; }  // the solvers integrate

  void Step(double, double dt) override {
    for (std::size_t k = 0; k < lanes_.size(); ++k) {
      Lane& l = lanes_[k];
      l.bodies.settings() = lane_settings(k);
      l.bodies.step(dt, {0, -9.81, 0});
      record(l);
    }
  }

  void Draw(Renderer& r, double) override {
    for (std::size_t k = 0; k < lanes_.size(); ++k) {
      const Lane& l = lanes_[k];
      OffsetDraw d(r, offset(k));
      // the bodies through the library (View menu: shapes, bounds, contacts, normals)
      RigidDrawOptions o;
      o.palette = kPalette;
      o.fixed = kStatic;
      o.highlight = l.top;
      o.highlight_color = kTop;
      o.horizontal_planes = false;  // the app's ground grid
      // compared, each ramp is drawn as wide as its copy's lane
      if (compare_ && along_z()) o.plane_half_size = 0.5 * spacing_;
      l.bodies.draw(d, ctx_.draw, o);
      // a marker ball above the measured body (its flat faces take one shade each, which may
      // never be the colour itself; a lit ball always shows it somewhere)
      // (not in the ramp and the row, whose bodies are labelled: the measured one's label takes
      // the marker's colour instead, as a ball over a ball would read as one more ball)
      if (l.bodies.valid(l.top) && l.labelled.empty()) d.sphere(l.bodies.center_of_mass(l.top) + Vec3(0, 0.9, 0), 0.3, kTop);
      // the ramp's boxes and the row's balls carry their coefficient ("mu=0.30", "e=0.40"),
      // and the scene its closed form, so the picture says which should stick or how high
      // each should rise
      for (std::size_t i = 0; i < l.labelled.size(); ++i) {
        const RigidBodyId id = l.labelled[i];
        if (!l.bodies.valid(id)) continue;
        const std::string& name = l.bodies.name(id);
        const std::size_t space = name.find(' ');
        // every other label a little higher, so that neighbours' labels do not run together
        r.text(offset(k) + l.bodies.center_of_mass(id) + Vec3(0, i % 2 ? 0.75 : 0.45, 0),
               space == std::string::npos ? std::string_view(name) : std::string_view(name).substr(space + 1),
               id == l.top ? kTop : Color{0.92f, 0.93f, 0.96f, 1}, 0.8f, 0.5f);
      }
      // (compared, over the middle of the copies, above their solvers' names)
      const Vec3 title_at = compare_ ? Vec3(0, 4.6, 0) : offset(k);
      if (k == 0 && scene_ == LabScene::Ramp) {
        char line[128];
        std::snprintf(line, sizeof line, "slope %.1f deg: mu above tan = %.2f sticks, below it slides at g (sin - mu cos)",
                      kRampAngle * 180 / kPi, std::tan(kRampAngle));
        r.text(title_at + Vec3(0, 3.2, 0), line, Color{0.92f, 0.93f, 0.96f, 1}, 1.0f, 0.5f);
      }
      if (k == 0 && scene_ == LabScene::Restitution)
        r.text(title_at + Vec3(0, 3.6, 0), "dropped from 2 m: each ball rebounds to e^2 of its drop",
               Color{0.92f, 0.93f, 0.96f, 1}, 1.0f, 0.5f);
      // in the compare mode, each copy's solver written above it
      if (compare_) {
        const double top = l.bodies.valid(l.top) ? l.bodies.center_of_mass(l.top).y + 1.8 : 4.0;
        r.text(offset(k) + Vec3(0, top, 0), kShortName[k], kSolverColor[k], 1.4f, 0.5f);
      }
    }
  }

  void DrawUI() override {
    int scene = static_cast<int>(scene_);
    ImGui::SetNextItemWidth(-110);
    bool rebuild = ImGui::Combo("scene", &scene, kSceneNames, 5);
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("size", &size_, 1, 40);
    rebuild |= ImGui::Checkbox("compare the four solvers", &compare_);
    if (compare_) {
      // the same number of contact passes per step for every solver (docs/rigid-bodies.md)
      ImGui::SetNextItemWidth(-110);
      ImGui::SliderInt("passes", &passes_, 2, 64);
      passes_ = std::max(2, passes_ & ~1);
      ImGui::Checkbox("sleep", &settings_.sleep);
      ImGui::TextWrapped("Equal budget: %d contact passes per step. Soft step and TGS: %d substeps of a biased and a "
                         "relax pass; XPBD: %d substeps of a projection and a velocity pass; sequential impulses: "
                         "%d iterations.",
                         passes_, passes_ / 2, passes_ / 2, passes_);
    } else {
      RigidSolverKnobs(settings_, lanes_.empty() ? 0 : lanes_[0].bodies.profile().substeps);
    }
    if (ImGui::Button("Restart") || rebuild) {
      scene_ = static_cast<LabScene>(scene);
      build();
    }

    // live measurements: one line per copy (the solver's colour is its key in the plots)
    for (std::size_t k = 0; k < lanes_.size(); ++k) {
      const Lane& l = lanes_[k];
      const RigidProfile& p = l.bodies.profile();
      if (compare_) {
        const Color c = kSolverColor[k];
        ImGui::TextColored(ImVec4(c.r, c.g, c.b, 1), "%s", std::string(to_string(kRigidSolvers[k])).c_str());
        ImGui::SameLine();
        ImGui::Text("%.2f ms, %zu awake", 1e3 * p.total, l.bodies.awake_count());
      } else {
        ImGui::Text("%zu bodies, %zu awake, %zu manifolds", l.bodies.size(), l.bodies.awake_count(),
                    l.bodies.manifold_count());
        ImGui::Text("step %.2f ms: pairs+manifolds %.2f, solve %.2f", 1e3 * p.total, 1e3 * p.collide, 1e3 * p.solve);
      }
      if (!l.t.empty())
        ImGui::Text("  top: sag %.1f mm, drift %.1f mm; deepest overlap %.1f mm", l.sag_mm.back(), l.drift_mm.back(),
                    l.depth_mm.back());
    }
    if (!lanes_.empty() && !lanes_[0].t.empty()) {
      // sag starts negative (the layers start 2 cm apart): the fitted range stops at -50 mm
      // (the stacks and pyramids start with 2 cm gaps, their top up to centimetres above its
      // resting height: the axis starts at -2 mm, so the settled millimetres are what it shows)
      plot("sag of the top body (mm)", "mm", &Lane::sag_mm, kTop, 110, -2);
      plot("drift of the top body (mm)", "mm", &Lane::drift_mm, colors::green, 90);
      plot("deepest overlap (mm)", "mm", &Lane::depth_mm, colors::red, 90);
      plot("kinetic energy (J)", "J", &Lane::energy, colors::purple, 90);
      plot("ms per step", "ms", &Lane::ms, colors::cyan, 90);
    }
    ImGui::TextWrapped(
        "The yellow body is the one the sag and drift are measured on (the top of a stack or pyramid). Soft step: "
        "contacts are implicit springs of 'contact Hz', solved once with position bias and once without (relax) "
        "per substep; a stack sags about n^2 g / (2 pi f)^2. Sequential impulses: one step, rigid contacts "
        "iterated, overlap removed by Baumgarte bias: tall stacks fall. TGS: the soft step's substeps with rigid "
        "contacts, biased by the separation at each substep's poses. XPBD: per substep, free motion, then "
        "contacts and static friction as position constraints, velocities from the positions, and a velocity "
        "pass for dynamic friction and restitution. 'Compare the four solvers' runs the same scene under each, "
        "side by side, at the same number of contact passes per step, and plots them together. View > contacts "
        "and normals show the manifolds (red overlapping, green speculative).");
  }

  std::vector<Color> ExpectedColors() const override {
    // the measured body's yellow marker; among a thousand falling boxes it may be hidden
    return {scene_ == LabScene::Falling ? kBox : kTop};
  }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    for (std::size_t k = 0; k < lanes_.size(); ++k) {
      const RigidBodySystem& b = lanes_[k].bodies;
      for (std::size_t i = 0; i < b.size() && out.size() < max_points; ++i)
        if (b.type(b.id_at(i)) == BodyType::Dynamic) out.push_back(b.center_of_mass(b.id_at(i)) + offset(k));
    }
  }

  FiniteCheck CheckFinite() const override {
    for (const Lane& l : lanes_)
      for (std::size_t i = 0; i < l.bodies.size(); ++i) {
        const RigidBodyId id = l.bodies.id_at(i);
        if (l.bodies.type(id) != BodyType::Dynamic) continue;
        const Vec3 p = l.bodies.center_of_mass(id);
        if (!is_finite(p)) return {false, id.index, "rigid body " + std::to_string(id.index) + " is not finite"};
      }
    return {};
  }

 private:
  // one copy of the scene under one solver, with its measurements over time
  struct Lane {
    RigidBodySystem bodies;
    RigidBodyId top{};
    Vec3 top0{0, 0, 0};
    std::vector<RigidBodyId> labelled;  // bodies whose name is written above them (ramp, restitution row)
    std::vector<float> t, energy, sag_mm, drift_mm, depth_mm, ms;
    bool reported = false;  // the 3 s line printed
  };

  // the settings of lane k: the knobs' in the single mode; in the compare mode the knobs'
  // shared contact settings with lane k's solver at the equal budget of passes_ per step
  ContactSettings lane_settings(std::size_t k) const {
    ContactSettings c = settings_;
    if (!compare_) return c;
    c.solver = kRigidSolvers[k];
    c.substeps = passes_ / 2;
    c.auto_substeps = false;  // (the budget is exact)
    c.iterations = passes_;
    c.substep_iterations = 1;
    c.relax_iterations = 1;
    return c;
  }

  // where lane k's copy is drawn: side by side, centred on the origin, along x (stacks,
  // pyramids, falling boxes) or along z (the ramp and the row of balls, which lie along x)
  Vec3 offset(std::size_t k) const {
    if (lanes_.size() < 2) return Vec3(0);
    const double d = (static_cast<double>(k) - 0.5 * (lanes_.size() - 1)) * spacing_;
    return along_z() ? Vec3(0, 0, d) : Vec3(d, 0, 0);
  }
  bool along_z() const { return scene_ == LabScene::Ramp || scene_ == LabScene::Restitution; }

  // one plot of a measurement, a curve per lane (coloured by solver in the compare mode)
  void plot(const char* title, const char* unit, std::vector<float> Lane::*what, Color single, float height,
            float y_clamp_lo = -1e30f) {
    ImGui::TextUnformatted(title);
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = unit;
    ax.y_include_zero = true;
    ax.y_clamp_lo = y_clamp_lo;
    std::vector<PlotSeries> series;
    for (std::size_t k = 0; k < lanes_.size(); ++k) {
      const Lane& l = lanes_[k];
      PlotSeries s = Series(l.t.data(), (l.*what).data(), static_cast<int>(l.t.size()), compare_ ? kSolverColor[k] : single,
                            compare_ ? 1.5f : 2.0f);
      series.push_back(s);
    }
    LinePlot(title, series, ax, height);
  }

  void build() {
    lanes_.clear();
    lanes_.resize(compare_ ? kRigidSolvers.size() : 1);
    float radius = 6;
    for (std::size_t k = 0; k < lanes_.size(); ++k) {
      Lane& l = lanes_[k];
      l.bodies = RigidBodySystem({.capacity = 4096, .contacts = lane_settings(k)});
      std::vector<RigidBodyId> dyn;
      switch (scene_) {
        case LabScene::Stack: dyn = rigid_scenes::vertical_stack(l.bodies, size_); radius = 0.6f * size_ + 2; break;
        case LabScene::Pyramid: dyn = rigid_scenes::square_pyramid(l.bodies, size_); radius = 0.9f * size_ + 2; break;
        case LabScene::Falling: dyn = rigid_scenes::falling_boxes(l.bodies, std::min(size_, 12)); radius = 12; break;
        case LabScene::Restitution:
          dyn = rigid_scenes::restitution_row(l.bodies, std::max(2, std::min(size_, 12)));
          radius = 4;
          break;
        case LabScene::Ramp: dyn = rigid_scenes::friction_ramp(l.bodies, kRampAngle, std::max(1, std::min(size_, 8))); radius = 5; break;
      }
      l.top = dyn.empty() ? RigidBodyId{} : dyn.back();
      // (alone: compared, four rows of labels run together)
      l.labelled = along_z() && !compare_ ? dyn : std::vector<RigidBodyId>{};
      // sag and drift are measured from the touching stack, before the gaps
      l.top0 = l.bodies.valid(l.top) ? l.bodies.center_of_mass(l.top) : Vec3(0);
      // stacks and pyramids start with 2 cm between layers, so they are seen to settle
      if (scene_ == LabScene::Stack || scene_ == LabScene::Pyramid)
        for (const RigidBodyId id : dyn) {
          Pose p = l.bodies.pose(id);
          p.position.y += 0.02 * std::floor(p.position.y);
          l.bodies.set_pose(id, p);
        }
    }
    // the copies stand a scene's width (and a margin) apart
    switch (scene_) {
      case LabScene::Stack: spacing_ = 4; break;
      case LabScene::Pyramid: spacing_ = size_ + 3; break;
      case LabScene::Falling: spacing_ = 1.5 * std::min(size_, 12) + 3; break;
      case LabScene::Restitution: spacing_ = 1.5; break;
      case LabScene::Ramp: spacing_ = 0.9 * std::max(1, std::min(size_, 8)) + 1.5; break;
    }
    const float cy = scene_ == LabScene::Stack || scene_ == LabScene::Pyramid ? 0.45f * size_ : 1.5f;
    const float wide =
        compare_ ? std::max(radius, 0.6f * static_cast<float>(spacing_ * lanes_.size())) : radius;
    // the ramp alone is seen from down the slope, so its row of boxes (along z) spreads across
    // the picture and each box's label stands clear of the next
    // (and its compared copies, which stand along z as its rows do, are seen from there too so
    // that they stand side by side)
    if (scene_ == LabScene::Ramp)
      ctx_.camera->frame({1.5f, 1.0f, 0.0f}, compare_ ? 0.8f * wide : radius - 0.5f, -1.45f, compare_ ? 0.3f : 0.35f);
    else
      ctx_.camera->frame({0.0f, cy, 0.0f}, wide, 0.5f, 0.3f);
  }

  void record(Lane& l) {
    if (!l.bodies.valid(l.top)) return;
    const Vec3 p = l.bodies.center_of_mass(l.top);
    double deepest = 0, energy = 0;
    for (const RigidContactPoint& c : l.bodies.contacts()) deepest = std::max(deepest, c.depth);
    // a sleeping island is not stepped and has no manifolds, so with every body asleep the
    // contacts say nothing; the poses have not moved since, nor has the overlap: hold it (the
    // plot dropped to 0 when a resting stack fell asleep)
    if (l.bodies.awake_count() == 0 && !l.depth_mm.empty()) deepest = 1e-3 * l.depth_mm.back();
    for (std::size_t i = 0; i < l.bodies.size(); ++i) energy += l.bodies.kinetic_energy(l.bodies.id_at(i));
    l.t.push_back(static_cast<float>(l.bodies.time()));
    l.sag_mm.push_back(static_cast<float>(1e3 * (l.top0.y - p.y)));
    l.drift_mm.push_back(static_cast<float>(1e3 * std::hypot(p.x - l.top0.x, p.z - l.top0.z)));
    l.depth_mm.push_back(static_cast<float>(1e3 * deepest));
    l.energy.push_back(static_cast<float>(energy));
    l.ms.push_back(static_cast<float>(1e3 * l.bodies.profile().total));
    // the measurements at 3 s, once, on stdout (for the tests)
    if (!l.reported && l.bodies.time() >= 3 - 1e-9) {
      l.reported = true;
      const std::string_view solver = to_string(l.bodies.settings().solver);
      std::printf("Solver lab: %.*s at t = 3 s: the top's sag %.2f mm, drift %.2f mm; deepest overlap %.2f mm; %zu of %zu "
                  "bodies awake\n",
                  static_cast<int>(solver.size()), solver.data(), l.sag_mm.back(), l.drift_mm.back(), l.depth_mm.back(),
                  l.bodies.awake_count(), l.bodies.size());
      std::fflush(stdout);
    }
    // keep the last 30 s
    if (l.t.size() > 1800)
      for (auto* v : {&l.t, &l.energy, &l.sag_mm, &l.drift_mm, &l.depth_mm, &l.ms}) v->erase(v->begin());
  }

  std::vector<Lane> lanes_;
  ContactSettings settings_{};
  LabScene scene_ = LabScene::Stack;
  int size_ = 10;
  bool compare_ = false;
  int passes_ = 16;      // contact passes per step of every solver in the compare mode
  double spacing_ = 12;  // m between the compare mode's copies
};

const int kRegistered = RegisterSample("Rigid bodies", "Solver lab", RigidLab::Create);

}  // namespace
}  // namespace pba::app
