// "Dynamics/Integrators" (workbook 3.2, advanced exercise): every integration method of
// pba/integrate.h drives an identical object side by side, on a ballistic shot, a spring
// and an orbit. Trails show the paths, a translucent ghost shows the exact solution, and a
// shared plot shows each method's energy error as it happens.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "method_colors.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {


enum class Scenario { Ballistic, Spring, Orbit };
constexpr const char* kScenarioNames[] = {"Ballistic shot", "Spring", "Orbit"};

// the problems, each with its acceleration, exact solution and energy (per unit mass)
struct ScenarioModel {
  Scenario kind = Scenario::Spring;
  bool drag = false;  // ballistic: linear air drag
  // ballistic
  Vec3 g{0, -9.81, 0};
  double k = 0.35;  // drag rate, 1/s
  Vec3 v0_shot{5.5, 8.5, 0};
  // spring: y'' = -w^2 y
  double w = 2.0;  // rad/s
  double amplitude = 1.0;
  // orbit: Kepler ellipse, periapsis on +x at t = 0
  double a = 2.0, e = 0.5, period = 6.0;

  double gm() const { return 4 * kPi * kPi * a * a * a / (period * period); }

  Vec3 accel(const Vec3& x, const Vec3& v) const {
    switch (kind) {
      case Scenario::Ballistic: return drag ? g - k * v : g;
      case Scenario::Spring: return -w * w * x;
      case Scenario::Orbit: {
        const double r = glm::length(x);
        return -gm() * x / (r * r * r);
      }
    }
    return {};
  }

  // exact position and velocity at time t
  void exact(double t, Vec3* x, Vec3* v) const {
    switch (kind) {
      case Scenario::Ballistic:
        if (!drag) {
          *x = v0_shot * t + 0.5 * g * t * t;
          *v = v0_shot + g * t;
        } else {
          const double f = std::exp(-k * t);
          *x = g * t / k + (v0_shot - g / k) * (1 - f) / k;
          *v = g / k + (v0_shot - g / k) * f;
        }
        return;
      case Scenario::Spring:
        *x = Vec3(0, amplitude * std::cos(w * t), 0);
        *v = Vec3(0, -amplitude * w * std::sin(w * t), 0);
        return;
      case Scenario::Orbit: {
        // Kepler's equation E - e sin E = M by Newton's method
        const double n = 2 * kPi / period;
        const double M = std::fmod(n * t, 2 * kPi);
        double E = e < 0.8 ? M : kPi;
        for (int i = 0; i < 30; ++i) {
          const double d = (E - e * std::sin(E) - M) / (1 - e * std::cos(E));
          E -= d;
          if (std::abs(d) < 1e-14) break;
        }
        const double b = a * std::sqrt(1 - e * e);
        const double dE = n / (1 - e * std::cos(E));
        *x = Vec3(a * (std::cos(E) - e), b * std::sin(E), 0);
        *v = Vec3(-a * std::sin(E) * dE, b * std::cos(E) * dE, 0);
        return;
      }
    }
  }

  double energy(const Vec3& x, const Vec3& v) const {
    const double kin = 0.5 * glm::dot(v, v);
    switch (kind) {
      case Scenario::Ballistic: return kin - glm::dot(g, x);
      case Scenario::Spring: return kin + 0.5 * w * w * glm::dot(x, x);
      case Scenario::Orbit: return kin - gm() / glm::length(x);
    }
    return kin;
  }
};

// one method's object: state, previous state for interpolation, trail and energy history
struct Lane {
  Method method = Method::ExplicitEuler;
  Integrator<Vec3> integ;
  Vec3 x{}, v{}, x_prev{};
  bool frozen = false;         // landed, escaped or failed: no more steps
  std::string status;          // why it is frozen
  std::vector<Vec3> trail;     // problem-space positions
  std::vector<float> trail_t;  // their times (spring trace)
  std::vector<float> hist_t, hist_e;  // energy error history
  double energy_error = 0;     // (E - E_exact) / |E0| now
  double position_error = 0;   // |x - x_exact| now (m)
  bool visible = true;
};

class Integrators final : public Sample {
 public:
  explicit Integrators(SampleContext& ctx) : Sample(ctx) {
    // a step long enough to tell the methods apart at a glance
    ctx.settings.stepper.fixed_dt = 1.0 / 30.0;
    ctx.renderer->style.grid_spacing = 1.0f;
    for (Method m : kAllMethods) {
      lanes_.emplace_back();
      lanes_.back().method = m;
      lanes_.back().integ = Integrator<Vec3>(m);
    }
    // --option scenario=... and drag=... override the last choice
    const std::string sc = ctx.option("scenario", "");
    const std::string d = ctx.option("drag", "");
    if (!sc.empty() && !options_read_) {
      if (sc == "ballistic") g_scenario = Scenario::Ballistic;
      else if (sc == "spring") g_scenario = Scenario::Spring;
      else if (sc == "orbit") g_scenario = Scenario::Orbit;
      else throw Error("--option scenario=" + sc + ": expected ballistic, spring or orbit");
      g_drag = false;
    }
    if (!d.empty() && !options_read_) {
      if (d != "0" && d != "1") throw Error("--option drag=" + d + ": expected 0 or 1");
      g_drag = d == "1";
    }
    // test hook for the app's divergence handling: poison one object at this time (s)
    const std::string nan_at = ctx.option("nan_at", "");
    if (!nan_at.empty()) {
      char* end = nullptr;
      nan_at_ = std::strtod(nan_at.c_str(), &end);
      if (end != nan_at.c_str() + nan_at.size() || !(nan_at_ >= 0))
        throw Error("--option nan_at=" + nan_at + ": expected a time in seconds >= 0");
    }
    options_read_ = true;
    problem_.kind = g_scenario;
    problem_.drag = g_drag;
    reset(true);
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Integrators>(ctx); }

  void Step(double, double dt) override {
    // every lane takes the same step from its own state
    t_prev_ = t_;
    for (Lane& l : lanes_) {
      l.x_prev = l.x;
      if (l.frozen) continue;
      try {
        l.integ.step_one(t_, dt, l.x, l.v, [this](double, const Vec3& x, const Vec3& v) { return problem_.accel(x, v); });
      } catch (const Error& e) {
        freeze(l, std::string("failed: ") + e.what());
      }
    }
    t_ += dt;
    if (nan_at_ >= 0 && t_ >= nan_at_) lanes_[0].x.y = std::numeric_limits<double>::quiet_NaN();
    after_step();
  }

  void Draw(Renderer& r, double alpha) override {
    const double a = std::clamp(alpha, 0.0, 1.0);
    const double t_draw = t_prev_ + a * (t_ - t_prev_);
    Vec3 xe{}, ve{};
    problem_.exact(t_draw, &xe, &ve);
    switch (problem_.kind) {
      case Scenario::Ballistic: draw_ballistic(r, a, xe); break;
      case Scenario::Spring: draw_spring(r, a, xe, t_draw); break;
      case Scenario::Orbit: draw_orbit(r, a, xe); break;
    }
  }

  void DrawUI() override {
    // scenario and its options
    int sc = static_cast<int>(problem_.kind);
    ImGui::SetNextItemWidth(-70);
    if (ImGui::Combo("scenario", &sc, kScenarioNames, 3)) {
      problem_.kind = g_scenario = static_cast<Scenario>(sc);
      reset(true);
    }
    if (problem_.kind == Scenario::Ballistic && ImGui::Checkbox("linear air drag", &problem_.drag)) {
      g_drag = problem_.drag;
      reset(false);
    }
    // dt is the app's fixed step: one source of truth for the stepper and this panel
    float dt = static_cast<float>(ctx_.settings.stepper.fixed_dt);
    ImGui::SetNextItemWidth(-70);
    if (ImGui::SliderFloat("dt", &dt, 0.002f, 0.2f, "%.4f s", ImGuiSliderFlags_Logarithmic))
      ctx_.settings.stepper.fixed_dt = std::clamp(static_cast<double>(dt), 1e-4, 1.0);
    if (ctx_.settings.stepper.strategy == Strategy::PerFrame || ctx_.settings.stepper.strategy == Strategy::MaxStep)
      ImGui::TextDisabled("(with %s the step follows the frame)",
                          std::string(strategy_name(ctx_.settings.stepper.strategy)).c_str());
    if (ImGui::Button("Reset objects")) reset(false);
    ImGui::SameLine();
    ImGui::Checkbox("trails", &trails_);
    ImGui::SameLine();
    ImGui::Checkbox("exact", &ghost_);

    // legend: colour, method, order, evaluations, errors
    ImGui::Spacing();
    if (ImGui::BeginTable("legend", 4, ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("method", ImGuiTableColumnFlags_WidthStretch, 3.9f);
      ImGui::TableSetupColumn("order", ImGuiTableColumnFlags_WidthStretch, 0.8f);
      ImGui::TableSetupColumn("dE/|E0|", ImGuiTableColumnFlags_WidthStretch, 1.5f);
      ImGui::TableSetupColumn("|x-x*| m", ImGuiTableColumnFlags_WidthStretch, 1.5f);
      ImGui::TableHeadersRow();
      for (Lane& l : lanes_) {
        const Color c = MethodColor(l.method);
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::PushID(static_cast<int>(l.method));
        ImGui::PushStyleColor(ImGuiCol_CheckMark, ImVec4(c.r, c.g, c.b, 1));
        ImGui::Checkbox("##vis", &l.visible);
        ImGui::PopStyleColor();
        ImGui::SameLine();
        ImGui::TextColored(ImVec4(c.r, c.g, c.b, 1), "%s", std::string(label(l.method)).c_str());
        if (ImGui::IsItemHovered() && !l.status.empty()) ImGui::SetTooltip("%s", l.status.c_str());
        ImGui::PopID();
        ImGui::TableNextColumn();
        ImGui::Text("%d%s", order(l.method), is_symplectic(l.method) ? " s" : "");
        ImGui::TableNextColumn();
        if (l.status.empty() || problem_.kind == Scenario::Ballistic) ImGui::Text("%+.1e", l.energy_error);
        else ImGui::TextColored(ImVec4(1, 0.5f, 0.4f, 1), "%s", short_status(l).c_str());
        ImGui::TableNextColumn();
        ImGui::Text("%.2e", l.position_error);
      }
      ImGui::EndTable();
    }
    ImGui::TextDisabled("order: global error ~ dt^order; s = symplectic");

    // energy error of every method on shared axes
    ImGui::Spacing();
    ImGui::SetNextItemWidth(-70);
    ImGui::Combo("plot", &plot_mode_, "dE / |E0|\0log10 |dE / E0|\0");
    std::vector<PlotSeries> series;
    std::vector<std::vector<float>> logs(lanes_.size());
    for (std::size_t i = 0; i < lanes_.size(); ++i) {
      const Lane& l = lanes_[i];
      if (!l.visible || l.hist_t.empty()) continue;
      PlotSeries s;
      s.x = l.hist_t.data();
      s.count = static_cast<int>(l.hist_t.size());
      s.color = MethodColor(l.method);
      s.width = 2.0f;
      if (plot_mode_ == 1) {
        logs[i].resize(l.hist_e.size());
        for (std::size_t k = 0; k < l.hist_e.size(); ++k) logs[i][k] = std::log10(std::max(std::abs(l.hist_e[k]), 1e-16f));
        s.y = logs[i].data();
      } else {
        s.y = l.hist_e.data();
      }
      series.push_back(s);
    }
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = plot_mode_ == 1 ? "log10 |dE/E0|" : "energy error dE/|E0|";
    if (plot_mode_ == 1) {
      ax.y_lo = -10, ax.y_hi = 1;
      ax.y_format = "%.0f";
    } else {
      ax.y_clamp_lo = -1.0f, ax.y_clamp_hi = 1.0f;
      ax.y_include_zero = true;
      ax.y_min_span = 0.02f;
      ax.y_format = "%+.2f";
    }
    LinePlot("energy", series, ax, 190);
    ImGui::TextWrapped("%s", explanation());
  }

  FiniteCheck CheckFinite() const override {
    for (const Lane& l : lanes_) {
      const FiniteCheck c = check_finite<Vec3>(std::span<const Vec3>(&l.x, 1), std::span<const Vec3>(&l.v, 1),
                                               std::string(label(l.method)) + " object", t_, steps_);
      if (!c.ok) return c;
    }
    return {};
  }

  std::vector<Color> ExpectedColors() const override {
    std::vector<Color> c;
    for (Method m : kAllMethods) c.push_back(MethodColor(m));
    return c;
  }

 private:
  // the scenario survives a restart (R) and a sample switch
  static inline Scenario g_scenario = Scenario::Spring;
  static inline bool g_drag = false;
  static inline bool options_read_ = false;  // the command line applies to the first load only

  void freeze(Lane& l, std::string why) {
    l.frozen = true;
    l.status = std::move(why);
  }

  static std::string short_status(const Lane& l) {
    if (l.status.rfind("escaped", 0) == 0) return "escaped";
    if (l.status.rfind("fell", 0) == 0) return "crashed";
    if (l.status.rfind("failed", 0) == 0) return "failed";
    if (l.status.rfind("blew", 0) == 0) return "blew up";
    return l.status;
  }

  // back to t = 0; `frame` also moves the camera to the scenario's framing
  void reset(bool frame) {
    t_ = t_prev_ = 0;
    steps_ = 0;
    Vec3 x0{}, v0{};
    problem_.exact(0, &x0, &v0);
    e0_ = problem_.energy(x0, v0);
    for (Lane& l : lanes_) {
      l.x = l.x_prev = x0;
      l.v = v0;
      l.integ.reset_history();
      l.frozen = false;
      l.status.clear();
      l.trail.assign(1, x0);
      l.trail_t.assign(1, 0.0f);
      l.hist_t.clear();
      l.hist_e.clear();
      l.energy_error = l.position_error = 0;
    }
    // where the exact shot lands (for placing labels)
    range_ = 0;
    for (double t = 0.01; t < 10; t += 0.01) {
      Vec3 x{}, v{};
      problem_.exact(t, &x, &v);
      if (x.y < 0) break;
      range_ = x.x;
    }
    if (!frame) return;
    Camera& cam = *ctx_.camera;
    switch (problem_.kind) {
      case Scenario::Ballistic: cam.frame({5.6f, 1.3f, -3.6f}, 7.0f, 0.22f, 0.26f); break;
      case Scenario::Spring: cam.frame({0.0f, 1.6f, -1.6f}, 4.2f, 0.55f, 0.22f); break;
      case Scenario::Orbit: cam.frame({0.0f, 4.5f, 0.0f}, 7.9f, 0.0f, 0.10f); break;
    }
  }

  // bookkeeping after each step: trails, errors, energy history, the loop of the shot
  void after_step() {
    ++steps_;
    Vec3 xe{}, ve{};
    problem_.exact(t_, &xe, &ve);
    const double e_exact = problem_.energy(xe, ve);
    const double scale = std::max(std::abs(e0_), 1e-12);
    for (Lane& l : lanes_) {
      if (!l.frozen) {
        // trails: ballistic keeps the whole shot, the others the last few seconds
        l.trail.push_back(l.x);
        l.trail_t.push_back(static_cast<float>(t_));
        const double keep = problem_.kind == Scenario::Orbit ? 1.25 * problem_.period : 6.0;
        std::size_t drop = 0;
        while (drop < l.trail_t.size() && problem_.kind != Scenario::Ballistic && l.trail_t[drop] < t_ - keep) ++drop;
        if (drop > 64 || (drop > 0 && l.trail.size() > 2048)) {
          l.trail.erase(l.trail.begin(), l.trail.begin() + static_cast<long>(drop));
          l.trail_t.erase(l.trail_t.begin(), l.trail_t.begin() + static_cast<long>(drop));
        }
        l.energy_error = (problem_.energy(l.x, l.v) - e_exact) / scale;
        l.position_error = glm::length(l.x - xe);
        l.hist_t.push_back(static_cast<float>(t_));
        l.hist_e.push_back(static_cast<float>(l.energy_error));
      }
      check_lane(l);
    }
    // energy history: the last 30 s
    for (Lane& l : lanes_) {
      std::size_t drop = 0;
      while (drop < l.hist_t.size() && l.hist_t[drop] < t_ - 30.0) ++drop;
      if (drop > 128) {
        l.hist_t.erase(l.hist_t.begin(), l.hist_t.begin() + static_cast<long>(drop));
        l.hist_e.erase(l.hist_e.begin(), l.hist_e.begin() + static_cast<long>(drop));
      }
    }
    // the shot starts again a moment after the exact ball has landed
    if (problem_.kind == Scenario::Ballistic && xe.y < 0 && t_ > 0.5) {
      if (landed_at_ < 0) landed_at_ = t_;
      if (t_ - landed_at_ > 0.8) {
        landed_at_ = -1;
        reset(false);
      }
    }
  }

  // freeze a lane that left the stage, so it does not fly off through its neighbours
  void check_lane(Lane& l) {
    if (l.frozen) return;
    switch (problem_.kind) {
      case Scenario::Ballistic:
        if (l.x.y < 0 && t_ > 0.1) {
          l.x.y = 0;
          freeze(l, "landed at x = " + std::to_string(l.x.x).substr(0, 5) + " m");
        }
        break;
      case Scenario::Spring:
        if (std::abs(l.x.y) > 2.5 * problem_.amplitude) freeze(l, "blew up: amplitude above 2.5x at t = " + fmt(t_) + " s");
        break;
      case Scenario::Orbit: {
        const double r = glm::length(l.x);
        if (r > 2.2 * problem_.a * (1 + problem_.e)) freeze(l, "escaped the orbit at t = " + fmt(t_) + " s");
        else if (r < 0.25 * problem_.a * (1 - problem_.e)) freeze(l, "fell into the centre at t = " + fmt(t_) + " s");
        break;
      }
    }
  }

  static std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.1f", v);
    return b;
  }

  // where lane i's problem origin sits in the world
  Vec3 lane_origin(std::size_t i) const {
    switch (problem_.kind) {
      case Scenario::Ballistic: return Vec3(0, 0.15, -1.45 * static_cast<double>(i));
      case Scenario::Spring: return Vec3((static_cast<double>(i) - 2.5) * 1.25, 1.85, 0);
      case Scenario::Orbit: {
        const double col = static_cast<double>(i % 3) - 1.0, row = i < 3 ? 1.0 : 0.0;
        // centre the ellipse (not its focus) in the cell
        return Vec3(col * 4.8 + problem_.a * problem_.e, 2.3 + row * 4.4, 0);
      }
    }
    return {};
  }

  Vec3 interp(const Lane& l, double a) const { return l.frozen && l.x == l.x_prev ? l.x : l.x_prev + a * (l.x - l.x_prev); }

  void draw_label(Renderer& r, const Lane& l, const Vec3& p, float align) {
    if (!ctx_.settings.show_labels) return;
    const Color c = MethodColor(l.method);
    std::string s(label(l.method));
    if (!l.status.empty() && problem_.kind != Scenario::Ballistic) s += " (" + short_status(l) + ")";
    r.text(p, s, c, 1.0f, align);
  }

  void draw_ballistic(Renderer& r, double a, const Vec3& xe) {
    const double radius = 0.15;
    for (std::size_t i = 0; i < lanes_.size(); ++i) {
      const Lane& l = lanes_[i];
      if (!l.visible) continue;
      const Vec3 o = lane_origin(i);
      const Color c = MethodColor(l.method);
      // the exact parabola (or drag curve) over the whole shot, and the ghost
      if (ghost_) {
        std::vector<Vec3> path;
        for (int k = 0; k <= 60; ++k) {
          Vec3 x{}, v{};
          problem_.exact(k * 0.04, &x, &v);
          if (x.y < -0.01) break;
          path.push_back(o + x);
        }
        r.polyline(path, Color{1, 1, 1, 0.35f}, 1.5f);
        if (xe.y >= 0) r.sphere(o + xe, radius, Color{0.92f, 0.94f, 1.0f, 0.32f});
      }
      if (trails_) {
        std::vector<Vec3> pts;
        for (const Vec3& p : l.trail) pts.push_back(o + p);
        pts.push_back(o + interp(l, a));
        r.polyline(pts, c, 2.5f);
      }
      r.sphere(o + interp(l, a), radius, c);
      // launch pad, and the name beyond the landing point where the view is free
      r.box(o + Vec3(0, -0.12, 0), {0.25, 0.03, 0.25}, Quat(1, 0, 0, 0), Color::hex(0x5a606b));
      draw_label(r, l, o + Vec3(range_ + 0.5, 0.0, 0), 0.0f);
    }
  }

  void draw_spring(Renderer& r, double a, const Vec3& xe, double t_draw) {
    const double radius = 0.2, top = 3.6;
    // the ceiling bar all springs hang from
    r.box({0, top + 0.06, 0}, {0.5 * 1.25 * 6 + 0.2, 0.06, 0.12}, Quat(1, 0, 0, 0), Color::hex(0x5a606b));
    const double speed = 0.55;  // m of depth per second of trace
    for (std::size_t i = 0; i < lanes_.size(); ++i) {
      const Lane& l = lanes_[i];
      if (!l.visible) continue;
      const Vec3 o = lane_origin(i);
      const Color c = MethodColor(l.method);
      const Vec3 p = o + interp(l, a);
      // the coil: a zigzag from the bar to the mass
      std::vector<Vec3> coil;
      const int turns = 14;
      const Vec3 from(o.x, top, 0), to = p + Vec3(0, radius, 0);
      for (int k = 0; k <= 2 * turns; ++k) {
        const double f = static_cast<double>(k) / (2 * turns);
        const double side = (k == 0 || k == 2 * turns) ? 0.0 : (k % 2 ? 0.12 : -0.12);
        coil.push_back(from + f * (to - from) + Vec3(side, 0, 0));
      }
      r.polyline(coil, Color{0.78f, 0.80f, 0.84f, 1.0f}, 1.5f);
      r.sphere(p, radius, c);
      if (ghost_) r.sphere(o + xe, radius * 1.02, Color{0.92f, 0.94f, 1.0f, 0.30f});
      // the trace: height against time, receding into the depth behind the mass
      if (trails_) {
        std::vector<Vec3> pts;
        for (std::size_t k = 0; k < l.trail.size(); ++k)
          pts.push_back(Vec3(o.x, o.y + l.trail[k].y, -(t_draw - l.trail_t[k]) * speed));
        pts.push_back(Vec3(p.x, p.y, 0));
        r.polyline(pts, c, 2.0f);
        if (ghost_) {
          std::vector<Vec3> ex;
          for (double s = 0; s <= 6.0 && s <= t_draw; s += 0.05) {
            Vec3 x{}, v{};
            problem_.exact(t_draw - s, &x, &v);
            ex.push_back(Vec3(o.x, o.y + x.y, -s * speed));
          }
          r.polyline(ex, Color{1, 1, 1, 0.28f}, 1.2f);
        }
      }
      draw_label(r, l, Vec3(o.x, 0.35, 0.2), 0.5f);
    }
  }

  void draw_orbit(Renderer& r, double a, const Vec3& xe) {
    const double radius = 0.14;
    for (std::size_t i = 0; i < lanes_.size(); ++i) {
      const Lane& l = lanes_[i];
      if (!l.visible) continue;
      const Vec3 o = lane_origin(i);
      const Color c = MethodColor(l.method);
      // the sun at the focus, the exact ellipse and the ghost
      r.sphere(o, 0.28, Color::hex(0xffb224));
      if (ghost_) {
        std::vector<Vec3> ell;
        const double b = problem_.a * std::sqrt(1 - problem_.e * problem_.e);
        for (int k = 0; k <= 96; ++k) {
          const double E = 2 * kPi * k / 96;
          ell.push_back(o + Vec3(problem_.a * (std::cos(E) - problem_.e), b * std::sin(E), 0));
        }
        r.polyline(ell, Color{1, 1, 1, 0.30f}, 1.5f);
        r.sphere(o + xe, radius, Color{0.92f, 0.94f, 1.0f, 0.32f});
      }
      if (trails_) {
        std::vector<Vec3> pts;
        for (const Vec3& p : l.trail) pts.push_back(o + p);
        pts.push_back(o + interp(l, a));
        r.polyline(pts, c, 2.2f);
      }
      r.sphere(o + interp(l, a), radius, c);
      const Vec3 centre = o - Vec3(problem_.a * problem_.e, 0, 0);
      draw_label(r, l, centre + Vec3(0, 2.05, 0), 0.5f);
    }
  }

  const char* explanation() const {
    switch (problem_.kind) {
      case Scenario::Ballistic:
        return "Constant gravity: Verlet, velocity Verlet and RK4 land exactly on the ghost; "
               "the Euler family is off by O(dt). Drag makes the force depend on velocity.";
      case Scenario::Spring:
        return "An undamped spring: explicit Euler gains energy every step (its swing grows), "
               "implicit Euler loses it (its swing dies), the symplectic methods keep it bounded, "
               "RK4 drifts too slowly to see. The traces behind the masses are height over time.";
      case Scenario::Orbit:
        return "A Kepler ellipse (e = 0.5): explicit Euler spirals out, implicit Euler spirals in, "
               "the symplectic methods keep the orbit but let it precess, RK4 follows the ghost.";
    }
    return "";
  }

  ScenarioModel problem_;
  std::vector<Lane> lanes_;
  double t_ = 0, t_prev_ = 0, e0_ = 1, landed_at_ = -1, range_ = 0;
  long long steps_ = 0;
  double nan_at_ = -1;  // --option nan_at: test hook, < 0 when off
  bool trails_ = true, ghost_ = true;
  int plot_mode_ = 0;
};

static int reg = RegisterSample("Dynamics", "Integrators", Integrators::Create);

}  // namespace
}  // namespace pba::app
