// "Particles/Bouncing balls" (workbook 4.2, exercise 3): the shared scene builder
// pba::scenes::bouncing_balls: balls dropped onto a ground plane, a box, a tilted box and a
// paddle on a circular Kinematic path. Restitution and friction change live; the first
// ball's height is plotted against the e^2 h rebound law.
#include <algorithm>
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

constexpr Color kBall = colors::blue;
constexpr Color kTracked = colors::yellow;

class BouncingBalls final : public Sample {
 public:
  explicit BouncingBalls(SampleContext& ctx) : Sample(ctx) {
    // --option restitution=E friction=MU count=N
    params_.restitution = OptionNumber(ctx, "restitution", 0.8, 0, 1);
    params_.friction = OptionNumber(ctx, "friction", 0.2, 0, 2);
    params_.count = OptionInteger(ctx, "count", 8, 1, 100);
    // a short step so the rebound heights follow e^2 h closely (the panel can change it)
    ctx.settings.stepper.fixed_dt = 1.0 / 240.0;
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.0f, 1.0f, 0.0f}, 3.0f, 0.0f, 0.22f);
    drop();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<BouncingBalls>(ctx); }

  void Step(double, double dt) override {
    if (auto_drop_ && world_.time() >= 9.0) drop();
    // surfaces take the panel's restitution and friction between ticks
    for (const char* name : {"ground", "box", "ramp", "paddle"}) {
      const EntityId e = world_.find(name);
      if (!world_.valid(e)) continue;
      world_.collider(e).material = {.restitution = params_.restitution, .friction = params_.friction};
    }
    TickWorld(world_, ctx_.settings, dt);
    record();
  }

  void Draw(Renderer& r, double) override {
    DrawColliders(r, world_.colliders(), {}, ctx_.draw);
    const ParticleSystem& ps = world_.particles();
    const std::size_t tracked = ps.index_of(tracked_);
    // short trails, then the balls
    for (std::size_t i = 0; i < trails_.size(); ++i) {
      const Color c = i == tracked ? kTracked : kBall;
      r.polyline(trails_[i], Color{c.r, c.g, c.b, 0.35f}, 1.5f);
    }
    if (ctx_.draw.particles) {
      for (std::size_t i = 0; i < ps.size(); ++i) r.sphere(ps.position(i), ps.radius(i), i == tracked ? kTracked : kBall);
      // the tracked ball ringed, three radii out in the plane facing the default camera: at
      // 640x360 the ball itself is 2-3 pixels across, and the plot's yellow line beside the
      // scene was what a look for its colour found
      const Vec3 c = ps.position(tracked);
      const double ring = 3 * ps.radius(tracked);
      ring_.clear();
      for (int k = 0; k <= 32; ++k) {
        const double a = 2 * kPi * k / 32;
        ring_.push_back(c + ring * Vec3(std::cos(a), std::sin(a), 0));
      }
      r.polyline(ring_, kTracked, 2.0f);
    }
    // the e^2 h and e^4 h marks beside the tracked ball
    if (ctx_.settings.show_labels) {
      const Vec3 p = ps.position(tracked);
      const double e2 = params_.restitution * params_.restitution;
      for (int k = 1; k <= 2; ++k) {
        const double h = drop_height_ * std::pow(e2, k) + ps.radius(tracked);
        r.line(Vec3(p.x - 0.25, h, 0), Vec3(p.x + 0.25, h, 0), Color{1, 0.77f, 0.24f, 0.7f}, 1.5f);
        r.text(Vec3(p.x + 0.27, h, 0), k == 1 ? "e^2 h" : "e^4 h", Color{1, 0.77f, 0.24f, 0.9f}, 0.9f, 0.0f);
      }
    }
  }

  void DrawUI() override {
    float e = static_cast<float>(params_.restitution), mu = static_cast<float>(params_.friction);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("restitution", &e, 0.0f, 1.0f, "e = %.2f")) params_.restitution = e;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("friction", &mu, 0.0f, 1.5f, "mu = %.2f")) params_.friction = mu;
    int n = params_.count;
    ImGui::SetNextItemWidth(-110);
    bool rebuild = ImGui::SliderInt("balls", &n, 1, 100);
    rebuild |= ImGui::Checkbox("boxes", &params_.boxes);
    ImGui::SameLine();
    rebuild |= ImGui::Checkbox("moving paddle", &params_.moving_paddle);
    if (ImGui::Button("Drop again") || rebuild) {
      params_.count = n;
      drop();
    }
    ImGui::SameLine();
    ImGui::Checkbox("drop every 9 s", &auto_drop_);

    // the tracked ball's height against the rebound law
    const double e2 = params_.restitution * params_.restitution;
    ImGui::Spacing();
    ImGui::TextColored(ImVec4(kTracked.r, kTracked.g, kTracked.b, 1), "yellow ball: height of its bottom (m)");
    std::vector<float> law_x, law2, law4;
    if (!hist_t_.empty()) {
      law_x = {hist_t_.front(), hist_t_.back()};
      law2.assign(2, static_cast<float>(drop_height_ * e2));
      law4.assign(2, static_cast<float>(drop_height_ * e2 * e2));
    }
    std::vector<PlotSeries> series;
    if (!law_x.empty()) {
      series.push_back(Series(law_x.data(), law2.data(), 2, Color{1, 0.77f, 0.24f, 0.45f}, 1.0f));
      series.push_back(Series(law_x.data(), law4.data(), 2, Color{1, 0.77f, 0.24f, 0.3f}, 1.0f));
      series.push_back(Series(hist_t_.data(), hist_h_.data(), static_cast<int>(hist_t_.size()), kTracked, 2.0f));
    }
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "height (m)";
    ax.y_lo = 0;
    ax.y_hi = static_cast<float>(drop_height_ * 1.1);
    LinePlot("height", series, ax, 150);
    ImGui::Text("drop h = %.3f m, e^2 h = %.3f m", drop_height_, drop_height_ * e2);
    if (!peaks_.empty()) {
      std::string s;
      char buf[48];
      for (std::size_t k = 0; k < std::min<std::size_t>(peaks_.size(), 3); ++k) {
        std::snprintf(buf, sizeof buf, "%s%.3f", k ? ", " : "", peaks_[k] / drop_height_);
        s += buf;
      }
      ImGui::Text("rebounds / h: %s  (e^2 = %.3f)", s.c_str(), e2);
    }
    ImGui::Text("contacts this step: %zu", world_.particles().contacts());
    ImGui::TextWrapped(
        "Each bounce keeps e of the normal speed, so a ball dropped from h rises to e^2 h (the dashes), then e^4 h. "
        "Friction takes tangential speed at each contact: watch balls on the ramp. The purple paddle is a box "
        "collider driven by a Kinematic on a circle; collisions are swept, so it cannot pass through a ball.");
  }

  std::vector<Color> ExpectedColors() const override { return {kBall, kTracked}; }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    WorldPoints(world_, out, max_points);
  }

 private:
  void drop() {
    world_ = World(WorldDef{.particles = {.capacity = 128}});
    scenes::bouncing_balls(world_, params_);
    tracked_ = world_.particle(world_.find("ball 0"));
    const ParticleSystem& ps = world_.particles();
    drop_height_ = ps.position(tracked_).y - ps.radius(ps.index_of(tracked_));
    trails_.assign(ps.size(), {});
    hist_t_.clear(), hist_h_.clear(), peaks_.clear();
    rising_ = false;
    last_vy_ = 0;
  }

  // trails, the tracked ball's height and its rebound peaks
  void record() {
    const ParticleSystem& ps = world_.particles();
    const std::size_t keep = 45;
    for (std::size_t i = 0; i < ps.size() && i < trails_.size(); ++i) {
      auto& t = trails_[i];
      t.push_back(ps.position(i));
      if (t.size() > keep) t.erase(t.begin());
    }
    const std::size_t k = ps.index_of(tracked_);
    const double h = ps.position(k).y - ps.radius(k), vy = ps.velocity(k).y;
    hist_t_.push_back(static_cast<float>(world_.time()));
    hist_h_.push_back(static_cast<float>(h));
    // a rebound peak: rising, then the vertical velocity turns
    if (last_vy_ < 0 && vy > 0) rising_ = true;
    if (rising_ && vy <= 0) {
      rising_ = false;
      peaks_.push_back(h + 0.5 * vy * vy / 9.81);
    }
    last_vy_ = vy;
  }

  scenes::BouncingBallsParams params_;
  World world_;
  ParticleId tracked_;
  double drop_height_ = 1;
  bool auto_drop_ = true, rising_ = false;
  double last_vy_ = 0;
  std::vector<std::vector<Vec3>> trails_;
  std::vector<Vec3> ring_;  // the tracked ball's ring, drawn each frame (kept: no allocation per frame)
  std::vector<float> hist_t_, hist_h_;
  std::vector<double> peaks_;
};

static int reg = RegisterSample("Particles", "Bouncing balls", BouncingBalls::Create);

}  // namespace
}  // namespace pba::app
