// "Soft bodies/Flag in the wind": an XPBD cloth pinned along its hoist to a pole, in
// gusting wind (pba::Wind: a steady part plus seeded noise gusts), pushed by per-triangle
// aerodynamic drag and lift (the air-relative velocity of each triangle against its
// normal). Arrows show the air's velocity now.
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

constexpr double kPoleTop = 3.3;  // top of the pole (m)

class FlagSample final : public OneBodySample {
 public:
  explicit FlagSample(SampleContext& ctx) : OneBodySample(ctx) {
    // --option wind=M/S gust=M/S drag=CD lift=CL nx=N ny=N solver=xpbd|mass-spring
    def_ = XpbdCloth(12, 0.2);
    def_.bend_compliance = 2e-3;
    view_.strain = false;
    wind_ = OptionNumber(ctx, "wind", wind_, 0, 30);
    def_.forces.wind.gust = OptionNumber(ctx, "gust", 3.0, 0, 20);
    def_.aero.drag = OptionNumber(ctx, "drag", 1.0, 0, 5);
    def_.aero.lift = OptionNumber(ctx, "lift", 0.6, 0, 5);
    nx_ = OptionInteger(ctx, "nx", nx_, 2, 256);
    ny_ = OptionInteger(ctx, "ny", ny_, 2, 256);
    def_.forces.wind.gust_period = 0.45;
    def_.forces.wind.seed = 7;
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.85f, 2.45f, 0.0f}, 1.9f, 0.42f, 0.14f);
    build();
    SolverFromOption();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<FlagSample>(ctx); }

  void Step(double, double dt) override {
    // the panel's wind (heading in the ground plane) applies from the next step
    SoftBodyDef& d = body_.settings();
    const double a = heading_deg_ * pba::kPi / 180;
    def_.forces.wind.velocity = Vec3(wind_ * std::cos(a), 0, wind_ * std::sin(a));
    d = def_;
    body_.step(t_, dt);
    t_ += dt;
    // the wind history for the plot
    hist_.Push(t_, {glm::length(d.forces.wind.at(t_))});
  }

  void Draw(Renderer& r, double) override {
    // the pole and its finial
    r.capsule(Vec3(0, 0, 0), Vec3(0, kPoleTop + 0.05, 0), 0.03, soft_colors::pole);
    r.sphere(Vec3(0, kPoleTop + 0.1, 0), 0.05, Color::hex(0xffc53d));
    // the flag, striped per particle row
    painter_.Draw(r, body_, view_, soft_colors::cloth, stripes_, ctx_.draw);
    // the air's velocity now, on a lattice behind the flag
    const Vec3 w = body_.settings().forces.wind.at(t_);
    DrawWindField(r, w, Vec3(-1.2, 1.4, -1.4), Vec3(3.2, 4.0, -1.4), 5, 4);
    if (ctx_.settings.show_labels) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "wind %.1f m/s", glm::length(w));
      r.text(Vec3(1.0, 4.35, -1.4), buf, particle_colors::wind, 1.0f, 0.5f);
    }
    grab_.Draw(r, Bodies());
    DrawBanner(ctx_, "Drag the flag with the mouse. Gusts are seeded noise: the same every run.");
  }

  void DrawUI() override {
    // wind
    float w = static_cast<float>(wind_), head = static_cast<float>(heading_deg_),
          gust = static_cast<float>(def_.forces.wind.gust), period = static_cast<float>(def_.forces.wind.gust_period);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("wind", &w, 0.0f, 20.0f, "%.1f m/s")) wind_ = w;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("heading", &head, -60.0f, 60.0f, "%.0f deg")) heading_deg_ = head;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("gusts", &gust, 0.0f, 10.0f, "+- %.1f m/s")) def_.forces.wind.gust = gust;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("gust period", &period, 0.1f, 3.0f, "%.2f s")) def_.forces.wind.gust_period = period;
    // aerodynamics
    float cd = static_cast<float>(def_.aero.drag), cl = static_cast<float>(def_.aero.lift);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("drag C_d", &cd, 0.0f, 3.0f, "%.2f")) def_.aero.drag = cd;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("lift C_l", &cl, 0.0f, 3.0f, "%.2f")) def_.aero.lift = cl;
    // solver and cloth
    SolverRows();
    if (ImGui::Button("Restart flag")) build();
    ViewRows();

    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "wind speed (m/s)";
    ax.y_include_zero = true;
    ax.y_min_span = 2;
    hist_.Plot("wind", std::span<const Color>(&particle_colors::wind, 1), ax, 90);
    ImGui::TextWrapped(
        "Each triangle of area A and normal n moving at u = v - wind through the air feels drag "
        "-1/2 rho C_d A |u| (u.n) n and lift across the flow, a third to each corner. A flag edge-on to "
        "the wind feels little; a flap that turns into it is pushed back, so the flag flutters.");
  }

  std::vector<Color> ExpectedColors() const override { return {particle_colors::wind}; }

 private:
  // the flag: nx x ny particles hanging off the pole, hoist pinned, in three bands
  void build() {
    Restart();
    hist_.Clear();
    ClothDef c;
    c.origin = Vec3(0.04, kPoleTop, 0);
    c.edge_u = Vec3(1.5, 0, 0);
    c.edge_v = Vec3(0, -1.0, 0);
    c.nx = nx_, c.ny = ny_;
    c.mass = 0.25;
    c.pins = ClothPins::FirstColumn;
    body_ = SoftBody::cloth_grid(c, def_);
    stripes_.resize(body_.size());
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const double v = static_cast<double>(j) / (ny_ - 1);
        stripes_[static_cast<std::size_t>(j * nx_ + i)] =
            v < 0.34 ? soft_colors::cloth : (v < 0.66 ? Color::hex(0xe9ecef) : Color::hex(0xf76b15));
      }
  }

  std::vector<Color> stripes_;
  PlotHistory hist_{1, 6.0};  // wind speed over the last 6 s
  int nx_ = 36, ny_ = 24;
  double wind_ = 6.0, heading_deg_ = 15;
};

static int reg = RegisterSample("Soft bodies", "Flag in the wind", FlagSample::Create);

}  // namespace
}  // namespace pba::app
