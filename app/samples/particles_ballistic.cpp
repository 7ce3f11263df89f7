// "Particles/Ballistic experiment" (workbook 4.2, exercise 1; exercise 2 with drag): one
// projectile of the shared scene builder pba::scenes::ballistic, fired over a ground
// plane. The simulated path is drawn beside the closed form (pba::scenes::ballistic_position),
// and range, apex and flight time are read out for both.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/scene.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

constexpr Color kSim = colors::orange;
constexpr Color kExact = Color{0.95f, 0.96f, 1.0f, 0.75f};

// range, apex and flight time of one shot
struct ShotFigures {
  double range = 0, apex = 0, flight = 0;
  bool done = false;  // the simulated shot has landed (range and flight known)
  bool apex_done = false;
};

// the closed form's figures, from pba::scenes::ballistic_position
ShotFigures ClosedForm(const scenes::BallisticParams& p, const Vec3& g) {
  ShotFigures f;
  const double gy = std::max(-g.y, 1e-9);
  const double vy = p.speed * std::sin(p.angle_deg * kPi / 180);
  // apex time: vy / g without drag, tau ln(1 + vy / (g tau)) with it
  double t_apex = vy / gy;
  if (p.linear_drag > 0) {
    const double tau = p.mass / p.linear_drag;
    t_apex = tau * std::log1p(vy / (gy * tau));
  }
  f.apex = scenes::ballistic_position(p, g, t_apex).y;
  // landing: bisection for y = 0 after the apex
  double lo = t_apex, hi = std::max(2 * t_apex, 1e-3);
  while (scenes::ballistic_position(p, g, hi).y > 0 && hi < 1e4) hi *= 2;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    (scenes::ballistic_position(p, g, mid).y > 0 ? lo : hi) = mid;
  }
  f.flight = 0.5 * (lo + hi);
  f.range = scenes::ballistic_position(p, g, f.flight).x;
  f.done = f.apex_done = true;
  return f;
}

class Ballistic final : public Sample {
 public:
  explicit Ballistic(SampleContext& ctx) : Sample(ctx) {
    // --option angle=DEG speed=M/S drag=B (kg/s; 0 = off) for scripted pictures
    params_.angle_deg = OptionNumber(ctx, "angle", 50, 1, 89);
    params_.speed = OptionNumber(ctx, "speed", 14, 1, 40);
    const double b = OptionNumber(ctx, "drag", 0, 0, 2);
    drag_ = b > 0;
    if (drag_) drag_b_ = b;
    params_.radius = 0.05;
    ctx.renderer->style.grid_spacing = 1.0f;
    launch();
    frame_camera();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Ballistic>(ctx); }

  void Step(double, double dt) override {
    // relaunch a moment after landing
    if (sim_.done && world_.time() - sim_.flight > 1.5) launch();
    const ParticleSystem& ps = world_.particles();
    const Vec3 x0 = ps.position(id_), v0 = ps.velocity(id_);
    const double t0 = world_.time();
    prev_ = x0;
    TickWorld(world_, ctx_.settings, dt);
    const Vec3 x1 = ps.position(id_), v1 = ps.velocity(id_);
    const double g = std::max(-ps.forces().gravity.y, 1e-9);
    // apex: vertical velocity turns; finish the rise from the state before the step
    if (!sim_.apex_done && v0.y > 0 && v1.y <= 0) {
      sim_.apex = x0.y + v0.y * v0.y / (2 * g);
      sim_.apex_done = true;
    }
    // landing: the ground pushed the ball (bounce or contact); the crossing of y = 0 is
    // the free flight continued from the state before the step
    const bool contact = v1.y > v0.y + 1e-9 || x1.y <= params_.radius * 1.0001;
    if (!sim_.done && t0 > 0 && contact && v0.y < 0) {
      const double s = (v0.y + std::sqrt(v0.y * v0.y + 2 * g * std::max(x0.y, 0.0))) / g;
      sim_.range = x0.x + v0.x * s;
      sim_.flight = t0 + s;
      sim_.done = true;
      if (!sim_.apex_done) sim_.apex = x0.y, sim_.apex_done = true;
    }
    if (!sim_.done) trail_.push_back(x1);
  }

  void Draw(Renderer& r, double alpha) override {
    const Vec3 g = world_.particles().forces().gravity;
    // the closed form for this shot, and the drag-free parabola for reference
    draw_closed_form(r, params_with_drag(), g, kExact, 2.0f);
    if (drag_) {
      scenes::BallisticParams nodrag = params_with_drag();
      nodrag.linear_drag = 0;
      draw_closed_form(r, nodrag, g, Color{0.7f, 0.72f, 0.78f, 0.35f}, 1.2f);
      const ShotFigures f0 = ClosedForm(nodrag, g);
      label(r, Vec3(0.5 * f0.range, f0.apex + 0.04 * scale_, 0), "without drag", Color{0.75f, 0.77f, 0.82f, 0.8f}, 0.5f);
    }
    // the simulated path with a dot every 5 steps, and the projectile
    std::vector<Vec3> pts = trail_;
    const Vec3 now = current(alpha);
    if (!sim_.done) pts.push_back(now);
    r.polyline(pts, kSim, 3.5f);
    for (std::size_t i = 0; i < trail_.size(); i += 5) r.point(trail_[i], 7.0f, kSim);
    r.sphere(now, std::max(params_.radius, 0.026 * scale_), kSim);
    // launch direction
    const double a = params_.angle_deg * kPi / 180;
    r.arrow({0, 0, 0}, Vec3(std::cos(a), std::sin(a), 0) * (0.12 * scale_), 0.03 * scale_, colors::yellow);
    r.box({0, -0.02, 0}, Vec3(0.03 * scale_, 0.02, 0.03 * scale_), Quat(1, 0, 0, 0), Color::hex(0x5a606b));
    // apex and range marks: white closed form, orange simulation
    const Vec3 apex_at = scenes::ballistic_position(params_with_drag(), g, apex_time_);
    r.line(Vec3(apex_at.x, 0, 0), Vec3(apex_at.x, exact_.apex, 0), Color{1, 1, 1, 0.3f}, 1.2f);
    r.line(Vec3(apex_at.x - 0.06 * scale_, exact_.apex, 0), Vec3(apex_at.x + 0.06 * scale_, exact_.apex, 0), kExact, 2.0f);
    char buf[96];
    std::snprintf(buf, sizeof buf, "apex %.3f m", exact_.apex);
    label(r, Vec3(apex_at.x, exact_.apex + 0.10 * scale_, 0), buf, kExact, 0.5f);
    if (sim_.apex_done) {
      r.line(Vec3(apex_at.x - 0.05 * scale_, sim_.apex, 0), Vec3(apex_at.x + 0.05 * scale_, sim_.apex, 0), kSim, 3.0f);
      std::snprintf(buf, sizeof buf, "sim %.3f m", sim_.apex);
      label(r, Vec3(apex_at.x, exact_.apex + 0.06 * scale_, 0), buf, kSim, 0.5f);
    }
    r.line(Vec3(exact_.range, 0.002, -0.06 * scale_), Vec3(exact_.range, 0.002, 0.06 * scale_), kExact, 3.0f);
    std::snprintf(buf, sizeof buf, "range %.3f m", exact_.range);
    label(r, Vec3(exact_.range, -0.05 * scale_, 0), buf, kExact, 0.5f);
    if (sim_.done) {
      r.line(Vec3(sim_.range, 0.004, -0.05 * scale_), Vec3(sim_.range, 0.004, 0.05 * scale_), kSim, 3.0f);
      std::snprintf(buf, sizeof buf, "sim %.3f m", sim_.range);
      label(r, Vec3(sim_.range, -0.1 * scale_, 0), buf, kSim, 0.5f);
    }
  }

  void DrawUI() override {
    bool relaunch = false;
    float angle = static_cast<float>(params_.angle_deg), speed = static_cast<float>(params_.speed);
    ImGui::SetNextItemWidth(-110);
    relaunch |= ImGui::SliderFloat("angle", &angle, 1.0f, 89.0f, "%.1f deg");
    reframe_ |= ImGui::IsItemDeactivatedAfterEdit();
    ImGui::SetNextItemWidth(-110);
    relaunch |= ImGui::SliderFloat("speed", &speed, 1.0f, 40.0f, "%.1f m/s");
    reframe_ |= ImGui::IsItemDeactivatedAfterEdit();
    relaunch |= ImGui::Checkbox("linear air drag", &drag_);
    ImGui::BeginDisabled(!drag_);
    float b = static_cast<float>(drag_b_), m = static_cast<float>(params_.mass);
    ImGui::SetNextItemWidth(-110);
    relaunch |= ImGui::SliderFloat("drag b", &b, 0.005f, 1.0f, "%.3f kg/s", ImGuiSliderFlags_Logarithmic);
    ImGui::SetNextItemWidth(-110);
    relaunch |= ImGui::SliderFloat("mass", &m, 0.02f, 2.0f, "%.2f kg", ImGuiSliderFlags_Logarithmic);
    ImGui::EndDisabled();
    if (drag_) ImGui::TextDisabled("time constant tau = m / b = %.2f s", params_.mass / drag_b_);
    if (ImGui::Button("Launch again")) relaunch = true;
    ImGui::SameLine();
    if (ImGui::Button("Frame the shot")) reframe_ = true;
    if (relaunch) {
      params_.angle_deg = angle;
      params_.speed = speed;
      drag_b_ = b;
      params_.mass = m;
      launch();
    }
    if (reframe_) {
      frame_camera();
      reframe_ = false;
    }

    // simulated against closed form
    ImGui::Spacing();
    if (ImGui::BeginTable("figures", 4, ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("", ImGuiTableColumnFlags_WidthStretch, 1.3f);
      ImGui::TableSetupColumn("simulated", ImGuiTableColumnFlags_WidthStretch, 1.2f);
      ImGui::TableSetupColumn("closed form", ImGuiTableColumnFlags_WidthStretch, 1.2f);
      ImGui::TableSetupColumn("rel. error", ImGuiTableColumnFlags_WidthStretch, 1.1f);
      ImGui::TableHeadersRow();
      row("range (m)", sim_.done, sim_.range, exact_.range);
      row("apex (m)", sim_.apex_done, sim_.apex, exact_.apex);
      row("flight (s)", sim_.done, sim_.flight, exact_.flight);
      ImGui::EndTable();
    }
    ImGui::TextDisabled("%s, dt = %.4f s", std::string(pba::label(ctx_.settings.method)).c_str(), ctx_.settings.stepper.fixed_dt);
    ImGui::TextWrapped(
        "The orange path is the simulated particle (a dot every 5 steps), the white curve the closed form%s. "
        "Without drag the range is v^2 sin(2a) / g and the apex (v sin a)^2 / 2g; the error shrinks with dt at the "
        "integrator's order (try RK4 or a higher step rate).",
        drag_ ? " with linear drag x(t) = v0 tau (1 - e^-t/tau) + g tau (t - tau (1 - e^-t/tau)); the grey parabola is "
                "the same shot in vacuum"
              : "");
  }

  FiniteCheck CheckFinite() const override {
    const Vec3 x = world_.particles().position(id_), v = world_.particles().velocity(id_);
    return check_finite<Vec3>(std::span<const Vec3>(&x, 1), std::span<const Vec3>(&v, 1), "projectile", world_.time(),
                              world_.ticks());
  }
  std::vector<Color> ExpectedColors() const override { return {kSim}; }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    WorldPoints(world_, out, max_points);
  }

 private:
  scenes::BallisticParams params_with_drag() const {
    scenes::BallisticParams p = params_;
    p.linear_drag = drag_ ? drag_b_ : 0;
    return p;
  }

  // a fresh world with the shot at t = 0
  void launch() {
    world_ = World(WorldDef{.particles = {.capacity = 4}});
    const scenes::BallisticParams p = params_with_drag();
    const EntityId e = scenes::ballistic(world_, p);
    id_ = world_.particle(e);
    trail_.assign(1, world_.particles().position(id_));
    prev_ = trail_.front();
    sim_ = {};
    const Vec3 g = world_.particles().forces().gravity;
    exact_ = ClosedForm(p, g);
    // the apex time, for placing its marks
    const double gy = std::max(-g.y, 1e-9), vy = p.speed * std::sin(p.angle_deg * kPi / 180);
    apex_time_ = p.linear_drag > 0 ? (p.mass / p.linear_drag) * std::log1p(vy / (gy * p.mass / p.linear_drag)) : vy / gy;
    scale_ = std::max({exact_.range, 2 * exact_.apex, 2.0});
  }

  // the whole shot in view (with drag, a margin where the longer shot in vacuum shows)
  void frame_camera() {
    const double k = drag_ ? 1.3 : 1.0;
    const float w = static_cast<float>(std::max(k * exact_.range, 1.0)), h = static_cast<float>(k * exact_.apex);
    ctx_.camera->frame({0.5f * w, 0.42f * h, 0.0f}, 0.53f * std::max(w, 2.2f * h) + 0.5f, 0.0f, 0.1f);
  }

  Vec3 current(double alpha) const {
    const Vec3 x = world_.particles().position(id_);
    const double a = std::clamp(alpha, 0.0, 1.0);
    return prev_ + a * (x - prev_);
  }

  void label(Renderer& r, const Vec3& p, const std::string& s, Color c, float align) const {
    if (ctx_.settings.show_labels) r.text(p, s, c, 1.0f, align);
  }

  static void row(const char* name, bool have, double sim, double exact) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(name);
    ImGui::TableNextColumn();
    if (have) ImGui::TextColored(ImVec4(kSim.r, kSim.g, kSim.b, 1), "%.4f", sim);
    else ImGui::TextDisabled("...");
    ImGui::TableNextColumn();
    ImGui::Text("%.4f", exact);
    ImGui::TableNextColumn();
    if (have && std::abs(exact) > 1e-12) ImGui::Text("%+.2e", (sim - exact) / exact);
  }

  void draw_closed_form(Renderer& r, const scenes::BallisticParams& p, const Vec3& g, Color c, float width) const {
    const ShotFigures f = ClosedForm(p, g);
    std::vector<Vec3> path;
    for (int k = 0; k <= 120; ++k) path.push_back(scenes::ballistic_position(p, g, f.flight * k / 120.0));
    r.polyline(path, c, width);
  }

  scenes::BallisticParams params_;
  bool drag_ = false;
  double drag_b_ = 0.1;
  bool reframe_ = false;
  World world_;
  ParticleId id_;
  std::vector<Vec3> trail_;
  Vec3 prev_{0, 0, 0};
  ShotFigures sim_, exact_;
  double apex_time_ = 0, scale_ = 10;
};

static int reg = RegisterSample("Particles", "Ballistic experiment", Ballistic::Create);

}  // namespace
}  // namespace pba::app
