// "Soft bodies/Jelly cube": a cube of tetrahedra (a lattice, six tets per cell) with a
// compliant distance constraint on every tet edge and a volume constraint per tet (XPBD,
// Macklin, Mueller & Chentanez 2016), dropped tumbling onto the ground: it lands, bounces
// and wobbles. The panel reads its volume as a percentage of the rest volume.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"
#include "soft_common.h"

namespace pba::app {
namespace {

class JellySample final : public OneBodySample {
 public:
  explicit JellySample(SampleContext& ctx) : OneBodySample(ctx) {
    // --option compliance=M/N volume=M5/N cells=N height=M solver=xpbd|mass-spring
    def_.stretch_compliance = OptionNumber(ctx, "compliance", 3e-3, 0, 1);
    def_.volume_compliance = OptionNumber(ctx, "volume", 1e-6, 0, 1);
    cells_ = static_cast<int>(OptionNumber(ctx, "cells", cells_, 1, 16));
    height_ = OptionNumber(ctx, "height", height_, 0.5, 5);
    def_.solver = SoftSolver::XPBD;
    def_.substeps = 15;
    def_.iterations = 1;
    def_.friction = 0.6;
    def_.thickness = 0.005;
    view_.strain = false;
    ctx.renderer->style.grid_spacing = 0.25f;
    ctx.camera->frame({0.0f, 0.5f, -0.2f}, 1.6f, 0.6f, 0.25f);
    build();
    SolverFromOption();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<JellySample>(ctx); }

  void Step(double, double dt) override {
    if (auto_drop_ && t_ >= 6.0 && !grab_.held()) build();
    body_.settings() = def_;
    body_.step(t_, dt, colliders_);
    t_ += dt;
    // the volume history
    volume_ = body_.volume() / body_.rest_volume();
    hist_.Push(t_, {100 * volume_});
  }

  void Draw(Renderer& r, double) override {
    painter_.Draw(r, body_, view_, soft_colors::jelly);
    const Vec3 c = body_.center_of_mass();
    r.shadow(Vec3(c.x, std::max(c.y, 0.0), c.z), 0.35);
    grab_.Draw(r, Bodies());
    if (ctx_.settings.show_labels) {
      char buf[48];
      std::snprintf(buf, sizeof buf, "volume %.1f %%", 100 * volume_);
      r.text(c + Vec3(0, 0.45, 0), buf, colors::white, 1.0f, 0.5f);
    }
    DrawBanner(ctx_, "Grab the jelly with the mouse and throw it.");
  }

  void DrawUI() override {
    SolverRows();
    float mu = static_cast<float>(def_.friction);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("friction", &mu, 0.0f, 1.5f, "%.2f")) def_.friction = mu;
    bool rebuild = false;
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("cells per side", &cells_, 1, 8);
    float h = static_cast<float>(height_);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("drop height", &h, 0.5f, 3.0f, "%.2f m")) {
      height_ = h;
      rebuild = true;
    }
    if (ImGui::Button("Drop again") || rebuild) build();
    ImGui::SameLine();
    ImGui::Checkbox("every 6 s", &auto_drop_);
    ViewControls(view_);
    ImGui::Text("volume: %.2f %% of rest", 100 * volume_);
    SoftReadout(body_);
    ImGui::Text("%zu particles, %zu tets, %zu edges", body_.size(), body_.tets().size(), body_.constraint_count());
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "volume (% of rest)";
    ax.y_min_span = 2;
    hist_.Plot("volume", std::span<const Color>(&soft_colors::jelly, 1), ax, 100);
    ImGui::TextWrapped(
        "Edge constraints give the jelly its shape and springiness; a volume constraint C = V - V0 on every "
        "tetrahedron keeps it from squashing flat (Macklin et al. 2016). Soften the edges and it wobbles more; "
        "make the volumes compliant too and it sags.");
  }

  std::vector<Color> ExpectedColors() const override { return {colors::white}; }

 private:
  // a tilted cube above the ground, and the ground
  void build() {
    Restart();
    hist_.Clear();
    JellyDef j;
    j.center = Vec3(0, height_, 0);
    j.size = Vec3(0.5);
    j.rotation = glm::angleAxis(0.6, glm::normalize(Vec3(1, 0.3, 0.8)));
    j.nx = j.ny = j.nz = cells_;
    j.mass = 1.0;
    body_ = SoftBody::jelly_box(j, def_);
    volume_ = 1;
    colliders_ = {Collider::plane(Vec3(0, 1, 0), 0)};
  }

  std::vector<Collider> colliders_;
  PlotHistory hist_{1, 6.0};  // volume (% of rest) over the last 6 s
  int cells_ = 4;
  double height_ = 1.4, volume_ = 1;
  bool auto_drop_ = true;
};

static int reg = RegisterSample("Soft bodies", "Jelly cube", JellySample::Create);

}  // namespace
}  // namespace pba::app
