// "Soft bodies/Spring" (workbook 4.3, exercise 2): a mass on a Hooke spring hanging from a
// fixed anchor, integrated by the method chosen in the panel (every pba::Method, through
// pba::SoftBody's mass-spring solver). A ghost shows the exact motion; the trace behind the
// mass is its height over the last seconds; the panel plots the oscillation energy, reads
// the period against 2 pi sqrt(m/k) and tabulates each method's largest stable step, from
// theory (omega h limits) and measured on this very spring. Raise dt past a limit and the
// spring blows up: the sample stops with a message (ExpectedStop: the app prints it and
// pauses, and the self-test passes, since showing the blow-up is the sample's purpose)
// instead of drawing garbage.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "method_colors.h"
#include "pba/lab.h"
#include "particles_common.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"
#include "soft_common.h"

namespace pba::app {
namespace {

constexpr double kG = 9.81;           // gravity (m/s^2)
constexpr double kRest = 1.0;         // rest length (m)
constexpr double kAnchorY = 3.6;      // the fixed end (m)
constexpr double kBlowUp = 10.0;      // frozen beyond this many initial amplitudes
constexpr int kMeasureSteps = 400;    // steps per stability trial

// The spring's parameters; they survive a restart (R) and a sample switch.
struct Params {
  double k = 40;          // stiffness (N/m)
  double m = 1;           // mass (kg)
  double c = 0;           // damping (N s/m)
  double amplitude = 0.4; // initial displacement below the equilibrium (m)
  bool operator==(const Params&) const = default;
};

// a spring without gravity at step h: true when its displacement stays below 10 times the
// start over kMeasureSteps steps (a linear recurrence: bounded iff its spectral radius is
// at most 1, and a radius of 1.006 already grows 10x in 400 steps)
bool stable_at(Method method, const Params& p, double h) {
  SoftBodyDef d;
  d.solver = SoftSolver::MassSpring;
  d.method = method;
  d.substeps = 1;
  d.forces.gravity = Vec3(0);
  // a long rest length keeps the motion linear: the mass never reaches the anchor, where
  // the spring's direction would flip
  const double rest = 4 * kBlowUp * p.amplitude;
  SpringDef sp;
  sp.a = Vec3(0);
  sp.b = Vec3(0, -(rest + p.amplitude), 0);
  sp.rest_length = rest;
  sp.mass = p.m, sp.stiffness = p.k, sp.damping = p.c;
  try {
    SoftBody b = SoftBody::spring(sp, d);
    for (int i = 0; i < kMeasureSteps; ++i) {
      b.step(i * h, h);
      if (!(std::abs(b.position(1).y + rest) < kBlowUp * p.amplitude)) return false;
    }
  } catch (const Error&) {
    return false;
  }
  return true;
}

// the largest stable step by bisection in log h over [0.01, 10] / omega: 0 when even the
// smallest grows, infinity when even the largest is stable
double measured_limit(Method method, const Params& p) {
  const double w = std::sqrt(p.k / p.m);
  double lo = 0.01 / w, hi = 10 / w;
  if (stable_at(method, p, hi)) return std::numeric_limits<double>::infinity();
  if (!stable_at(method, p, lo)) return 0;
  for (int i = 0; i < 24; ++i) {
    const double mid = std::sqrt(lo * hi);
    (stable_at(method, p, mid) ? lo : hi) = mid;
  }
  return lo;
}

std::string fmt_step(double h) {
  char b[48];
  if (std::isinf(h)) return "any";
  if (h <= 0) return "none";
  if (h < 0.1) std::snprintf(b, sizeof b, "%.2f ms", 1e3 * h);
  else std::snprintf(b, sizeof b, "%.3f s", h);
  return b;
}

class SpringSample final : public Sample {
 public:
  explicit SpringSample(SampleContext& ctx) : Sample(ctx) {
    // --option k=N/M mass=KG damping=NS/M amplitude=M (first load only)
    if (!options_read_) {
      g_params.k = OptionNumber(ctx, "k", g_params.k, 0.1, 1e5);
      g_params.m = OptionNumber(ctx, "mass", g_params.m, 0.01, 100);
      g_params.c = OptionNumber(ctx, "damping", g_params.c, 0, 100);
      g_params.amplitude = OptionNumber(ctx, "amplitude", g_params.amplitude, 0.01, 1);
      options_read_ = true;
    }
    params_ = g_params;
    // a restart after a blow-up runs again (the app paused on the blow-up)
    if (g_stopped) ctx.settings.paused = false;
    g_stopped = false;
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.0f, 2.3f, -1.3f}, 2.9f, 0.62f, 0.16f);
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<SpringSample>(ctx); }

  void Step(double, double dt) override {
    if (!failure_.empty()) return;
    // a new integrator starts the spring again, so the plot shows one method
    if (ctx_.settings.method != method_) build();
    const double y_prev = body_.position(1).y;
    try {
      body_.step(t_, dt);
    } catch (const Error& e) {
      fail(e.what());
      return;
    }
    t_prev_ = t_;
    t_ += dt;
    last_h_ = dt;
    after_step(y_prev, dt);
  }

  void Draw(Renderer& r, double alpha) override {
    const Color mc = MethodColor(method_);
    // a blown-up spring is drawn where it was before the step that took it out of bounds
    const double a = failure_.empty() ? std::clamp(alpha, 0.0, 1.0) : 0.0;
    const double y = y_prev_draw_ + a * (body_.position(1).y - y_prev_draw_);
    const double t_draw = t_prev_ + a * (t_ - t_prev_);
    const Vec3 top(0, kAnchorY, 0), p(0, y, 0);
    const double radius = 0.13;
    // the anchor bar and the coil
    r.box(top + Vec3(0, 0.05, 0), {0.35, 0.05, 0.2}, Quat(1, 0, 0, 0), soft_colors::pole);
    std::vector<Vec3> coil;
    const int turns = 16;
    const Vec3 to = p + Vec3(0, radius, 0);
    for (int k = 0; k <= 2 * turns; ++k) {
      const double f = static_cast<double>(k) / (2 * turns);
      const double side = (k == 0 || k == 2 * turns) ? 0.0 : (k % 2 ? 0.1 : -0.1);
      coil.push_back(top + f * (to - top) + Vec3(side, 0, 0));
    }
    r.polyline(coil, Color{0.80f, 0.82f, 0.86f, 1.0f}, 2.0f);
    r.sphere(p, radius, mc);
    // the exact motion as a ghost, the equilibrium as a tick
    if (g_ghost) r.sphere(Vec3(0, exact_y(t_draw), 0), radius * 1.02, Color{0.92f, 0.94f, 1.0f, 0.30f});
    r.line(Vec3(-0.35, y_eq_, 0), Vec3(0.35, y_eq_, 0), Color{1, 1, 1, 0.5f}, 1.5f);
    // the trace: height against time, receding into the depth behind the mass
    const double speed = 0.45;  // m of depth per second
    const std::vector<float>& tt = trail_.t();
    if (g_trace && !tt.empty()) {
      std::vector<Vec3> pts;
      pts.reserve(tt.size() + 1);
      for (std::size_t k = 0; k < tt.size(); ++k)
        if (tt[k] >= t_draw - kTrail) pts.push_back(Vec3(0, trail_.column(0)[k], -(t_draw - tt[k]) * speed));
      pts.push_back(p);
      r.polyline(pts, mc, 2.0f);
      if (g_ghost) {
        std::vector<Vec3> ex;
        for (double s = 0; s <= kTrail && s <= t_draw; s += 0.02) ex.push_back(Vec3(0, exact_y(t_draw - s), -s * speed));
        r.polyline(ex, Color{1, 1, 1, 0.3f}, 1.2f);
      }
    }
    if (ctx_.settings.show_labels) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%s   omega h = %.3f", std::string(label(method_)).c_str(), omega() * last_h_);
      r.text(p + Vec3(0.25, 0, 0), buf, mc, 1.0f, 0.0f);
      r.text(Vec3(-0.4, y_eq_, 0), "equilibrium", Color{1, 1, 1, 0.7f}, 0.85f, 1.0f);
    }
    if (!failure_.empty()) DrawBanner(ctx_, failure_, colors::red);
    else DrawBanner(ctx_, "Raise dt (or k) past the method's limit in the table to see it blow up.");
  }

  void DrawUI() override {
    // the integrator is the app's (one source of truth with the Simulation panel)
    ImGui::SetNextItemWidth(-110);
    if (ImGui::BeginCombo("integrator", std::string(label(ctx_.settings.method)).c_str())) {
      for (Method m : kAllMethods)
        if (ImGui::Selectable(std::string(label(m)).c_str(), m == ctx_.settings.method)) ctx_.settings.method = m;
      ImGui::EndCombo();
    }
    // dt is the app's fixed step
    float dt = static_cast<float>(ctx_.settings.stepper.fixed_dt);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("dt", &dt, 0.001f, 0.5f, "%.4f s", ImGuiSliderFlags_Logarithmic))
      ctx_.settings.stepper.fixed_dt = std::clamp(static_cast<double>(dt), 1e-4, 1.0);
    if (ctx_.settings.stepper.strategy == Strategy::PerFrame || ctx_.settings.stepper.strategy == Strategy::MaxStep)
      ImGui::TextDisabled("(with %s the step follows the frame)",
                          std::string(strategy_name(ctx_.settings.stepper.strategy)).c_str());
    // the spring
    Params p = params_;
    float k = static_cast<float>(p.k), m = static_cast<float>(p.m), c = static_cast<float>(p.c),
          amp = static_cast<float>(p.amplitude);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("stiffness k", &k, 1.0f, 2000.0f, "%.1f N/m", ImGuiSliderFlags_Logarithmic)) p.k = k;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("mass m", &m, 0.1f, 10.0f, "%.2f kg", ImGuiSliderFlags_Logarithmic)) p.m = m;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("damping c", &c, 0.0f, 5.0f, "%.2f N s/m")) p.c = c;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("amplitude", &amp, 0.05f, 1.0f, "%.2f m")) p.amplitude = amp;
    if (!(p == params_)) {
      params_ = g_params = p;
      restart();
    }
    if (ImGui::Button("Restart spring")) restart();
    ImGui::SameLine();
    ImGui::Checkbox("exact", &g_ghost);
    ImGui::SameLine();
    ImGui::Checkbox("trace", &g_trace);
    if (!failure_.empty()) {
      ImGui::PushTextWrapPos(0);
      ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "%s", failure_.c_str());
      ImGui::PopTextWrapPos();
    }

    // period and energy
    const double w = omega(), gamma = params_.c / (2 * params_.m);
    const double t0 = 2 * kPi / w;
    ImGui::Spacing();
    ImGui::Text("omega = sqrt(k/m) = %.3f rad/s", w);
    ImGui::Text("omega h = %.3f", w * ctx_.settings.stepper.fixed_dt);
    ImGui::Text("2 pi sqrt(m/k) = %.4f s", t0);
    if (gamma > 0 && gamma < w) ImGui::TextDisabled("damped: 2 pi / sqrt(omega^2 - (c/2m)^2) = %.4f s", 2 * kPi / std::sqrt(w * w - gamma * gamma));
    if (period_ > 0)
      ImGui::Text("measured period  = %.4f s (%+.2f %%)", period_, 100 * (period_ / exact_period() - 1));
    else
      ImGui::TextDisabled("measured period: (two crossings needed)");
    ImGui::Text("oscillation energy E/E0 = %.4f", energy_ratio_);

    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "E / E0 (white: exact)";
    ax.y_include_zero = true;
    ax.y_min_span = 1.2f;
    ax.y_clamp_hi = 1e6f;
    const Color energy_colors[2] = {Color{1, 1, 1, 0.45f}, MethodColor(method_)};
    hist_.Plot("energy", energy_colors, ax, 120);

    // the largest stable step of each method, theory and measured
    ImGui::Spacing();
    ImGui::TextUnformatted("largest stable step h on this spring");
    if (ImGui::BeginTable("limits", 4, ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("method", ImGuiTableColumnFlags_WidthStretch, 2.6f);
      ImGui::TableSetupColumn("limit", ImGuiTableColumnFlags_WidthStretch, 1.1f);
      ImGui::TableSetupColumn("theory", ImGuiTableColumnFlags_WidthStretch, 1.3f);
      ImGui::TableSetupColumn("measured", ImGuiTableColumnFlags_WidthStretch, 1.4f);
      ImGui::TableHeadersRow();
      for (std::size_t i = 0; i < kAllMethods.size(); ++i) {
        const Method m = kAllMethods[i];
        const Color col = MethodColor(m);
        const double lim = StabilityLimit(m);
        ImGui::TableNextRow();
        if (m == method_) ImGui::TableSetBgColor(ImGuiTableBgTarget_RowBg0, IM_COL32(70, 80, 100, 160));
        ImGui::TableNextColumn();
        ImGui::TextColored(ImVec4(col.r, col.g, col.b, 1), "%s", std::string(label(m)).c_str());
        ImGui::TableNextColumn();
        if (lim <= 0) ImGui::TextUnformatted("never");
        else if (std::isinf(lim)) ImGui::TextUnformatted("always");
        else ImGui::Text("%.3f", lim);
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(fmt_step(lim <= 0 ? 0.0 : lim / w).c_str());
        ImGui::TableNextColumn();
        const double hm = measured_[i];
        if (m == Method::ExplicitEuler && hm > 0 && !std::isinf(hm)) ImGui::Text("%s*", fmt_step(hm).c_str());
        else if (std::isinf(hm)) ImGui::Text("> %s", fmt_step(10 / w).c_str());
        else ImGui::TextUnformatted(fmt_step(hm).c_str());
      }
      ImGui::EndTable();
    }
    ImGui::TextWrapped(
        "limit: omega h below which the swing stays bounded. measured: bisection on h, %d steps each, "
        "stable while the swing stays under 10x the start. "
        "* explicit Euler grows at every h (by sqrt(1 + (omega h)^2) per step); below this h it just "
        "needs more than %d steps to reach 10x.",
        kMeasureSteps, kMeasureSteps);
    ImGui::TextWrapped(
        "Hooke's law F = -k (l - l0) - c v along the spring, gravity 9.81 m/s^2. The symplectic methods keep "
        "the energy bounded and the period close to 2 pi sqrt(m/k); explicit Euler's swing grows, implicit "
        "Euler's dies away.");
  }

  std::vector<Color> ExpectedColors() const override { return {MethodColor(method_)}; }
  std::string ExpectedStop() const override { return failure_; }

 private:
  static inline Params g_params{};
  static inline bool options_read_ = false;
  static inline bool g_stopped = false;  // a blow-up stopped the spring (and the app paused)
  // the view toggles survive a reload (a restart after a stop reloads the sample)
  static inline bool g_ghost = true, g_trace = true;
  static constexpr double kTrail = 8.0;  // seconds of trace

  double omega() const { return std::sqrt(params_.k / params_.m); }
  double exact_period() const {
    const double w = omega(), gamma = params_.c / (2 * params_.m);
    return gamma < w ? 2 * kPi / std::sqrt(w * w - gamma * gamma) : std::numeric_limits<double>::infinity();
  }

  // the exact height: a damped oscillation about the equilibrium, released at rest
  // amplitude below it: u(t) = -A e^(-gamma t) (cos w_d t + gamma / w_d sin w_d t)
  double exact_y(double t) const {
    const double w = omega(), gamma = params_.c / (2 * params_.m), A = params_.amplitude;
    double u;
    if (gamma < w) {
      const double wd = std::sqrt(w * w - gamma * gamma);
      u = -A * std::exp(-gamma * t) * (std::cos(wd * t) + gamma / wd * std::sin(wd * t));
    } else if (gamma == w) {
      u = -A * std::exp(-w * t) * (1 + w * t);
    } else {
      // overdamped: roots r1,2 = -gamma +- sqrt(gamma^2 - w^2)
      const double q = std::sqrt(gamma * gamma - w * w), r1 = -gamma + q, r2 = -gamma - q;
      u = -A * (r2 * std::exp(r1 * t) - r1 * std::exp(r2 * t)) / (r2 - r1);
    }
    return y_eq_ + u;
  }

  // the exact oscillation energy ratio: 1/2 (m u'^2 + k u^2) / (1/2 k A^2)
  double exact_energy(double t) const {
    const double h = 1e-5;
    const double u = exact_y(t) - y_eq_, v = (exact_y(t + h) - exact_y(t - h)) / (2 * h);
    return (params_.m * v * v + params_.k * u * u) / (params_.k * params_.amplitude * params_.amplitude);
  }

  // a new spring at rest `amplitude` below its equilibrium, with the app's integrator
  void build() {
    method_ = ctx_.settings.method;
    const Params& p = params_;
    y_eq_ = kAnchorY - kRest - p.m * kG / p.k;
    SoftBodyDef d;
    d.solver = SoftSolver::MassSpring;
    d.method = method_;
    d.substeps = 1;
    d.forces.gravity = Vec3(0, -kG, 0);
    SpringDef sp;
    sp.a = Vec3(0, kAnchorY, 0);
    sp.b = Vec3(0, y_eq_ - p.amplitude, 0);
    sp.rest_length = kRest;
    sp.mass = p.m, sp.stiffness = p.k, sp.damping = p.c;
    body_ = SoftBody::spring(sp, d);
    // E_eq: the energy at rest in equilibrium, so E - E_eq = 1/2 m v^2 + 1/2 k u^2
    e_eq_ = 0.5 * p.k * (p.m * kG / p.k) * (p.m * kG / p.k) + p.m * kG * y_eq_;
    t_ = t_prev_ = 0;
    y_prev_draw_ = body_.position(1).y;
    failure_.clear();
    period_ = 0;
    last_up_ = -1;
    periods_.clear();
    energy_ratio_ = 1;
    hist_.Clear(), trail_.Clear();
    hist_.Push(0, {1, 1});
    trail_.Push(0, {y_prev_draw_});
    last_h_ = ctx_.settings.stepper.fixed_dt;
    // the measured limits depend only on the spring: cached across restarts
    if (!(g_measured_for == p) || !g_measured_valid) {
      for (std::size_t i = 0; i < kAllMethods.size(); ++i) g_measured[i] = measured_limit(kAllMethods[i], p);
      g_measured_for = p;
      g_measured_valid = true;
    }
    measured_ = g_measured;
  }

  void fail(const std::string& why) {
    failure_ = why;
    g_stopped = true;
  }

  // a new spring; after a stop the app reloads the sample (it holds the stop until then)
  void restart() {
    if (failure_.empty()) build();
    else ctx_.settings.restart = true;
  }

  // energy, period, trace and the blow-up check after each step
  void after_step(double y_prev, double dt) {
    y_prev_draw_ = y_prev;
    const double y = body_.position(1).y;
    const double u = y - y_eq_;
    const double e = body_.kinetic_energy() + body_.potential_energy() - e_eq_;
    energy_ratio_ = e / (0.5 * params_.k * params_.amplitude * params_.amplitude);
    // upward crossings of the equilibrium, interpolated: the period is their spacing
    const double u_prev = y_prev - y_eq_;
    if (u_prev < 0 && u >= 0) {
      const double tc = t_prev_ + dt * (-u_prev) / (u - u_prev);
      if (last_up_ >= 0) {
        periods_.push_back(tc - last_up_);
        if (periods_.size() > 3) periods_.erase(periods_.begin());
        period_ = 0;
        for (double q : periods_) period_ += q / static_cast<double>(periods_.size());
      }
      last_up_ = tc;
    }
    // histories: the exact and the simulated energy ratio, the height for the trace
    hist_.Push(t_, {exact_energy(t_), energy_ratio_});
    trail_.Push(t_, {y});
    // blown up: stop with the reason, in the method's terms; the growth factor is the
    // energy's per step, rho^2 with rho the spectral radius of one step on the undamped
    // oscillator (lab::spectral_radius; 1 + (omega h)^2 for explicit Euler)
    if (!(std::abs(u) < kBlowUp * params_.amplitude)) {
      const double wh = omega() * dt, lim = StabilityLimit(method_);
      const double rho = lab::spectral_radius(method_, wh);
      const char* undamped = params_.c > 0 ? " (undamped)" : "";
      char buf[360];
      if (lim <= 0)
        std::snprintf(buf, sizeof buf,
                      "%s blew up at t = %.2f s: the mass is %.3g m from equilibrium (%gx the start). It gains "
                      "energy at every step size: x%.4f per step%s at omega h = %.3f.",
                      std::string(label(method_)).c_str(), t_, std::abs(u), kBlowUp, rho * rho, undamped, wh);
      else
        std::snprintf(buf, sizeof buf,
                      "%s blew up at t = %.2f s: the mass is %.3g m from equilibrium (%gx the start). omega h = %.3f "
                      "is above its limit %.3f, so the energy grows x%.4f per step%s: use dt < %.4f s.",
                      std::string(label(method_)).c_str(), t_, std::abs(u), kBlowUp, wh, lim, rho * rho, undamped,
                      lim / omega());
      fail(buf);
    }
  }

  Params params_;
  SoftBody body_;
  Method method_ = Method::SemiImplicitEuler;
  double t_ = 0, t_prev_ = 0, y_prev_draw_ = 0, y_eq_ = 0, e_eq_ = 0, last_h_ = 1.0 / 60;
  double energy_ratio_ = 1, period_ = 0, last_up_ = -1;
  std::vector<double> periods_;
  PlotHistory hist_{2, 20.0};      // exact and simulated E/E0 over the last 20 s
  PlotHistory trail_{1, kTrail};  // the height (m) over the last kTrail s
  std::array<double, kAllMethods.size()> measured_{};
  std::string failure_;

  static inline std::array<double, kAllMethods.size()> g_measured{};
  static inline Params g_measured_for{};
  static inline bool g_measured_valid = false;
};

static int reg = RegisterSample("Soft bodies", "Spring", SpringSample::Create);

}  // namespace
}  // namespace pba::app
