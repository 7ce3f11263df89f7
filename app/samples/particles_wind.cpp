// "Particles/Wind and drag" (workbook 4.2, exercise 2): the shared scene builder
// pba::scenes::wind_and_drag: a column of light particles of four masses released into
// steady and gusting wind, with linear and quadratic drag switched on and off. Arrows show
// the air's velocity now; each particle trails its last second.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/scene.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

// one colour per mass (the builder gives masses 5, 10, 15 and 20 g)
constexpr std::array<Color, 4> kMassColors = {colors::green, colors::yellow, colors::orange, colors::red};

class WindDrag final : public Sample {
 public:
  explicit WindDrag(SampleContext& ctx) : Sample(ctx) {
    // --option wind=M/S gust=M/S linear=B quadratic=C
    params_.wind.velocity.x = OptionNumber(ctx, "wind", 3, -10, 10);
    params_.wind.gust = OptionNumber(ctx, "gust", 1.5, 0, 6);
    linear_b_ = OptionNumber(ctx, "linear", 0, 0, 0.2);
    use_linear_ = linear_b_ > 0;
    if (!use_linear_) linear_b_ = 0.01;
    quadratic_c_ = OptionNumber(ctx, "quadratic", 0.01, 0, 0.05);
    use_quadratic_ = quadratic_c_ > 0;
    if (!use_quadratic_) quadratic_c_ = 0.01;
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.4f, 1.9f, 0.0f}, 3.7f, 0.0f, 0.3f);
    release();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<WindDrag>(ctx); }

  void Step(double, double dt) override {
    if (auto_release_ && world_.time() >= 7.0) release();
    // the panel's wind and drag apply from the next tick
    Forces& f = world_.particles().forces();
    f.wind = params_.wind;
    f.linear_drag = use_linear_ ? linear_b_ : 0.0;
    f.quadratic_drag = use_quadratic_ ? quadratic_c_ : 0.0;
    TickWorld(world_, ctx_.settings, dt);
    // trails and the wind history
    const ParticleSystem& ps = world_.particles();
    for (std::size_t i = 0; i < ps.size() && i < trails_.size(); ++i) {
      trails_[i].push_back(ps.position(i));
      if (trails_[i].size() > 60) trails_[i].erase(trails_[i].begin());
    }
    const Vec3 w = f.wind.at(world_.time());
    hist_t_.push_back(static_cast<float>(world_.time()));
    hist_wx_.push_back(static_cast<float>(w.x));
    hist_wy_.push_back(static_cast<float>(w.y));
    if (hist_t_.size() > 600) {
      hist_t_.erase(hist_t_.begin()), hist_wx_.erase(hist_wx_.begin()), hist_wy_.erase(hist_wy_.begin());
    }
  }

  void Draw(Renderer& r, double) override {
    const ParticleSystem& ps = world_.particles();
    // the air's velocity now, on a lattice behind the column
    const Vec3 w = ps.forces().wind.at(world_.time());
    DrawWindField(r, w, Vec3(-3.0, 0.6, -0.9), Vec3(3.6, 4.2, -0.9), 6, 4);
    if (ctx_.settings.show_labels) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "wind (%.1f, %.1f, %.1f) m/s", w.x, w.y, w.z);
      r.text(Vec3(0.3, 4.75, -0.9), buf, particle_colors::wind, 1.0f, 0.5f);
    }
    // trails, then the particles coloured by mass (drawn at twice their radius)
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const Color c = mass_color(ps.mass(i));
      if (i < trails_.size()) r.polyline(trails_[i], Color{c.r, c.g, c.b, 0.45f}, 1.5f);
      if (ctx_.draw.particles) r.sphere(ps.position(i), 2 * ps.radius(i), c);
    }
    // the release column
    r.line(Vec3(-3, 0, 0), Vec3(-3, 4.6, 0), Color{1, 1, 1, 0.25f}, 1.0f);
  }

  void DrawUI() override {
    // wind
    float wx = static_cast<float>(params_.wind.velocity.x), gust = static_cast<float>(params_.wind.gust),
          period = static_cast<float>(params_.wind.gust_period);
    ImGui::SetNextItemWidth(-120);
    if (ImGui::SliderFloat("steady wind", &wx, -8.0f, 8.0f, "%.1f m/s")) params_.wind.velocity.x = wx;
    ImGui::SetNextItemWidth(-120);
    if (ImGui::SliderFloat("gusts", &gust, 0.0f, 5.0f, "+- %.1f m/s")) params_.wind.gust = gust;
    ImGui::SetNextItemWidth(-120);
    if (ImGui::SliderFloat("gust period", &period, 0.1f, 3.0f, "%.2f s")) params_.wind.gust_period = period;
    // drag
    ImGui::Checkbox("##lin", &use_linear_);
    ImGui::SameLine();
    ImGui::BeginDisabled(!use_linear_);
    float b = static_cast<float>(linear_b_), c = static_cast<float>(quadratic_c_);
    ImGui::SetNextItemWidth(-120);
    if (ImGui::SliderFloat("linear b", &b, 0.001f, 0.1f, "%.3f kg/s", ImGuiSliderFlags_Logarithmic)) linear_b_ = b;
    ImGui::EndDisabled();
    ImGui::Checkbox("##quad", &use_quadratic_);
    ImGui::SameLine();
    ImGui::BeginDisabled(!use_quadratic_);
    ImGui::SetNextItemWidth(-120);
    if (ImGui::SliderFloat("quadratic c", &c, 0.0002f, 0.05f, "%.4f kg/m", ImGuiSliderFlags_Logarithmic)) quadratic_c_ = c;
    ImGui::EndDisabled();
    if (ImGui::Button("Release again")) release();
    ImGui::SameLine();
    ImGui::Checkbox("every 7 s", &auto_release_);

    // the wind over time
    std::vector<PlotSeries> s;
    if (!hist_t_.empty()) {
      const int n = static_cast<int>(hist_t_.size());
      s.push_back(Series(hist_t_.data(), hist_wx_.data(), n, particle_colors::wind, 2.0f));
      s.push_back(Series(hist_t_.data(), hist_wy_.data(), n, Color{0.6f, 0.6f, 0.65f, 1.0f}, 1.2f));
    }
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "wind x, y (m/s)";
    ax.y_include_zero = true;
    ax.y_min_span = 2;
    LinePlot("wind", s, ax, 110);

    // the legend: terminal speeds per mass in still air
    ImGui::TextUnformatted("mass   terminal fall speed");
    const double g = 9.81;
    for (int k = 0; k < 4; ++k) {
      const double m = 0.005 * (k + 1);
      const double bl = use_linear_ ? linear_b_ : 0, cq = use_quadratic_ ? quadratic_c_ : 0;
      // m g = b v + c v^2
      double vt = 0;
      if (cq > 0) vt = (-bl + std::sqrt(bl * bl + 4 * cq * m * g)) / (2 * cq);
      else if (bl > 0) vt = m * g / bl;
      const Color col = kMassColors[k];
      if (vt > 0)
        ImGui::TextColored(ImVec4(col.r, col.g, col.b, 1), "%2.0f g    %.2f m/s", 1e3 * m, vt);
      else
        ImGui::TextColored(ImVec4(col.r, col.g, col.b, 1), "%2.0f g    none (no drag)", 1e3 * m);
    }
    ImGui::TextWrapped(
        "Drag acts on the velocity relative to the air, F = -(b + c|u|) u with u = v - wind, so the wind carries "
        "the particles along and light ones drift furthest. Gusts are smooth seeded noise on each axis (the same "
        "every run). Without drag the wind has nothing to push on and every particle falls straight down.");
  }

  std::vector<Color> ExpectedColors() const override { return {colors::green, colors::yellow}; }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    WorldPoints(world_, out, max_points);
  }

 private:
  static Color mass_color(double m) {
    const int k = std::clamp(static_cast<int>(std::lround(m / 0.005)) - 1, 0, 3);
    return kMassColors[static_cast<std::size_t>(k)];
  }

  void release() {
    world_ = World(WorldDef{.particles = {.capacity = 128}});
    scenes::WindDragParams p = params_;
    p.linear_drag = use_linear_ ? linear_b_ : 0;
    p.quadratic_drag = use_quadratic_ ? quadratic_c_ : 0;
    scenes::wind_and_drag(world_, p);
    trails_.assign(world_.particles().size(), {});
    hist_t_.clear(), hist_wx_.clear(), hist_wy_.clear();
  }

  scenes::WindDragParams params_;
  bool use_linear_ = false, use_quadratic_ = true, auto_release_ = true;
  double linear_b_ = 0.01, quadratic_c_ = 0.002;
  World world_;
  std::vector<std::vector<Vec3>> trails_;
  std::vector<float> hist_t_, hist_wx_, hist_wy_;
};

static int reg = RegisterSample("Particles", "Wind and drag", WindDrag::Create);

}  // namespace
}  // namespace pba::app
