// "Dynamics/Time stepping" (workbook 3.1): the four strategies of pba/time.h side by side,
// each driving its own bouncing ball from the same frame clock. A frame-rate limit, an
// artificial render delay (the workbook's doWork()) and an artificial physics cost per tick
// let the user provoke the physics stall and watch each strategy's answer: bigger ticks
// (per-frame), more ticks until the cap (max-step, fixed) or a thread that does not care
// how slowly frames are drawn (threaded). The white ghost is the exact ball at real time.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "physics_loop.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

constexpr double kGravity = 9.81;  // m/s^2
constexpr double kRadius = 0.3;    // m
constexpr double kDrop = 3.0;      // m, height of the ball's bottom at t = 0

Color StrategyColor(Strategy s) {
  switch (s) {
    case Strategy::PerFrame: return Color::hex(0xf76b15);
    case Strategy::MaxStep: return Color::hex(0xffc53d);
    case Strategy::Fixed: return Color::hex(0x46a758);
    case Strategy::Threaded: return Color::hex(0x7c9cff);
  }
  return colors::white;
}

// a ball falling under gravity onto y = radius, bouncing elastically
struct Ball {
  Vec3 x{0, kRadius + kDrop, 0};
  Vec3 v{0, 0, 0};

  // one tick with the chosen integrator, then the bounce
  void step(Integrator<Vec3>& integ, double t, double dt) {
    integ.step_one(t, dt, x, v, [](double, const Vec3&, const Vec3&) { return Vec3(0, -kGravity, 0); });
    if (x.y < kRadius) {
      x.y = 2 * kRadius - x.y;
      v.y = -v.y;
      integ.reset_history();  // position Verlet's velocity lives in its history
    }
  }
};

// the exact ball at time t: periodic free fall from kDrop with elastic bounces
double ExactHeight(double t) {
  const double tf = std::sqrt(2 * kDrop / kGravity);
  const double s = std::fmod(t + tf, 2 * tf) - tf;
  return kRadius + kDrop - 0.5 * kGravity * s * s;
}

// busy work standing in for an expensive physics tick (real time only)
void spin_for(double seconds) {
  if (seconds <= 0) return;
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
  }
}

// one strategy's lane: its stepper (or thread), its ball and its statistics
struct Lane {
  Strategy strategy = Strategy::Fixed;
  std::unique_ptr<TimeStepper> stepper;  // null for the threaded lane
  Integrator<Vec3> integ;
  Ball ball, ball_prev;
  FrameStats last;
  double sim_time = 0, dropped = 0, alpha = 1;
  int ticks = 0;
  std::vector<float> hist_t, hist_lag;
};

struct Snap {
  Vec3 x{0, kRadius + kDrop, 0};
};

class TimeStepping final : public Sample {
 public:
  explicit TimeStepping(SampleContext& ctx) : Sample(ctx) {
    ctx.camera->frame({0.0f, 1.9f, 0.0f}, 4.3f, 0.0f, 0.10f);
    // defaults that show the stall quickly; --option delay=, cost=, fps= preset the load
    settings_.fixed_dt = 1.0 / 60.0;
    settings_.ticks_per_frame = 1;
    settings_.max_dt = 1.0 / 240.0;
    settings_.max_ticks_per_frame = 8;
    settings_.max_frame_dt = 0.25;
    ctx.settings.render_delay_ms = number_option("delay", 0, 0, 1000);
    cost_ms_ = number_option("cost", 0, 0, 100);
    method_ = ctx.settings.method;
    ctx.settings.frame_limit_hz = number_option("fps", 0, 0, 1000);
    for (Strategy s : kStrategies) {
      lanes_.emplace_back();
      Lane& l = lanes_.back();
      l.strategy = s;
      l.integ = Integrator<Vec3>(ctx.settings.method);
      if (s != Strategy::Threaded) {
        StepperSettings st = settings_;
        st.strategy = s;
        l.stepper = std::make_unique<TimeStepper>(st);
      }
    }
    // the threaded lane: its ball belongs to the physics thread; the renderer reads snapshots
    if (ctx.virtual_time) clock_ = std::make_unique<ManualClock>(0);
    thread_ = std::make_unique<PhysicsThread>(
        settings_,
        [this](double t, double dt) {
          if (!ctx_.virtual_time) spin_for(cost_ms_.load() / 1000.0);
          const Method m = method_.load();
          if (thread_integ_.method() != m) thread_integ_.set_method(m);
          thread_ball_.step(thread_integ_, t, dt);
        },
        [this](const TickStamp& stamp) {
          snaps_.write_slot().x = thread_ball_.x;
          snaps_.publish(stamp);
        },
        clock_.get());
    thread_integ_ = Integrator<Vec3>(ctx.settings.method);
    thread_->start(ctx.settings.paused);
  }
  ~TimeStepping() override { thread_->stop(); }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<TimeStepping>(ctx); }

  bool OwnsTime() const override { return true; }

  void Update(double frame_dt) override {
    Settings& s = ctx_.settings;
    const bool step_once = s.paused && s.single_step;
    s.single_step = false;
    // the strategies on this thread, each from the same frame time
    for (Lane& l : lanes_) {
      if (!l.stepper) continue;
      StepperSettings st = settings_;
      st.strategy = l.strategy;
      if (!(l.stepper->settings() == st)) l.stepper->set_settings(st);
      if (l.integ.method() != s.method) l.integ.set_method(s.method);
      auto tick = [&](double t, double dt) {
        l.ball_prev = l.ball;
        // the artificial physics cost: real work, or virtual work the frame is charged for
        if (ctx_.virtual_time) ctx_.virtual_charge += cost_ms_.load() / 1000.0;
        else spin_for(cost_ms_.load() / 1000.0);
        l.ball.step(l.integ, t, dt);
      };
      if (s.paused) l.last = step_once ? l.stepper->single_step(tick) : FrameStats{};
      else l.last = l.stepper->advance(frame_dt, tick);
      l.alpha = l.strategy == Strategy::Fixed ? l.stepper->alpha() : 1.0;
      l.sim_time = l.stepper->time();
      l.dropped = l.stepper->totals().dropped_time;
      l.ticks = l.last.ticks;
    }
    // the threaded lane: keep the thread's settings in line, then read its latest state
    method_ = s.method;
    update_thread(frame_dt, step_once);
    if (!s.paused) real_time_ += frame_dt * settings_.time_scale;
    // lag history: real time minus simulated time
    for (Lane& l : lanes_) {
      l.hist_t.push_back(static_cast<float>(real_time_));
      l.hist_lag.push_back(static_cast<float>(real_time_ - l.sim_time));
      if (l.hist_t.size() > 4000) {
        l.hist_t.erase(l.hist_t.begin(), l.hist_t.begin() + 1000);
        l.hist_lag.erase(l.hist_lag.begin(), l.hist_lag.begin() + 1000);
      }
    }
  }

  void Draw(Renderer& r, double) override {
    const double spacing = 2.3;
    for (std::size_t i = 0; i < lanes_.size(); ++i) {
      const Lane& l = lanes_[i];
      const double x = (static_cast<double>(i) - 1.5) * spacing;
      const Color c = StrategyColor(l.strategy);
      // the pad, the exact ball at real time (ghost), the simulated ball
      r.box({x, 0.04, 0}, {0.7, 0.04, 0.7}, Quat(1, 0, 0, 0), Color::hex(0x3a3f47));
      r.sphere({x, ExactHeight(real_time_), 0}, kRadius * 1.02, Color{0.92f, 0.94f, 1.0f, 0.28f});
      const Vec3 p = l.strategy == Strategy::Threaded ? thread_pos_ : l.ball_prev.x + l.alpha * (l.ball.x - l.ball_prev.x);
      // a ball that bounced out of the view is drawn at its edge with an arrow and its height
      const double top = 5.4;
      if (p.y > top) {
        r.sphere({x, top, 0}, kRadius, c);
        r.arrow({x, top + kRadius, 0}, {x, top + kRadius + 0.5, 0}, 0.18, c);
        char up[32];
        std::snprintf(up, sizeof up, "%.0f m", p.y);
        r.text({x + 0.35, top + 0.3, 0}, up, c, 0.9f, 0.0f);
      } else {
        r.sphere({x, p.y, 0}, kRadius, c);
      }
      // the drop height as a faint marker
      r.line({x - 0.45, kRadius + kDrop, 0}, {x + 0.45, kRadius + kDrop, 0}, Color{1, 1, 1, 0.25f}, 1.0f);
      if (!ctx_.settings.show_labels) continue;
      char buf[96];
      r.text({x, kRadius + kDrop + 0.75, 0}, std::string(strategy_name(l.strategy)), c, 1.25f, 0.5f);
      std::snprintf(buf, sizeof buf, "%d tick%s/frame", l.ticks, l.ticks == 1 ? "" : "s");
      r.text({x, kRadius + kDrop + 0.45, 0}, buf, colors::white, 0.9f, 0.5f);
      const double behind = real_time_ - l.sim_time;
      std::snprintf(buf, sizeof buf, "behind %.2f s", std::abs(behind) < 0.005 ? 0.0 : behind);
      r.text({x, -0.35, 0}, buf, real_time_ - l.sim_time > 0.05 ? Color::hex(0xff8b6a) : colors::white, 0.9f, 0.5f);
      std::snprintf(buf, sizeof buf, "dropped %.2f s", l.dropped);
      r.text({x, -0.62, 0}, buf, colors::grey, 0.9f, 0.5f);
    }
  }

  void DrawUI() override {
    Settings& s = ctx_.settings;
    // the load: frame-rate limit, render delay (doWork), physics cost
    ImGui::TextDisabled("load");
    bool limit = s.frame_limit_hz > 0;
    if (ImGui::Checkbox("limit frame rate", &limit)) s.frame_limit_hz = limit ? 30 : 0;
    if (limit) {
      float hz = static_cast<float>(s.frame_limit_hz);
      ImGui::SetNextItemWidth(-110);
      if (ImGui::SliderFloat("frame limit", &hz, 2.0f, 240.0f, "%.0f Hz", ImGuiSliderFlags_Logarithmic))
        s.frame_limit_hz = std::max(hz, 1.0f);
    }
    float delay = static_cast<float>(s.render_delay_ms);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("render delay", &delay, 0.0f, 300.0f, "%.0f ms")) s.render_delay_ms = std::max(delay, 0.0f);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("the workbook's doWork(): extra time spent drawing each frame");
    float cost = static_cast<float>(cost_ms_.load());
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("physics cost", &cost, 0.0f, 20.0f, "%.1f ms/tick")) cost_ms_ = std::max(cost, 0.0f);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("busy work inside every tick: push it up to start a death spiral");

    // the strategies' parameters
    ImGui::Spacing();
    ImGui::TextDisabled("strategies");
    float hz = static_cast<float>(1.0 / settings_.fixed_dt);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("fixed rate", &hz, 10.0f, 1000.0f, "%.0f Hz", ImGuiSliderFlags_Logarithmic))
      settings_.fixed_dt = 1.0 / std::max(hz, 1.0f);
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("ticks/frame", &settings_.ticks_per_frame, 1, 16);
    float max_ms = static_cast<float>(settings_.max_dt * 1000);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("max dt", &max_ms, 0.5f, 50.0f, "%.1f ms", ImGuiSliderFlags_Logarithmic))
      settings_.max_dt = std::max(max_ms, 0.01f) / 1000.0;
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("tick cap", &settings_.max_ticks_per_frame, 1, 256, "%d", ImGuiSliderFlags_Logarithmic);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("stall guard: most ticks per frame; the rest is dropped and counted");
    if (ImGui::Button("Reset clocks")) ctx_.settings.restart = true;

    // one row per strategy
    ImGui::Spacing();
    if (ImGui::BeginTable("lanes", 4, ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("strategy", ImGuiTableColumnFlags_WidthStretch, 1.6f);
      ImGui::TableSetupColumn("ticks", ImGuiTableColumnFlags_WidthStretch, 0.8f);
      ImGui::TableSetupColumn("tick dt", ImGuiTableColumnFlags_WidthStretch, 1.1f);
      ImGui::TableSetupColumn("dropped", ImGuiTableColumnFlags_WidthStretch, 1.1f);
      ImGui::TableHeadersRow();
      for (const Lane& l : lanes_) {
        const Color c = StrategyColor(l.strategy);
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextColored(ImVec4(c.r, c.g, c.b, 1), "%s", std::string(strategy_name(l.strategy)).c_str());
        if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", std::string(strategy_description(l.strategy)).c_str());
        ImGui::TableNextColumn();
        ImGui::Text("%d", l.ticks);
        ImGui::TableNextColumn();
        const double dt = l.strategy == Strategy::Threaded ? settings_.fixed_dt : l.last.tick_dt;
        ImGui::Text("%.1f ms", dt * 1000);
        ImGui::TableNextColumn();
        ImGui::Text("%.2f s", l.dropped);
      }
      ImGui::EndTable();
    }
    ImGui::Text("real time %.2f s, frame %.1f ms", real_time_, ctx_.frame_dt * 1000);

    // how far each strategy's simulated time trails real time
    std::vector<PlotSeries> series;
    for (const Lane& l : lanes_) {
      PlotSeries ps;
      ps.x = l.hist_t.data();
      ps.y = l.hist_lag.data();
      ps.count = static_cast<int>(l.hist_t.size());
      ps.color = StrategyColor(l.strategy);
      ps.width = 2.0f;
      series.push_back(ps);
    }
    PlotAxes ax;
    ax.x_label = "real time (s)";
    ax.y_label = "real - simulated time (s)";
    ax.y_include_zero = true;
    ax.y_min_span = 0.1f;
    ax.y_format = "%.2f";
    if (!lanes_.empty() && !lanes_[0].hist_t.empty())
      ax.x_lo = std::max(0.0f, lanes_[0].hist_t.back() - 20.0f), ax.x_hi = std::max(lanes_[0].hist_t.back(), 1.0f);
    LinePlot("lag", series, ax, 150);
    ImGui::TextWrapped(
        "White ghosts: the exact ball at real time. Raise the render delay or the physics cost: "
        "per-frame takes bigger ticks (the bounce goes wrong), max-step and fixed hit the tick cap "
        "and drop time (they fall behind), threaded keeps time on its own thread.");
  }

  FiniteCheck CheckFinite() const override {
    for (const Lane& l : lanes_) {
      const Vec3& x = l.strategy == Strategy::Threaded ? thread_pos_ : l.ball.x;
      const FiniteCheck c = check_finite<Vec3>(std::span<const Vec3>(&x, 1), std::span<const Vec3>(&l.ball.v, 1),
                                               std::string(strategy_name(l.strategy)) + " ball", l.sim_time, 0);
      if (!c.ok) return c;
    }
    return {};
  }

  std::vector<Color> ExpectedColors() const override {
    std::vector<Color> c;
    for (Strategy s : kStrategies) c.push_back(StrategyColor(s));
    return c;
  }

 private:
  double number_option(const std::string& key, double fallback, double lo, double hi) const {
    const std::string v = ctx_.option(key, "");
    if (v.empty()) return fallback;
    char* end = nullptr;
    const double d = std::strtod(v.c_str(), &end);
    if (end != v.c_str() + v.size() || !std::isfinite(d) || d < lo || d > hi)
      throw Error("--option " + key + "=" + v + ": expected a number in [" + format_value(lo) + ", " +
                  format_value(hi) + "]");
    return d;
  }

  void update_thread(double frame_dt, bool step_once) {
    Settings& s = ctx_.settings;
    if (!(thread_->settings() == settings_)) thread_->set_settings(settings_);
    if (thread_->paused() != s.paused) thread_->set_paused(s.paused);
    if (step_once) thread_->step(1);
    if (ctx_.virtual_time && !s.paused) {
      // virtual time: the thread sees the frame's time pass tick by tick
      AdvanceVirtualClock(*thread_, *clock_, frame_dt, &fed_);
    }
    // the latest published ball, interpolated from the one before
    snaps_.acquire();
    const std::int64_t now = clock_ ? clock_->now_ns() : SteadyClock::instance().now_ns();
    const double a = snaps_.alpha(now, settings_.fixed_dt);
    thread_pos_ = snaps_.previous().x + a * (snaps_.current().x - snaps_.previous().x);
    const PhysicsThreadStats st = thread_->stats();
    Lane& l = lanes_.back();
    l.ticks = static_cast<int>(st.totals.ticks - thread_ticks_);
    thread_ticks_ = st.totals.ticks;
    l.sim_time = st.time;
    l.dropped = st.totals.dropped_time;
  }

  StepperSettings settings_;
  std::atomic<double> cost_ms_{0};             // read by the physics thread too
  std::atomic<Method> method_{Method::SemiImplicitEuler};
  double real_time_ = 0;
  std::vector<Lane> lanes_;
  // the threaded lane (its ball and integrator are touched only by the physics thread)
  Ball thread_ball_;
  Integrator<Vec3> thread_integ_;
  SnapshotBuffer<Snap> snaps_;
  Vec3 thread_pos_{0, kRadius + kDrop, 0};
  long long thread_ticks_ = 0;
  double fed_ = 0;
  std::unique_ptr<ManualClock> clock_;
  std::unique_ptr<PhysicsThread> thread_;  // last: stops before the state it ticks goes away
};

static int reg = RegisterSample("Dynamics", "Time stepping", TimeStepping::Create);

}  // namespace
}  // namespace pba::app
