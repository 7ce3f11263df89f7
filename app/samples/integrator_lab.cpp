// "Dynamics/Integrator lab" (workbook 3.2.4): the accuracy lab of pba/lab.h, live. For the
// chosen problem it measures every method's global error at t_end against dt (log-log, with
// the observed order), the energy error over a long run, and shows the measured stability
// limits. The 3D view shows each method's run at one of the measured steps next to the
// exact solution. The measurements advance a little every frame, so the UI stays live and
// the plots fill in as the numbers arrive.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "method_colors.h"
#include "plot.h"
#include "pba/lab.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int kMethodCount = static_cast<int>(kAllMethods.size());

// work per frame: a wall-clock limit live, a fixed number of acceleration evaluations in
// headless capture (so the frames are the same on every run and every machine)
constexpr double kLiveBudgetSeconds = 0.012;
constexpr long long kHeadlessBudgetEvals = 120000;
constexpr long long kChunkEvals = 4096;  // evaluations between clock checks

// points kept of each run's path for the 3D view, and of each long run for the plot
constexpr long long kPathPoints = 600;
constexpr long long kEnergyUniformPoints = 1000;
// |dE/E0| and errors below this are drawn at it (log axes have no zero)
constexpr double kFloor = 1e-16;

// acceleration evaluations per step, roughly (implicit Euler: a few Newton iterations)
long long StepCost(Method m) {
  switch (m) {
    case Method::VelocityVerlet: return 2;
    case Method::Rk4: return 4;
    case Method::ImplicitEuler: return 6;
    default: return 1;
  }
}

// line width in the plots: explicit Euler and position Verlet wider, so where their curves
// coincide with implicit Euler's and velocity Verlet's they show as a coloured rim
float PlotWidth(Method m) { return m == Method::ExplicitEuler || m == Method::PositionVerlet ? 4.0f : 1.8f; }

// short names for the legends
const char* ShortName(Method m) {
  switch (m) {
    case Method::ExplicitEuler: return "Euler";
    case Method::SemiImplicitEuler: return "Semi-impl.";
    case Method::PositionVerlet: return "Verlet";
    case Method::VelocityVerlet: return "Vel. Verlet";
    case Method::Rk4: return "RK4";
    case Method::ImplicitEuler: return "Implicit";
  }
  return "";
}

std::string Fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// how much work this frame may still do
class Budget {
 public:
  Budget(bool fixed, long long evals) : fixed_(fixed), evals_(evals), start_(std::chrono::steady_clock::now()) {}
  bool left() const {
    if (fixed_) return evals_ > 0;
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count() < kLiveBudgetSeconds;
  }
  void spend(long long evals) { evals_ -= std::max(evals, 1LL); }

 private:
  bool fixed_;
  long long evals_;
  std::chrono::steady_clock::time_point start_;
};

// one resumable run of a problem: a method, a step and a step count
struct Run {
  Integrator<double> integ = Integrator<double>(Method::SemiImplicitEuler);
  std::vector<double> x, v;
  double dt = 0;
  long long steps = 0, done = 0;
  std::string failure;  // the solver failed or the state became non-finite

  void start(const lab::Problem& p, Method m, double step, long long count) {
    integ = Integrator<double>(m);
    integ.resize(p.x0.size());
    x = p.x0;
    v = p.v0;
    dt = step;
    steps = count;
    done = 0;
    failure.clear();
  }
  bool finished() const { return done >= steps || !failure.empty(); }

  // up to `max_steps` steps; after(k) runs after step k and returns false to stop the run
  // (a non-finite value); returns the acceleration evaluations spent
  template <class After>
  long long advance(const lab::Problem& p, long long max_steps, After&& after) {
    const long long evals0 = integ.evaluations();
    const long long end = std::min(steps, done + max_steps);
    try {
      while (done < end) {
        // time from the step index, as the lab does, so it does not drift
        integ.step(static_cast<double>(done) * dt, dt, std::span<double>(x), std::span<double>(v), p.accel);
        ++done;
        if (!after()) break;
      }
    } catch (const Error& e) {
      failure = e.what();  // e.g. implicit Euler's Newton failing near the orbit's centre
    }
    const FiniteCheck c = check_finite<double>(x, v, "coordinate", static_cast<double>(done) * dt, done);
    if (!c.ok && failure.empty()) failure = c.message;
    return integ.evaluations() - evals0;
  }
};

// one point of the convergence study: a method at one step size
struct ConvPoint {
  double dt = 0;
  long long steps = 0;
  double error = kNaN;        // max |x - x_ref| over coordinates at t_end; inf: diverged
  std::string failure;        // why the run stopped early, if it did
  bool done = false, fitted = false;
  std::vector<float> path;    // the run in view coordinates (pairs), for the 3D view
  long long path_stride = 1;  // steps between path points
};

// one method's convergence line
struct ConvLine {
  std::vector<ConvPoint> pts;  // coarse to fine
  double order = kNaN;         // fitted slope; NaN: fewer than 3 usable points
  int done = 0;                // points measured (a prefix: coarse ones first)
};

// one method's long run for the energy error
struct EnergyLine {
  Run run;
  double e0 = 0, norm = 1;
  double peak = 0;              // largest |dE/E0| since the last recorded point
  long long next_record = 1;
  std::vector<float> t, err;    // recorded points: time (s), peak |dE/E0| in the interval
};

class IntegratorLab final : public Sample {
 public:
  explicit IntegratorLab(SampleContext& ctx) : Sample(ctx), problems_(lab::standard_problems()) {
    ctx.renderer->style.grid_spacing = 0.5f;
    // --option problem=NAME picks the problem on the first load (lab names)
    const std::string name = ctx.option("problem", "");
    if (!name.empty() && !options_read_) {
      const lab::Problem& p = lab::find_problem(problems_, name, "--option problem");
      g_problem = static_cast<int>(&p - problems_.data());
    }
    options_read_ = true;
    for (int i = 0; i < kMethodCount; ++i) stability_[i] = lab::measure_stability(kAllMethods[i]);
    select_problem(std::clamp(g_problem, 0, static_cast<int>(problems_.size()) - 1));
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<IntegratorLab>(ctx); }

  bool OwnsTime() const override { return true; }

  void Update(double frame_dt) override {
    // the animation of the 3D view follows the frame clock; the measurements do not
    if (!ctx_.settings.paused) anim_ += frame_dt;
    // a slice of measuring: convergence and long runs take turns in small chunks
    Budget budget(ctx_.virtual_time, kHeadlessBudgetEvals);
    while (budget.left() && (!convergence_done() || !energy_done())) {
      if (!convergence_done()) budget.spend(work_convergence(kChunkEvals));
      if (!energy_done() && budget.left()) budget.spend(work_energy(kChunkEvals));
    }
  }

  void Draw(Renderer& r, double) override {
    const lab::Problem& p = problem();
    // title and the meaning of the picture
    const Vec3 top(0, kRowY[0] + kHalf + 0.95, 0);
    if (ctx_.settings.show_labels) {
      r.text(top, p.description, colors::white, 1.1f, 0.5f);
      const std::string how = std::string(two_d_ ? "path y against x" : "phase portrait: v/w against x") +
                              ", every run at dt = " + Fmt("%.3g", view_dt()) + " s to t_end = " +
                              Fmt("%.3g", p.t_end) + " s; white: exact";
      r.text(top - Vec3(0, 0.38, 0), how, Color{0.78f, 0.80f, 0.84f, 1}, 0.9f, 0.5f);
    }
    // where the animated dots are: a loop over [0, t_end], holding at the end a moment
    const double loop = 4.0, hold = 0.8;
    const double u = std::min(1.0, std::fmod(anim_, loop + hold) / loop);
    for (int i = 0; i < kMethodCount; ++i)
      if (visible_[i]) draw_cell(r, i, u);
  }

  void DrawUI() override {
    const lab::Problem& p = problem();
    // problem
    int sel = g_problem;
    ImGui::SetNextItemWidth(-60);
    if (ImGui::BeginCombo("problem", p.name.c_str())) {
      for (int i = 0; i < static_cast<int>(problems_.size()); ++i) {
        if (ImGui::Selectable(problems_[i].name.c_str(), i == sel)) sel = i;
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", problems_[i].description.c_str());
      }
      ImGui::EndCombo();
    }
    if (sel != g_problem) {
      select_problem(sel);
      return;
    }

    // methods: toggle, observed order (theory), stability limit measured (theory)
    ImGui::PushStyleVar(ImGuiStyleVar_FramePadding, ImVec2(2, 1));
    if (ImGui::BeginTable("methods", 3, ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("method", ImGuiTableColumnFlags_WidthStretch, 2.75f);
      ImGui::TableSetupColumn("order (th.)", ImGuiTableColumnFlags_WidthStretch, 1.3f);
      ImGui::TableSetupColumn("max w\u00b7dt (th.)", ImGuiTableColumnFlags_WidthStretch, 1.6f);
      ImGui::TableHeadersRow();
      for (int i = 0; i < kMethodCount; ++i) {
        const Method m = kAllMethods[i];
        const Color c = MethodColor(m);
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::PushID(i);
        ImGui::PushStyleColor(ImGuiCol_CheckMark, ImVec4(c.r, c.g, c.b, 1));
        ImGui::Checkbox("##vis", &visible_[i]);
        ImGui::PopStyleColor();
        ImGui::PopID();
        ImGui::SameLine();
        ImGui::TextColored(ImVec4(c.r, c.g, c.b, 1), "%s", std::string(label(m)).c_str());
        ImGui::TableNextColumn();
        ImGui::Text("%s (%d)", order_text(i).c_str(), order(m));
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", order_note(i).c_str());
        ImGui::TableNextColumn();
        ImGui::Text("%s (%s)", limit_text(stability_[i].limit).c_str(), limit_text(stability_[i].theory).c_str());
      }
      ImGui::EndTable();
    }
    ImGui::PopStyleVar();
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("order: fitted slope of log error against log dt (theory in brackets)\n"
                        "max w\u00b7dt: measured stability limit on x'' = -w^2 x (theory in brackets)");

    // step sizes: the study's range (halvings of the coarsest) and the step the view shows
    float coarse = static_cast<float>(dt_coarse_), fine = static_cast<float>(dt_fine_);
    const float half = 0.5f * (ImGui::GetContentRegionAvail().x - 90 - ImGui::GetStyle().ItemSpacing.x);
    ImGui::SetNextItemWidth(half);
    ImGui::SliderFloat("##fine", &fine, static_cast<float>(p.t_end / 2e6), static_cast<float>(dt_coarse_ / 4),
                       "%.3g s", ImGuiSliderFlags_Logarithmic);
    const bool fine_done = ImGui::IsItemDeactivatedAfterEdit();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("finest dt of the study (halvings of the coarsest)");
    ImGui::SameLine();
    ImGui::SetNextItemWidth(half);
    ImGui::SliderFloat("dt range", &coarse, static_cast<float>(p.t_end / 2000), static_cast<float>(p.t_end / 4),
                       "%.3g s", ImGuiSliderFlags_Logarithmic);
    const bool coarse_done = ImGui::IsItemDeactivatedAfterEdit();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("coarsest dt of the study");
    if (coarse_done || fine_done) set_range(coarse, fine);
    int level = view_level_;
    char fmt[64];
    std::snprintf(fmt, sizeof fmt, "%.3g s (dt %d of %d)", view_dt(), view_level_ + 1, levels());
    ImGui::SetNextItemWidth(-90);
    if (ImGui::SliderInt("view dt", &level, 0, levels() - 1, fmt)) view_level_ = std::clamp(level, 0, levels() - 1);

    // convergence: error at t_end against dt, with reference slopes through the coarse end
    conv_plot();
    // energy error over the long run
    energy_plot();
    ImGui::TextWrapped("%s", explanation());
  }

  std::vector<Color> ExpectedColors() const override {
    std::vector<Color> c;
    for (int i = 0; i < kMethodCount; ++i)
      if (visible_[i]) c.push_back(MethodColor(kAllMethods[i]));
    return c;
  }

 private:
  // the choice of problem survives a restart (R) and a sample switch
  static inline int g_problem = 2;  // the undamped oscillator
  static inline bool options_read_ = false;  // the command line applies to the first load only
  // the 3D layout: cells of half-size kHalf in 3 columns and 2 rows
  static constexpr double kHalf = 1.1, kColX = 2.75;
  static constexpr std::array<double, 2> kRowY = {4.75, 1.55};

  const lab::Problem& problem() const { return problems_[static_cast<std::size_t>(g_problem)]; }
  int levels() const { return static_cast<int>(conv_[0].pts.size()); }
  double view_dt() const { return conv_[0].pts[static_cast<std::size_t>(view_level_)].dt; }

  // ---- set-up ----------------------------------------------------------------------

  void select_problem(int index) {
    g_problem = index;
    const lab::Problem& p = problem();
    two_d_ = p.x0.size() >= 2;
    w_ = p.omega > 0 ? p.omega : 1.0;
    dt_coarse_ = p.dt_coarse;
    dt_fine_ = p.dt_coarse / 512;  // the lab's 10 levels
    energy_steps_ = std::min<long long>(lab::EnergySettings{}.steps, 1000000);
    view_level_ = 0;
    anim_ = 0;
    // the exact path, which also sets the 3D cells' scale
    exact_path_.clear();
    if (p.exact) {
      std::vector<double> x(p.x0.size()), v(p.x0.size());
      for (int k = 0; k <= 400; ++k) {
        p.exact(p.t_end * k / 400.0, x, v);
        push_view(exact_path_, x, v);
      }
    }
    restart_convergence();
    restart_energy();
    fit_view_box();
    // a straight view of the six cells
    ctx_.camera->frame({0.0f, 3.45f, 0.0f}, 4.3f, 0.0f, 0.06f);
  }

  // the study's step sizes: halvings of the coarsest down to the finest
  void set_range(double coarse, double fine) {
    const lab::Problem& p = problem();
    dt_coarse_ = std::clamp(coarse, p.t_end / 2000, p.t_end / 4);
    dt_fine_ = std::clamp(fine, p.t_end / 2e6, dt_coarse_ / 4);
    restart_convergence();
    if (exact_path_.empty()) fit_view_box();
  }

  void restart_convergence() {
    const lab::Problem& p = problem();
    const int n = std::clamp(static_cast<int>(std::floor(std::log2(dt_coarse_ / dt_fine_) + 1e-9)) + 1, 2, 20);
    view_level_ = std::min(view_level_, n - 1);
    for (ConvLine& line : conv_) {
      line = ConvLine{};
      for (int k = 0; k < n; ++k) {
        // as the lab does: the step count rounded, and dt adjusted to land on t_end
        ConvPoint pt;
        pt.steps = std::max(1LL, std::llround(p.t_end / std::ldexp(dt_coarse_, -k)));
        pt.dt = p.t_end / static_cast<double>(pt.steps);
        pt.path_stride = std::max(1LL, pt.steps / kPathPoints);
        line.pts.push_back(std::move(pt));
      }
    }
    // the reference at t_end: closed form, or RK4 with 8x the finest step count
    x_ref_.assign(p.x0.size(), 0);
    v_ref_.assign(p.x0.size(), 0);
    need_ref_ = !p.exact;
    if (p.exact) p.exact(p.t_end, x_ref_, v_ref_);
    else ref_run_.start(p, Method::Rk4, p.t_end / (8.0 * conv_[0].pts.back().steps), 8 * conv_[0].pts.back().steps);
    ref_path_.clear();
    job_level_ = job_method_ = 0;
    job_active_ = false;
  }

  void restart_energy() {
    const lab::Problem& p = problem();
    for (int i = 0; i < kMethodCount; ++i) {
      EnergyLine& e = energy_[i];
      e = EnergyLine{};
      if (!p.energy) continue;
      e.run.start(p, kAllMethods[i], p.energy_dt, energy_steps_);
      e.e0 = p.energy(p.x0, p.v0);
      e.norm = e.e0 != 0 ? std::abs(e.e0) : 1.0;
    }
    xe_.assign(p.x0.size(), 0);
    ve_.assign(p.x0.size(), 0);
    energy_next_ = 0;
  }

  // the view's coordinates: (x, y) for a path, (x, v/w) for a phase portrait
  void push_view(std::vector<float>& out, std::span<const double> x, std::span<const double> v) const {
    out.push_back(static_cast<float>(x[0]));
    out.push_back(static_cast<float>(two_d_ ? x[1] : v[0] / w_));
  }

  // the cells' box around the exact path with a margin; one scale unless very elongated
  void fit_view_box() {
    const std::vector<float>& path = exact_path_.empty() ? ref_path_ : exact_path_;
    double lo[2] = {kInf, kInf}, hi[2] = {-kInf, -kInf};
    for (std::size_t k = 0; k + 1 < path.size(); k += 2)
      for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], double(path[k + a])), hi[a] = std::max(hi[a], double(path[k + a]));
    if (!(hi[0] >= lo[0])) lo[0] = lo[1] = -1, hi[0] = hi[1] = 1;
    double span[2];
    for (int a = 0; a < 2; ++a) {
      span[a] = std::max(hi[a] - lo[a], 1e-9 * std::max(1.0, std::abs(hi[a])));
      box_mid_[a] = 0.5 * (lo[a] + hi[a]);
    }
    const double big = std::max(span[0], span[1]);
    for (int a = 0; a < 2; ++a) {
      // equal scales keep circles round; an elongated path (a projectile) gets its own
      const double s = big > 2.5 * std::min(span[0], span[1]) ? std::max(span[a], 0.4 * big) : big;
      box_scale_[a] = 0.85 * 2 * kHalf / s;
    }
  }

  // ---- measuring -------------------------------------------------------------------

  bool convergence_done() const { return !need_ref_ && job_level_ >= levels(); }
  bool energy_done() const {
    for (const EnergyLine& e : energy_)
      if (e.run.steps > 0 && !e.run.finished()) return false;
    return true;
  }

  // runs of the study in order: every method at the coarsest dt, then the next dt, ...
  long long work_convergence(long long evals) {
    const lab::Problem& p = problem();
    if (need_ref_) {
      // the RK4 reference when the problem has no closed form
      const long long stride = std::max(1LL, ref_run_.steps / kPathPoints);
      if (ref_run_.done == 0) push_view(ref_path_, ref_run_.x, ref_run_.v);
      const long long spent = ref_run_.advance(p, std::max(1LL, evals / 4), [&] {
        if (ref_run_.done % stride == 0 || ref_run_.done == ref_run_.steps) push_view(ref_path_, ref_run_.x, ref_run_.v);
        return true;
      });
      if (ref_run_.finished()) {
        x_ref_ = ref_run_.x;
        v_ref_ = ref_run_.v;
        need_ref_ = false;
        fit_view_box();
      }
      return spent;
    }
    const Method m = kAllMethods[job_method_];
    ConvLine& line = conv_[job_method_];
    ConvPoint& pt = line.pts[static_cast<std::size_t>(job_level_)];
    if (!job_active_) {
      job_.start(p, m, pt.dt, pt.steps);
      pt.path.clear();
      push_view(pt.path, job_.x, job_.v);
      job_active_ = true;
    }
    const long long spent = job_.advance(p, std::max(1LL, evals / StepCost(m)), [&] {
      if (job_.done % pt.path_stride == 0 || job_.done == job_.steps) push_view(pt.path, job_.x, job_.v);
      return true;
    });
    if (job_.finished()) {
      // the global error at t_end, or infinity for a run that diverged
      double err = job_.failure.empty() ? 0.0 : kInf;
      for (std::size_t c = 0; c < p.x0.size() && job_.failure.empty(); ++c)
        err = std::max(err, std::abs(job_.x[c] - x_ref_[c]));
      if (!std::isfinite(err)) err = kInf;
      pt.error = err;
      pt.failure = job_.failure;
      pt.done = true;
      line.done = job_level_ + 1;
      fit_order(line, m);
      job_active_ = false;
      if (++job_method_ == kMethodCount) job_method_ = 0, ++job_level_;
    }
    return spent;
  }

  // the long runs take turns, so all six curves grow together
  long long work_energy(long long evals) {
    const lab::Problem& p = problem();
    for (int tries = 0; tries < kMethodCount; ++tries) {
      const int i = energy_next_;
      energy_next_ = (energy_next_ + 1) % kMethodCount;
      EnergyLine& e = energy_[i];
      if (e.run.steps == 0 || e.run.finished()) continue;
      const long long uniform = std::max(1LL, e.run.steps / kEnergyUniformPoints);
      // the energy (and the exact state of a dissipative problem) count as evaluations too
      const long long done0 = e.run.done, extra = p.dissipative ? 3 : 1;
      const long long spent = e.run.advance(p, std::max(1LL, evals / (StepCost(kAllMethods[i]) + extra)), [&] {
        // energy against the reference: initial, or the exact solution's for dissipative problems
        const double t1 = static_cast<double>(e.run.done) * e.run.dt;
        double e_ref = e.e0;
        if (p.dissipative) {
          p.exact(t1, xe_, ve_);
          e_ref = p.energy(xe_, ve_);
        }
        const double rel = std::abs((p.energy(e.run.x, e.run.v) - e_ref) / e.norm);
        if (!std::isfinite(rel)) return false;
        e.peak = std::max(e.peak, rel);
        // points: every step at first, then 1% apart in time, then evenly spaced
        if (e.run.done >= e.next_record || e.run.done == e.run.steps) {
          e.t.push_back(static_cast<float>(t1));
          e.err.push_back(static_cast<float>(std::clamp(e.peak, kFloor, 1e30)));
          e.peak = 0;
          e.next_record = e.run.done + std::max(1LL, std::min(uniform, e.run.done / 100));
        }
        return true;
      });
      return spent + extra * (e.run.done - done0);
    }
    return 0;
  }

  // the lab's order fit (lab::fit_order, the rule lab::measure_convergence uses) over
  // the points measured so far
  void fit_order(ConvLine& line, Method m) const {
    const std::size_t count = static_cast<std::size_t>(line.done);
    std::vector<double> dts(count), errors(count);
    std::vector<long long> steps(count);
    for (std::size_t i = 0; i < count; ++i) {
      dts[i] = line.pts[i].dt;
      errors[i] = line.pts[i].error;
      steps[i] = line.pts[i].steps;
    }
    double scale = 1;
    for (double xr : x_ref_) scale = std::max(scale, std::abs(xr));
    std::vector<bool> fitted;
    line.order = lab::fit_order(m, dts, errors, steps, scale, problem().model_error,
                                lab::ConvergenceSettings{}, fitted);
    for (std::size_t i = 0; i < line.pts.size(); ++i) line.pts[i].fitted = i < count && fitted[i];
  }

  // ---- panel -----------------------------------------------------------------------

  std::string order_text(int i) const {
    const ConvLine& line = conv_[i];
    const bool final = line.done == levels();
    // as the lab's table: "exact" at round-off, "-" under the closed form's model error
    if (std::isnan(line.order)) return final ? (problem().model_error > 0 ? "-" : "exact") : "...";
    return (final ? "" : "~") + Fmt("%.2f", line.order);
  }

  std::string order_note(int i) const {
    const ConvLine& line = conv_[i];
    if (line.done < levels()) return "measuring: " + std::to_string(line.done) + " of " + std::to_string(levels()) + " step sizes";
    if (std::isnan(line.order))
      return problem().model_error > 0 ? "error below the closed form's own model error (or round-off)"
                                       : "error at round-off for every dt: the method is exact here";
    // the fitted window
    double lo = kInf, hi = 0;
    for (const ConvPoint& pt : line.pts)
      if (pt.fitted) lo = std::min(lo, pt.dt), hi = std::max(hi, pt.dt);
    return "least-squares slope of log error against log dt, fitted on dt = " + Fmt("%.3g", lo) + " to " +
           Fmt("%.3g", hi) + " s";
  }

  // a short reason for a run that stopped
  static std::string failure_text(const std::string& failure) {
    return failure.find("Newton") != std::string::npos ? "Newton failed" : "non-finite";
  }

  // a step count: 1e6 for a power of ten, else the number
  static std::string count_text(long long n) {
    const int e = static_cast<int>(std::lround(std::log10(static_cast<double>(n))));
    return std::llround(std::pow(10.0, e)) == n && e >= 4 ? "1e" + std::to_string(e) : std::to_string(n);
  }

  static std::string limit_text(double z) {
    if (std::isinf(z)) return "any";
    if (z == 0) return "0";
    if (z < 1e-3) return Fmt("%.0e", z);
    return Fmt("%.3g", z);
  }

  void conv_plot() {
    const lab::Problem& p = problem();
    // per method: dt and error as floats, errors floored for the log axis
    std::vector<PlotSeries> series;
    std::array<std::vector<float>, kMethodCount> xs, ys;
    float top = 0;
    for (int i = 0; i < kMethodCount; ++i) {
      const ConvLine& line = conv_[i];
      for (int k = 0; k < line.done; ++k) {
        const ConvPoint& pt = line.pts[static_cast<std::size_t>(k)];
        xs[i].push_back(static_cast<float>(pt.dt));
        ys[i].push_back(std::isfinite(pt.error) ? static_cast<float>(std::max(pt.error, kFloor)) : kNaN);
        if (visible_[i] && k == 0 && std::isfinite(pt.error)) top = std::max(top, static_cast<float>(pt.error));
      }
      // increasing dt for the plot
      std::reverse(xs[i].begin(), xs[i].end());
      std::reverse(ys[i].begin(), ys[i].end());
    }
    // reference slopes 1, 2 and 4 fanning out from the largest coarse error
    std::array<std::vector<float>, 3> rx, ry;
    const int slopes[3] = {1, 2, 4};
    if (top > 0) {
      for (int s = 0; s < 3; ++s) {
        for (int k = 0; k <= 32; ++k) {
          const double dt = dt_fine_ * std::pow(dt_coarse_ / dt_fine_, k / 32.0);
          rx[s].push_back(static_cast<float>(dt));
          ry[s].push_back(static_cast<float>(3.0 * top * std::pow(dt / dt_coarse_, slopes[s])));
        }
        PlotSeries ref;
        ref.x = rx[s].data();
        ref.y = ry[s].data();
        ref.count = static_cast<int>(rx[s].size());
        ref.color = Color{1, 1, 1, 0.22f};
        ref.width = 1.0f;
        ref.tag = "slope " + std::to_string(slopes[s]);
        series.push_back(ref);
      }
    }
    for (int i = 0; i < kMethodCount; ++i) {
      if (!visible_[i] || xs[i].empty()) continue;
      PlotSeries s;
      s.x = xs[i].data();
      s.y = ys[i].data();
      s.count = static_cast<int>(xs[i].size());
      s.color = MethodColor(kAllMethods[i]);
      s.width = PlotWidth(kAllMethods[i]);
      s.marker = 2.4f;
      s.label = std::string(ShortName(kAllMethods[i])) + " " + order_text(i);
      series.push_back(s);
    }
    PlotAxes ax;
    ax.x_log = ax.y_log = true;
    ax.x_lo = static_cast<float>(conv_[0].pts.back().dt / 1.15), ax.x_hi = static_cast<float>(dt_coarse_ * 1.15);
    ax.y_clamp_lo = static_cast<float>(kFloor), ax.y_clamp_hi = 1e3f;
    ax.x_label = "dt (s)";
    int done = 0, total = 0;
    for (const ConvLine& line : conv_) done += line.done, total += static_cast<int>(line.pts.size());
    ax.y_label = "error at t_end = " + Fmt("%g", p.t_end) + " s" +
                 (done < total ? "  (measuring " + std::to_string(100 * done / total) + "%)" : "");
    ax.x_marks = {static_cast<float>(view_dt())};
    ax.legend = PlotCorner::Below;
    LinePlot("convergence", series, ax, 182);
  }

  void energy_plot() {
    const lab::Problem& p = problem();
    if (!p.energy) {
      ImGui::TextDisabled("this problem has no energy function");
      return;
    }
    std::vector<PlotSeries> series;
    double progress = 0;
    for (int i = 0; i < kMethodCount; ++i) {
      const EnergyLine& e = energy_[i];
      progress += e.run.finished() ? 1.0 : static_cast<double>(e.run.done) / static_cast<double>(e.run.steps);
      if (!visible_[i] || e.t.empty()) continue;
      PlotSeries s;
      s.x = e.t.data();
      s.y = e.err.data();
      s.count = static_cast<int>(e.t.size());
      s.color = MethodColor(kAllMethods[i]);
      s.width = PlotWidth(kAllMethods[i]) - 0.3f;
      series.push_back(s);
      // a run that stopped early ends in a dot saying why
      if (!e.run.failure.empty()) {
        PlotSeries stop = s;
        stop.x = &e.t.back();
        stop.y = &e.err.back();
        stop.count = 1;
        stop.marker = 3.5f;
        stop.tag = failure_text(e.run.failure) + " at t = " + Fmt("%.3g", e.t.back()) + " s";
        series.push_back(stop);
      }
    }
    progress /= kMethodCount;
    ImGui::Checkbox("log t", &log_t_);
    ImGui::SameLine();
    ImGui::TextDisabled("energy error over %s steps of %.3g s", count_text(energy_steps_).c_str(), p.energy_dt);
    PlotAxes ax;
    ax.x_log = log_t_;
    ax.y_log = true;
    const double t_max = static_cast<double>(energy_steps_) * p.energy_dt;
    ax.x_lo = static_cast<float>(log_t_ ? p.energy_dt : 0.0), ax.x_hi = static_cast<float>(t_max);
    ax.y_clamp_lo = static_cast<float>(kFloor), ax.y_clamp_hi = 1e3f;
    ax.x_label = "t (s)";
    ax.y_label = std::string(p.dissipative ? "|E - E_exact(t)| / |E0|" : "|E - E0| / |E0|") +
                 (progress < 1 ? "  (" + std::to_string(static_cast<int>(100 * progress)) + "%)" : "");
    LinePlot("energy", series, ax, 118);
  }

  const char* explanation() const {
    const std::string& n = problem().name;
    if (n == "projectile")
      return "Constant gravity: both Verlets and RK4 are exact on a parabola (error at round-off, "
             "no order); the Euler pair is first order.";
    if (n == "projectile-drag")
      return "Drag depends on velocity, so every method shows its order. Energy is compared with "
             "the exact, decaying energy.";
    if (n == "oscillator")
      return "Slope = order: halving dt divides the error by 2^order, down to round-off. Energy: "
             "Euler grows, implicit Euler decays, symplectic stays bounded.";
    if (n == "damped-oscillator")
      return "A velocity-dependent force. Energy is compared with the exact, decaying energy, so "
             "its error dies away with the motion.";
    if (n == "pendulum-small")
      return "The reference is the small-angle formula, itself slightly off: errors below 10x its "
             "model error are not fitted.";
    if (n == "pendulum-large")
      return "A 2.5 rad swing, exact through Jacobi elliptic functions: nonlinear, yet each method "
             "keeps its order once dt is small.";
    if (n == "orbit")
      return "Kepler ellipse, e = 0.5: the fast periapsis pass sets the error. Explicit Euler "
             "spirals out, implicit Euler in, symplectic stays bounded.";
    if (n == "orbit-circular")
      return "A circular orbit: explicit Euler spirals out, implicit Euler in, the symplectic "
             "methods keep the radius.";
    return "";
  }

  // ---- 3D view ---------------------------------------------------------------------

  Vec3 cell_center(int i) const { return Vec3((i % 3 - 1) * kColX, kRowY[static_cast<std::size_t>(i / 3)], 0); }

  // a view point (path or phase coordinates) in cell i's world frame, `depth` behind it
  Vec3 to_world(int i, double a, double b, double depth = 0) const {
    return cell_center(i) + Vec3((a - box_mid_[0]) * box_scale_[0], (b - box_mid_[1]) * box_scale_[1], -depth);
  }

  bool in_cell(int i, const Vec3& q) const {
    const Vec3 d = q - cell_center(i);
    return std::abs(d.x) <= kHalf && std::abs(d.y) <= kHalf;
  }

  // a path in view coordinates, cut where it leaves the cell
  void draw_path(Renderer& r, int i, const std::vector<float>& path, Color c, float width, double depth = 0) const {
    std::vector<Vec3> run;
    for (std::size_t k = 0; k + 1 < path.size(); k += 2) {
      const Vec3 q = to_world(i, path[k], path[k + 1], depth);
      if (in_cell(i, q)) {
        run.push_back(q);
        continue;
      }
      if (run.size() > 1) r.polyline(run, c, width);
      run.clear();
    }
    if (run.size() > 1) r.polyline(run, c, width);
  }

  // the point of a recorded path at fraction u of the run (interpolated)
  Vec3 path_at(int i, const std::vector<float>& path, double u) const {
    const std::size_t n = path.size() / 2;
    if (n == 0) return cell_center(i);
    const double f = std::clamp(u, 0.0, 1.0) * static_cast<double>(n - 1);
    const std::size_t k = std::min(static_cast<std::size_t>(f), n - 1), k1 = std::min(k + 1, n - 1);
    const double w = f - static_cast<double>(k);
    return to_world(i, path[2 * k] + w * (path[2 * k1] - path[2 * k]), path[2 * k + 1] + w * (path[2 * k1 + 1] - path[2 * k + 1]));
  }

  void draw_cell(Renderer& r, int i, double u) {
    const Method m = kAllMethods[i];
    const Color c = MethodColor(m);
    const Vec3 o = cell_center(i);
    const Color frame{0.55f, 0.58f, 0.63f, 0.55f};
    // frame, and the axes through zero when they cross the cell
    const Vec3 a(o.x - kHalf, o.y - kHalf, 0), b(o.x + kHalf, o.y + kHalf, 0);
    r.polyline({a, Vec3(b.x, a.y, 0), b, Vec3(a.x, b.y, 0), a}, frame, 1.0f);
    const Vec3 zero = to_world(i, 0, 0);
    if (std::abs(zero.y - o.y) < kHalf) r.line(Vec3(a.x, zero.y, 0), Vec3(b.x, zero.y, 0), Color{1, 1, 1, 0.12f}, 1.0f);
    if (std::abs(zero.x - o.x) < kHalf) r.line(Vec3(zero.x, a.y, 0), Vec3(zero.x, b.y, 0), Color{1, 1, 1, 0.12f}, 1.0f);
    // the exact solution: path and ghost
    const std::vector<float>& exact = exact_path_.empty() ? ref_path_ : exact_path_;
    // (a little behind the runs, so a run on top of it is not striped by it)
    draw_path(r, i, exact, Color{1, 1, 1, 0.5f}, 1.5f, 0.03);
    if (!exact.empty()) r.sphere(path_at(i, exact, u), 0.075, Color{0.92f, 0.94f, 1.0f, 0.35f});
    // the method's run at the view dt (as far as it has been measured)
    const ConvPoint& pt = conv_[i].pts[static_cast<std::size_t>(view_level_)];
    draw_path(r, i, pt.path, c, 2.5f);
    std::string err = "measuring...";
    if (pt.done) {
      if (!std::isfinite(pt.error)) {
        const double t_stop = static_cast<double>(pt.path_stride) * static_cast<double>(pt.path.size() / 2 - 1) * pt.dt;
        err = pt.failure.empty() ? "diverged" : failure_text(pt.failure) + " near t = " + Fmt("%.3g", t_stop) + " s";
      } else {
        // where the error is measured: the run's end against the exact end
        const Vec3 end = to_world(i, pt.path[pt.path.size() - 2], pt.path.back());
        std::vector<float> ref;
        push_view(ref, x_ref_, v_ref_);
        const Vec3 ref_end = to_world(i, ref[0], ref[1]);
        if (in_cell(i, end)) r.point(end, 8.0f, c);
        if (in_cell(i, ref_end)) r.point(ref_end, 6.0f, colors::white);
        if (in_cell(i, end) && in_cell(i, ref_end)) r.line(end, ref_end, Color{1, 1, 1, 0.8f}, 1.5f);
        err = "error at t_end " + Fmt("%.1e", pt.error);
        if (!in_cell(i, end)) err += " (leaves the frame)";
      }
      if (pt.path.size() >= 2) {
        const Vec3 q = path_at(i, pt.path, u);
        if (in_cell(i, q)) r.sphere(q, 0.075, c);
      }
    }
    if (!ctx_.settings.show_labels) return;
    r.text(o + Vec3(0, kHalf + 0.22, 0), label(m), c, 1.0f, 0.5f);
    r.text(o - Vec3(0, kHalf + 0.22, 0), err, Color{0.80f, 0.82f, 0.86f, 1}, 0.85f, 0.5f);
  }

  std::vector<lab::Problem> problems_;
  std::array<lab::StabilityResult, kMethodCount> stability_;
  std::array<bool, kMethodCount> visible_ = {true, true, true, true, true, true};
  // the convergence study: one line per method, runs done one at a time
  std::array<ConvLine, kMethodCount> conv_;
  double dt_coarse_ = 0.05, dt_fine_ = 0.05 / 512;
  std::vector<double> x_ref_, v_ref_;
  Run job_, ref_run_;
  bool job_active_ = false, need_ref_ = false;
  int job_level_ = 0, job_method_ = 0;
  // the long runs
  std::array<EnergyLine, kMethodCount> energy_;
  long long energy_steps_ = 1000000;
  int energy_next_ = 0;
  std::vector<double> xe_, ve_;  // scratch for the exact state
  bool log_t_ = true;
  // the 3D view
  bool two_d_ = false;
  double w_ = 1;  // velocity scale of phase portraits (rad/s)
  std::vector<float> exact_path_, ref_path_;
  double box_mid_[2] = {0, 0}, box_scale_[2] = {1, 1};
  int view_level_ = 0;
  double anim_ = 0;
};

static int reg = RegisterSample("Dynamics", "Integrator lab", IntegratorLab::Create);

}  // namespace
}  // namespace pba::app
