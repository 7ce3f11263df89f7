// "Rigid bodies/Solver lab" (workbook chapter 6): the shared rigid scenes (vertical stack,
// square pyramid, falling boxes, restitution row, friction ramp) under any of the four contact
// solvers, switched live: the soft step (Box2D v3's substeps, soft contacts, relax and
// restitution passes), sequential impulses, TGS (substeps of rigid contacts, Macklin et al.
// 2019) or XPBD (positional contacts, Mueller et al. 2020). The panel plots the top box's sag
// and drift, the deepest overlap and the kinetic energy, and shows where the step's time went.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
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

enum class LabScene : int { Stack, Pyramid, Falling, Restitution, Ramp };
constexpr const char* kSceneNames[] = {"vertical stack", "square pyramid", "falling boxes", "restitution row",
                                       "friction ramp"};

class RigidLab final : public Sample {
 public:
  explicit RigidLab(SampleContext& ctx) : Sample(ctx) {
    // --option scene=stack|pyramid|falling|restitution|ramp size=N solver=soft|si|tgs|xpbd
    // (or the solvers' library names: soft-step, sequential-impulse)
    const std::string scene = ctx.option("scene", "stack");
    const char* keys[] = {"stack", "pyramid", "falling", "restitution", "ramp"};
    scene_ = LabScene::Stack;
    bool found = false;
    for (int i = 0; i < 5; ++i)
      if (scene == keys[i]) scene_ = static_cast<LabScene>(i), found = true;
    if (!found) throw Error("--option scene: expected stack, pyramid, falling, restitution or ramp, got '" + scene + "'");
    settings_.solver = RigidSolverOption(ctx);
    size_ = static_cast<int>(OptionNumber(ctx, "size", 10, 1, 40));
    ctx.settings.stepper.fixed_dt = 1.0 / 60.0;
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<RigidLab>(ctx); }

  void Step(double, double dt) override {
    bodies_.settings() = settings_;
    bodies_.step(dt, {0, -9.81, 0});
    record();
  }

  void Draw(Renderer& r, double) override {
    // the bodies through the library (View menu: shapes, bounds, contacts, normals)
    RigidDrawOptions o;
    o.palette = kPalette;
    o.fixed = kStatic;
    o.highlight = top_;
    o.highlight_color = kTop;
    o.horizontal_planes = false;  // the app's ground grid
    bodies_.draw(r, ctx_.draw, o);
    // a marker ball above the measured body (its flat faces take one shade each, which may
    // never be the colour itself; a lit ball always shows it somewhere)
    if (bodies_.valid(top_)) r.sphere(bodies_.center_of_mass(top_) + Vec3(0, 0.9, 0), 0.3, kTop);
  }

  void DrawUI() override {
    int scene = static_cast<int>(scene_);
    ImGui::SetNextItemWidth(-110);
    bool rebuild = ImGui::Combo("scene", &scene, kSceneNames, 5);
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("size", &size_, 1, 40);
    RigidSolverKnobs(settings_);
    if (ImGui::Button("Restart") || rebuild) {
      scene_ = static_cast<LabScene>(scene);
      build();
    }

    // live measurements
    const RigidProfile& p = bodies_.profile();
    ImGui::Text("%zu bodies, %zu manifolds", bodies_.size(), bodies_.manifold_count());
    ImGui::Text("step %.2f ms: pairs+manifolds %.2f, solve %.2f", 1e3 * p.total, 1e3 * p.collide, 1e3 * p.solve);
    if (!t_.empty()) {
      ImGui::Text("top: sag %.1f mm, drift %.1f mm; deepest overlap %.1f mm", 1e3 * sag_.back(), 1e3 * drift_.back(),
                  1e3 * depth_.back());
      PlotAxes ax;
      ax.x_label = "t (s)";
      ax.y_label = "mm";
      std::vector<PlotSeries> series{Series(t_.data(), sag_mm_.data(), static_cast<int>(t_.size()), kTop, 2.0f),
                                     Series(t_.data(), drift_mm_.data(), static_cast<int>(t_.size()), colors::green, 1.5f),
                                     Series(t_.data(), depth_mm_.data(), static_cast<int>(t_.size()), colors::red, 1.5f)};
      LinePlot("sag", series, ax, 130);
      ImGui::TextColored(ImVec4(kTop.r, kTop.g, kTop.b, 1), "sag");
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(0.27f, 0.65f, 0.35f, 1), "drift");
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(0.9f, 0.28f, 0.3f, 1), "deepest overlap");
      PlotAxes ae;
      ae.x_label = "t (s)";
      ae.y_label = "J";
      std::vector<PlotSeries> energy{Series(t_.data(), energy_.data(), static_cast<int>(t_.size()), colors::purple, 1.5f)};
      LinePlot("energy", energy, ae, 90);
    }
    ImGui::TextWrapped(
        "The yellow body is the one the sag and drift are measured on (the top of a stack or pyramid). Soft step: "
        "contacts are implicit springs of 'contact Hz', solved once with position bias and once without (relax) "
        "per substep; a stack sags about n^2 g / (2 pi f)^2. Sequential impulses: one step, rigid contacts "
        "iterated, overlap removed by Baumgarte bias: tall stacks fall. TGS: the soft step's substeps with rigid "
        "contacts, biased by the separation at each substep's poses. XPBD: per substep, free motion, then "
        "contacts and static friction as position constraints, velocities from the positions, and a velocity "
        "pass for dynamic friction and restitution. View > contacts and normals show the manifolds (red "
        "overlapping, green speculative).");
  }

  std::vector<Color> ExpectedColors() const override {
    // the measured body's yellow marker; among a thousand falling boxes it may be hidden
    return {scene_ == LabScene::Falling ? kBox : kTop};
  }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    for (std::size_t i = 0; i < bodies_.size() && out.size() < max_points; ++i)
      if (bodies_.type(bodies_.id_at(i)) == BodyType::Dynamic) out.push_back(bodies_.center_of_mass(bodies_.id_at(i)));
  }

  FiniteCheck CheckFinite() const override {
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const RigidBodyId id = bodies_.id_at(i);
      if (bodies_.type(id) != BodyType::Dynamic) continue;
      const Vec3 p = bodies_.center_of_mass(id);
      if (!is_finite(p)) return {false, id.index, "rigid body " + std::to_string(id.index) + " is not finite"};
    }
    return {};
  }

 private:
  void build() {
    bodies_ = RigidBodySystem({.capacity = 4096, .contacts = settings_});
    std::vector<RigidBodyId> dyn;
    float radius = 6;
    switch (scene_) {
      case LabScene::Stack: dyn = rigid_scenes::vertical_stack(bodies_, size_); radius = 0.6f * size_ + 2; break;
      case LabScene::Pyramid: dyn = rigid_scenes::square_pyramid(bodies_, size_); radius = 0.9f * size_ + 2; break;
      case LabScene::Falling: dyn = rigid_scenes::falling_boxes(bodies_, std::min(size_, 12)); radius = 12; break;
      case LabScene::Restitution: dyn = rigid_scenes::restitution_row(bodies_, std::max(2, std::min(size_, 12))); radius = 4; break;
      case LabScene::Ramp: dyn = rigid_scenes::friction_ramp(bodies_, 0.3805, std::max(1, std::min(size_, 8))); radius = 5; break;
    }
    top_ = dyn.empty() ? RigidBodyId{} : dyn.back();
    // sag and drift are measured from the touching stack, before the gaps
    top0_ = bodies_.valid(top_) ? bodies_.center_of_mass(top_) : Vec3(0);
    // stacks and pyramids start with 2 cm between layers, so they are seen to settle
    if (scene_ == LabScene::Stack || scene_ == LabScene::Pyramid)
      for (const RigidBodyId id : dyn) {
        Pose p = bodies_.pose(id);
        p.position.y += 0.02 * std::floor(p.position.y);
        bodies_.set_pose(id, p);
      }
    const float cy = scene_ == LabScene::Stack || scene_ == LabScene::Pyramid ? 0.45f * size_ : 1.5f;
    ctx_.camera->frame({0.0f, cy, 0.0f}, radius, 0.5f, 0.3f);
    t_.clear(), sag_.clear(), drift_.clear(), depth_.clear(), energy_.clear();
    sag_mm_.clear(), drift_mm_.clear(), depth_mm_.clear();
  }

  void record() {
    if (!bodies_.valid(top_)) return;
    const Vec3 p = bodies_.center_of_mass(top_);
    double deepest = 0, energy = 0;
    for (const RigidContactPoint& c : bodies_.contacts()) deepest = std::max(deepest, c.depth);
    for (std::size_t i = 0; i < bodies_.size(); ++i) energy += bodies_.kinetic_energy(bodies_.id_at(i));
    t_.push_back(static_cast<float>(bodies_.time()));
    sag_.push_back(top0_.y - p.y);
    drift_.push_back(std::hypot(p.x - top0_.x, p.z - top0_.z));
    depth_.push_back(deepest);
    energy_.push_back(static_cast<float>(energy));
    sag_mm_.push_back(static_cast<float>(1e3 * sag_.back()));
    drift_mm_.push_back(static_cast<float>(1e3 * drift_.back()));
    depth_mm_.push_back(static_cast<float>(1e3 * deepest));
    // keep the last 30 s
    if (t_.size() > 1800)
      for (auto* v : {&t_, &energy_, &sag_mm_, &drift_mm_, &depth_mm_}) v->erase(v->begin());
    if (sag_.size() > 1800)
      for (auto* v : {&sag_, &drift_, &depth_}) v->erase(v->begin());
  }

  RigidBodySystem bodies_;
  ContactSettings settings_{};
  LabScene scene_ = LabScene::Stack;
  int size_ = 10;
  RigidBodyId top_{};
  Vec3 top0_{0, 0, 0};
  std::vector<float> t_, energy_, sag_mm_, drift_mm_, depth_mm_;
  std::vector<double> sag_, drift_, depth_;
};

const int kRegistered = RegisterSample("Rigid bodies", "Solver lab", RigidLab::Create);

}  // namespace
}  // namespace pba::app
