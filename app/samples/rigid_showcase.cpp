// The rigid-body samples of workbook chapter 6 (each a scene you can drive; the mouse grabs
// and throws any body, see rigid_common.h):
//   "Rigid bodies/T-handle"       the intermediate-axis flip in zero gravity, L and E plotted
//   "Rigid bodies/Bullet"         a 0.1 m ball at hundreds of m/s at a thin dynamic plate and a wall
//   "Rigid bodies/Rain"           thousands of mixed bodies falling and going to sleep
//   "Rigid bodies/Dominoes"       a curved row of dominoes toppled by a push
//   "Rigid bodies/Mass ratio"     a heavy box on light ones, the overlap measured
//   "Rigid bodies/Roll and slide" a ball rolls, a box slides and a box sticks on one slope
//   "Rigid bodies/Conveyor"       kinematic rollers carry boxes to a kinematic paddle wheel
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/rigid_scenes.h"
#include "plot.h"
#include "renderer.h"
#include "rigid_common.h"

namespace pba::app {
namespace {

constexpr Color kMarker = colors::yellow;  // lit marker balls: the self-test finds their colour

RigidShapeDef box_def(const Vec3& half, double mu = 0.5, double density = 1000, const Pose& local = {}) {
  return {.shape = ColliderShape::box(half), .local = local, .density = density,
          .material = {.restitution = 0, .friction = mu}};
}

// a small deterministic generator for the scenes (xorshift64*), uniform in [0, 1)
struct Random {
  std::uint64_t x = 0x2545f4914f6cdd1dull;
  double next() {
    x ^= x >> 12, x ^= x << 25, x ^= x >> 27;
    return static_cast<double>((x * 0x2545f4914f6cdd1dull) >> 11) * 0x1.0p-53;
  }
};

// a time series kept to its last `keep` samples
struct Trace {
  std::vector<float> t;
  std::vector<std::vector<float>> y;
  explicit Trace(int n = 1) : y(n) {}
  void add(double time, std::initializer_list<double> values, std::size_t keep = 1800) {
    t.push_back(static_cast<float>(time));
    std::size_t k = 0;
    for (double v : values) y[k++].push_back(static_cast<float>(v));
    if (t.size() > keep) {
      t.erase(t.begin());
      for (auto& s : y) s.erase(s.begin());
    }
  }
  void clear() {
    t.clear();
    for (auto& s : y) s.clear();
  }
  // `counts`: the series are counts, never negative, so the fitted y range starts at 0 (a
  // count's axis reaching below zero read as bodies less than none)
  void plot(const char* id, std::initializer_list<Color> colours, const char* y_label, float height = 110,
            bool counts = false) const {
    if (t.empty()) return;
    std::vector<PlotSeries> s;
    std::size_t k = 0;
    for (Color c : colours) s.push_back(Series(t.data(), y[k++].data(), static_cast<int>(t.size()), c, 1.5f));
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = y_label;
    if (counts) ax.y_include_zero = true, ax.y_clamp_lo = 0;
    LinePlot(id, s, ax, height);
  }
};

// ---------------------------------------------------------------------------------------
// T-handle: a free body spun about its intermediate principal axis flips over and back
// (Dzhanibekov); with no torque its angular momentum and energy stay what they were.

class THandle final : public RigidSample {
 public:
  explicit THandle(SampleContext& ctx) : RigidSample(ctx) {
    spin_ = OptionNumber(ctx, "spin", 10, 0.5, 50);
    gravity_ = Vec3(0);
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<THandle>(ctx); }

  void Build() override {
    // a bar along x and a stem along -y: the stem's axis is the intermediate one
    handle_ = bodies_.create({.name = "T-handle", .pose = {{0, 1.5, 0}}, .angular_velocity = {0.01 * spin_, spin_, 0},
                              .shapes = {box_def({0.5, 0.05, 0.05}), box_def({0.05, 0.3, 0.05}, 0.5, 1000, Pose{{0, -0.35, 0}})}});
    l0_ = bodies_.angular_momentum(handle_);
    e0_ = bodies_.kinetic_energy(handle_);
    trace_.clear();
    flips_.clear();
    ctx_.camera->frame({0, 1.5f, 0}, 1.6f, 0.6f, 0.25f);
  }

  void AfterStep(double, double) override {
    // body-axis angular velocity: the spin about the stem changes sign at each flip
    const Pose p = bodies_.pose(handle_);
    const Vec3 wb = glm::conjugate(p.rotation) * bodies_.angular_velocity(handle_);
    if (!trace_.t.empty() && (trace_.y[1].back() > 0) != (wb.y > 0)) flips_.push_back(bodies_.time());
    trace_.add(bodies_.time(), {wb.x, wb.y, wb.z});
  }

  void Draw(Renderer& r, double alpha) override {
    RigidSample::Draw(r, alpha);
    // the angular momentum (fixed in space) and the stem's axis
    const Pose p = bodies_.pose(handle_);
    const Vec3 c = bodies_.center_of_mass(handle_);
    r.arrow(c, c + 0.1 * bodies_.angular_momentum(handle_), 0.08, colors::green);
    // the stem's end marked by a ball seated on it, big enough to find at 640x360 (at 0.06 m, half
    // inside the stem, it was 1-3 pixels there and the selftest counted the plot's yellow line)
    r.sphere(apply(p, Vec3(0, -0.7, 0)), 0.1, kMarker);
  }

  void DrawUI() override {
    SolverControls();
    const double dl = glm::length(bodies_.angular_momentum(handle_) - l0_) / glm::length(l0_);
    const double de = (bodies_.kinetic_energy(handle_) - e0_) / e0_;
    ImGui::Text("|L - L0| / |L0| = %.2e   (E - E0) / E0 = %.2e", dl, de);
    if (flips_.size() >= 3)
      ImGui::Text("flip period %.3f s (time between one flip and the next but one)",
                  flips_.back() - flips_[flips_.size() - 3]);
    else
      ImGui::Text("flips so far: %zu", flips_.size());
    trace_.plot("omega", {colors::red, kMarker, colors::blue}, "rad/s about the body axes: x red, y yellow, z blue");
    ImGui::TextWrapped(
        "Spun about its intermediate axis (the stem, yellow ball at its end), the T-handle turns over every "
        "half period and back, while its angular momentum (green arrow) stays fixed. The rotation is integrated "
        "by a symmetric splitting of the free rigid-body flow, so |L| is kept to rounding and energy to second "
        "order. --option spin=RAD_PER_S.");
  }

  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  double spin_ = 10;
  RigidBodyId handle_{};
  Vec3 l0_{0, 0, 0};
  double e0_ = 0;
  Trace trace_{3};
  std::vector<double> flips_;
};

// ---------------------------------------------------------------------------------------
// Bullet: a 0.1 m ball fired every half second at a 4 cm dynamic plate standing on a heavy
// foot, with a 10 cm static wall behind it. At 240 m/s it moves 4 m per 60 Hz step, forty times
// the wall's thickness; the continuous pass stops any fast ball at the static wall, but only a
// ball flagged as a bullet is also swept against the moving (dynamic) plate: with the flag off
// the balls pass through the plate (their speculative contact reaches no farther than their
// size) and stop at the wall.

class Bullet final : public RigidSample {
 public:
  explicit Bullet(SampleContext& ctx) : RigidSample(ctx) {
    speed_ = OptionNumber(ctx, "speed", 240, 1, 2000);
    bullet_ = OptionFlag(ctx, "bullet", true);
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Bullet>(ctx); }

  void Build() override {
    rigid_scenes::ground(bodies_);
    bodies_.create({.name = "wall", .type = BodyType::Static, .pose = {{10, 2, 0}}, .shapes = {box_def({0.05, 2, 2})}});
    // the plate (4 cm thick, 3 m tall and wide, steel) on a 1.2 m deep foot that holds it up
    // as the shots push it (one shot carries 1,000 kg m/s at 240 m/s; the body weighs 8.64 t:
    // 0.36 + 0.72 m^3 of steel at 8000 kg/m^3)
    plate_ = bodies_.create({.name = "plate", .pose = {{kPlateX, 0, 0}},
                             .shapes = {box_def({0.02, 1.5, 1.5}, 0.5, 8000, Pose{{0, 1.7, 0}}),
                                        box_def({0.6, 0.1, 1.5}, 0.5, 8000, Pose{{0, 0.1, 0}})}});
    shots_.clear();
    fired_ = passed_ = through_plate_ = 0;
    next_ = 0;
    ctx_.camera->frame({-1, 1.5f, 0}, 12, 0.0f, 0.35f);
  }

  void AfterStep(double, double) override {
    const double t = bodies_.time();
    if (t >= next_) {
      // one shot from the gun at x = -10, at one of five heights
      const double y = 0.8 + 0.5 * (fired_ % 5);
      Shot s;
      s.id = bodies_.create({.name = "bullet " + std::to_string(fired_), .pose = {{-10, y, 0}},
                             .linear_velocity = {speed_, 0, 0},
                             .shapes = {{.shape = ColliderShape::sphere(0.1), .material = {.restitution = 0}}},
                             .bullet = bullet_});
      s.fired = t;
      shots_.push_back(s);
      ++fired_;
      next_ = t + 0.5;
    }
    for (Shot& s : shots_) {
      if (!bodies_.valid(s.id)) continue;
      const Vec3 c = bodies_.center_of_mass(s.id);
      s.trail.push_back(c);
      if (c.x > 10.05 && !s.through) s.through = true, ++passed_;
      const double plate_x = bodies_.center_of_mass(plate_).x;
      if (c.x > plate_x + 0.1 && c.y > 0.2 && !s.past_plate) s.past_plate = true, ++through_plate_;
    }
    // shots live 3 s
    while (!shots_.empty() && t - shots_.front().fired > 3) {
      if (bodies_.valid(shots_.front().id)) bodies_.destroy(shots_.front().id);
      shots_.pop_front();
    }
  }

  void Draw(Renderer& r, double alpha) override {
    RigidSample::Draw(r, alpha);
    // where each ball was at the end of each step: the jumps show how far a step goes
    for (const Shot& s : shots_) {
      for (const Vec3& p : s.trail) r.point(p, 5.0f, colors::orange);
      if (bodies_.valid(s.id)) r.sphere(bodies_.center_of_mass(s.id), 0.1, kMarker);
    }
    // the gun
    r.sphere({-10.6, 1.8, 0}, 0.4, kMarker);
    r.text({-10.6, 2.4, 0}, "gun", colors::white, 0.8f, 0.5f);
    r.box({-10.6, 0.7, 0}, {0.15, 0.7, 0.15}, Quat(1, 0, 0, 0), colors::grey);
    const Vec3 plate = bodies_.center_of_mass(plate_);
    r.text({plate.x, 3.6, 0}, "dynamic plate", colors::white, 0.8f, 0.5f);
    r.text({10, 4.4, 0}, "static wall", colors::white, 0.8f, 0.5f);
    r.text({-10.6, 3.0, 0}, bullet_ ? "bullet: on" : "bullet: off", bullet_ ? colors::green : colors::red, 0.8f, 0.5f);
  }

  void DrawUI() override {
    SolverControls();
    float v = static_cast<float>(speed_);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("speed", &v, 1, 2000, "%.0f m/s", ImGuiSliderFlags_Logarithmic)) speed_ = v;
    ImGui::Checkbox("bullet flag (next shots)", &bullet_);
    ImGui::Text("fired %d, through the plate %d, through the wall %d", fired_, through_plate_, passed_);
    ImGui::Text("%.2f m per step against a 0.04 m plate and a 0.10 m wall", speed_ / 60.0);
    Readout();
    ImGui::TextWrapped(
        "Orange dots: the ball at the end of each step. A ball that moves farther than half its size in a step "
        "is swept from its start to its end pose against the static shapes (conservative advancement) and put "
        "back at the first time of impact; the next step's contact stops it. A ball flagged as a bullet is "
        "also swept against the moving bodies at their poses at the step's end, so it stops at the dynamic "
        "plate; without the flag it passes through the plate and stops at the wall. "
        "--option speed=M_PER_S, --option bullet=0|1."); 
  }

  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  struct Shot {
    RigidBodyId id{};
    double fired = 0;
    bool through = false, past_plate = false;
    std::vector<Vec3> trail;
  };
  static constexpr double kPlateX = 3;  // where the plate stands (m)
  double speed_ = 240, next_ = 0;
  bool bullet_ = true;
  RigidBodyId plate_{};
  int fired_ = 0, passed_ = 0, through_plate_ = 0;
  std::deque<Shot> shots_;
};

// ---------------------------------------------------------------------------------------
// Rain: boxes, balls and capsules dropped over a field with a few static blocks; they fall
// asleep in islands (sleeping bodies are drawn faded).

class Rain final : public RigidSample {
 public:
  explicit Rain(SampleContext& ctx) : RigidSample(ctx) {
    count_ = OptionInteger(ctx, "count", 1000, 1, 20000);
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Rain>(ctx); }

  void Build() override {
    rigid_scenes::ground(bodies_, 0.6);
    for (int i = 0; i < 4; ++i)
      bodies_.create({.name = "block", .type = BodyType::Static, .pose = {{-6.0 + 4 * i, 0.5, (i % 2) * 3.0 - 1.5}},
                      .shapes = {box_def({1, 0.5, 1})}});
    random_ = {};
    spawned_ = 0;
    trace_.clear();
    ctx_.camera->frame({0, 4, 0}, 13, 0.6f, 0.4f);
  }

  void AfterStep(double, double) override {
    // 20 bodies a step from a 16 x 16 m area 12 m up, until the count
    for (int k = 0; k < 20 && spawned_ < count_; ++k, ++spawned_) {
      const Vec3 p{16 * random_.next() - 8, 12 + 4 * random_.next(), 16 * random_.next() - 8};
      const Quat q = glm::normalize(Quat(random_.next(), random_.next(), random_.next(), random_.next()) + Quat(0.1, 0, 0, 0));
      RigidShapeDef s;
      switch (spawned_ % 3) {
        case 0: s = box_def(Vec3(0.15 + 0.2 * random_.next(), 0.15 + 0.2 * random_.next(), 0.15 + 0.2 * random_.next()), 0.6); break;
        case 1: s = {.shape = ColliderShape::sphere(0.15 + 0.2 * random_.next()), .material = {.restitution = 0.1, .friction = 0.6},
                     .rolling_resistance = 0.05}; break;
        default: s = {.shape = ColliderShape::capsule(0.1 + 0.25 * random_.next(), 0.12 + 0.1 * random_.next()),
                      .material = {.restitution = 0, .friction = 0.6}}; break;
      }
      bodies_.create({.name = "drop", .pose = {p, q}, .shapes = {s}});
    }
    const double awake = static_cast<double>(bodies_.awake_count());
    trace_.add(bodies_.time(), {awake, static_cast<double>(spawned_) - awake});
  }

  void DrawUI() override {
    SolverControls();
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderInt("bodies", &count_, 1, 20000, "%d", ImGuiSliderFlags_Logarithmic)) count_ = std::max(count_, 1);
    Readout();
    trace_.plot("sleep", {colors::blue, colors::grey}, "bodies awake (blue), asleep (grey)", 110, true);
    ImGui::TextWrapped(
        "Bodies touching each other form islands; an island whose bodies have all been slower than the sleep "
        "tolerances for half a second falls asleep (drawn faded) and costs nothing until something fast comes "
        "near, a force pulls it or the mouse grabs it. --option count=N.");
  }

  void Draw(Renderer& r, double alpha) override {
    RigidSample::Draw(r, alpha);
    r.sphere({9, 0.6, 9}, 0.6, kMarker);  // a corner of the field (the rain falls on 16 x 16 m)
    r.text({9, 1.5, 9}, "corner of the 16 x 16 m field", colors::white, 0.8f, 0.5f);
  }
  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  int count_ = 1000, spawned_ = 0;
  Random random_;
  Trace trace_{2};
};

// ---------------------------------------------------------------------------------------
// Dominoes: 40 on an arc; the first is pushed.

class Dominoes final : public RigidSample {
 public:
  explicit Dominoes(SampleContext& ctx) : RigidSample(ctx) {
    count_ = OptionInteger(ctx, "count", 40, 2, 400);
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Dominoes>(ctx); }

  void Build() override {
    rigid_scenes::ground(bodies_, 0.6);
    // an Archimedean spiral out from 2 m, its turns 1.3 m apart (more than a domino's
    // height, so a falling one reaches only the next along the row), 0.45 m apart along it
    const double gap = 0.45, r0 = 2.0, b = 1.3 / (2 * kPi);
    first_ = last_ = {};
    double a = 0, r = r0;
    for (int i = 0; i < count_; ++i) {
      r = r0 + b * a;
      const Vec3 p{r * std::sin(a), 0.5, -r * std::cos(a)};
      const Quat q = glm::angleAxis(-a, Vec3(0, 1, 0));
      const RigidBodyId d = bodies_.create({.name = "domino " + std::to_string(i), .pose = {p, q},
                                            .shapes = {box_def({0.05, 0.5, 0.25}, 0.6, 600)}});
      if (i == 0) first_ = d;
      last_ = d;
      a += gap / r;
    }
    ctx_.camera->frame({0, 0.5f, 0}, static_cast<float>(r + 1.0), 0.6f, 0.6f);
    pushed_ = false;
    fallen_at_ = -1;
  }

  void AfterStep(double, double) override {
    // a push on the first domino's top after a fifth of a second
    if (!pushed_ && bodies_.time() > 0.2) {
      const Pose p = bodies_.pose(first_);
      bodies_.apply_impulse(first_, p.rotation * Vec3(10, 0, 0), apply(p, Vec3(0, 0.45, 0)));
      pushed_ = true;
    }
    const Vec3 up = bodies_.pose(last_).rotation * Vec3(0, 1, 0);
    if (fallen_at_ < 0 && up.y < 0.5) fallen_at_ = bodies_.time();
  }

  void Draw(Renderer& r, double alpha) override {
    RigidSample::Draw(r, alpha);
    r.sphere(apply(bodies_.pose(last_), Vec3(0, 0.8, 0)), 0.3, kMarker);
  }

  void DrawUI() override {
    SolverControls();
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("dominoes", &count_, 2, 400);
    if (fallen_at_ >= 0)
      ImGui::Text("the last one fell at t = %.2f s (%.2f m/s along the row)", fallen_at_,
                  (count_ - 1) * 0.45 / std::max(1e-9, fallen_at_ - 0.2));
    else
      ImGui::Text("the last one (yellow ball) is still standing");
    Readout();
    ImGui::TextWrapped("Each domino is a 1 m x 0.1 m x 0.5 m box of 600 kg/m^3, 0.45 m from the next, mu 0.6. "
                       "Drag one with the mouse to push it. --option count=N.");
  }

  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  int count_ = 40;
  RigidBodyId first_{}, last_{};
  bool pushed_ = false;
  double fallen_at_ = -1;
};

// ---------------------------------------------------------------------------------------
// Mass ratio: a heavy box on a column of light ones. An iterative solver spreads an impulse
// over the column slowly when the masses differ a lot; the overlap shows how well it copes.
// The ratio goes up to what the default solver holds awake (rigid_scenes::kHeavyOnLightMaxRatio:
// beyond it the column buckles on the soft contacts' springs; up to 10,000:1 it stood only
// when it fell asleep before the lean grew).

class MassRatio final : public RigidSample {
 public:
  explicit MassRatio(SampleContext& ctx) : RigidSample(ctx) {
    ratio_ = static_cast<float>(OptionNumber(ctx, "ratio", 400, 1, rigid_scenes::kHeavyOnLightMaxRatio));
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<MassRatio>(ctx); }

  void Build() override {
    column_ = rigid_scenes::heavy_on_light(bodies_, ratio_);
    heavy_ = column_.back();
    trace_.clear();
    ctx_.camera->frame({0, 1.2f, 0}, 2.6f, 0.5f, 0.25f);
  }

  void AfterStep(double, double) override {
    // the overlaps along the column from the centres' heights (asleep or not): ground and
    // each box with the one below
    double deepest = 0, below = 0;
    for (std::size_t i = 0; i < column_.size(); ++i) {
      const double half = i + 1 == column_.size() ? 0.5 : 0.25, y = bodies_.center_of_mass(column_[i]).y;
      deepest = std::max(deepest, below - (y - half));
      below = y + half;
    }
    trace_.add(bodies_.time(), {1e3 * deepest, 10.0});
  }

  void Draw(Renderer& r, double alpha) override {
    draw_options_.highlight = heavy_;
    draw_options_.highlight_color = colors::red;
    RigidSample::Draw(r, alpha);
    // a pin over the box's top with its caption beside it (the caption had sat on the ball)
    const double top = bodies_.shapes(heavy_)[0].shape.half_extents.y;
    const Vec3 pin = bodies_.center_of_mass(heavy_) + Vec3(0, top + 0.3, 0);
    r.sphere(pin, 0.12, kMarker);
    r.text(pin + Vec3(0.2, 0.05, 0), "the heavy box", colors::white, 0.8f, 0.0f);
  }

  void DrawUI() override {
    SolverControls();
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("mass ratio", &ratio_, 1, static_cast<float>(rigid_scenes::kHeavyOnLightMaxRatio), "%.0f : 1",
                           ImGuiSliderFlags_Logarithmic | ImGuiSliderFlags_AlwaysClamp))
      Restart();
    if (!trace_.t.empty()) ImGui::Text("deepest overlap %.2f mm (the issue's bound: 10 mm)", trace_.y[0].back());
    trace_.plot("overlap", {colors::red, colors::grey}, "mm: overlap (red), 10 mm bound (grey)");
    Readout();
    ImGui::TextWrapped("The red box is 'mass ratio' times heavier than each small box below it (its density "
                       "is scaled; it is twice their size). --option ratio=R.");
    ImGui::TextWrapped("Up to %.0f:1, what the soft step holds awake at its defaults: a soft contact is as stiff as "
                       "the light box's mass makes it, so past about 430:1 the load's lean outgrows the springs and "
                       "the column buckles (sleeping only hides it). Sequential impulses, TGS and XPBD hold less "
                       "(docs/rigid-bodies.md, known limits).",
                       rigid_scenes::kHeavyOnLightMaxRatio);
  }

  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  float ratio_ = 400;
  RigidBodyId heavy_{};
  std::vector<RigidBodyId> column_;
  Trace trace_{2};
};

// ---------------------------------------------------------------------------------------
// Roll and slide: on one slope a ball rolls at (5/7) g sin(theta), a box with mu = 0.2 slides
// at g (sin(theta) - mu cos(theta)) and a box with mu = 0.8 stays put.

class RollSlide final : public RigidSample {
 public:
  explicit RollSlide(SampleContext& ctx) : RigidSample(ctx) {
    degrees_ = static_cast<float>(OptionNumber(ctx, "angle", 20, 1, 60));
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<RollSlide>(ctx); }

  void Build() override {
    const double th = degrees_ * kPi / 180;
    const Quat tilt = glm::angleAxis(-th, Vec3(0, 0, 1));
    down_ = tilt * Vec3(1, 0, 0);
    const Vec3 normal = tilt * Vec3(0, 1, 0);
    // a slab 20 m long whose top surface passes through (0, 5, 0)
    const Vec3 top{0, 5, 0};
    bodies_.create({.name = "slope", .type = BodyType::Static, .pose = {top - 0.25 * normal, tilt},
                    .shapes = {{.shape = ColliderShape::box({10, 0.25, 2}), .material = {.restitution = 0, .friction = 0.8}}}});
    const Vec3 start = top - 9.0 * down_;
    ball_ = bodies_.create({.name = "ball", .pose = {start + 0.3 * normal + Vec3(0, 0, -1.2)},
                            .shapes = {{.shape = ColliderShape::sphere(0.3), .material = {.restitution = 0, .friction = 0.8}}}});
    slider_ = bodies_.create({.name = "sliding box", .pose = {start + 0.25 * normal, tilt}, .shapes = {box_def(Vec3(0.25), 0.05)}});
    sticker_ = bodies_.create({.name = "sticking box", .pose = {start + 0.25 * normal + Vec3(0, 0, 1.2), tilt},
                               .shapes = {box_def(Vec3(0.25), 0.8)}});
    for (int k = 0; k < 3; ++k) s0_[k] = glm::dot(bodies_.center_of_mass(ids()[k]), down_);
    t0_ = bodies_.time();
    if (!framed_) ctx_.camera->frame({0, 4, 0}, 9, 0.25f, 0.3f);  // once: the runs repeat under the user's view
    framed_ = true;
  }

  void AfterStep(double, double) override {
    // each body's travel down the slope against its closed form s = a t^2 / 2 (mixed friction
    // is the geometric mean of the body's and the slope's 0.8)
    const double th = degrees_ * kPi / 180, g = 9.81, t = bodies_.time() - t0_;
    const double mu_slide = std::sqrt(0.05 * 0.8), mu_stick = 0.8;
    const double a[3] = {5.0 / 7.0 * g * std::sin(th), std::max(0.0, g * (std::sin(th) - mu_slide * std::cos(th))),
                         std::max(0.0, g * (std::sin(th) - mu_stick * std::cos(th)))};
    for (int k = 0; k < 3; ++k) {
      measured_[k] = glm::dot(bodies_.center_of_mass(ids()[k]), down_) - s0_[k];
      expected_[k] = 0.5 * a[k] * t * t;
    }
    accel_[0] = a[0], accel_[1] = a[1], accel_[2] = a[2];
    // once the ball has rolled 17 m (near the slab's end), keep each body's mean acceleration
    // 2 s / t^2 of the run and start again
    if (measured_[0] > 17) {
      for (int k = 0; k < 3; ++k) last_[k] = 2 * measured_[k] / (t * t);
      last_time_ = t;
      Restart();
    }
  }

  void Draw(Renderer& r, double alpha) override {
    draw_options_.highlight = ball_;
    draw_options_.highlight_color = kMarker;
    RigidSample::Draw(r, alpha);
  }

  void DrawUI() override {
    SolverControls();
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("slope", &degrees_, 1, 60, "%.0f deg")) Restart();
    const char* names[3] = {"ball", "box mu 0.2", "box mu 0.8"};
    for (int k = 0; k < 3; ++k)
      ImGui::Text("%-12s travelled %6.3f m, closed form %6.3f m", names[k], measured_[k], expected_[k]);
    if (last_time_ > 0) {
      ImGui::Text("last run (%.2f s), acceleration (m/s^2):", last_time_);
      for (int k = 0; k < 3; ++k)
        ImGui::Text("  %-12s %.3f (theory %.3f, %+.1f%%)", names[k], last_[k], accel_[k],
                    accel_[k] > 0 ? 100 * (last_[k] / accel_[k] - 1) : 0.0);
    }
    Readout();
    ImGui::TextWrapped(
        "A ball that rolls without slipping accelerates at (5/7) g sin(theta) whatever its friction, as long "
        "as mu >= (2/7) tan(theta); a box slides at g (sin(theta) - mu cos(theta)) once tan(theta) > mu and "
        "stays put otherwise. The run starts again when the ball nears the slab's end. --option angle=DEG.");
  }

  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  std::array<RigidBodyId, 3> ids() const { return {ball_, slider_, sticker_}; }
  float degrees_ = 20;
  Vec3 down_{1, 0, 0};
  RigidBodyId ball_{}, slider_{}, sticker_{};
  double s0_[3] = {0, 0, 0}, measured_[3] = {0, 0, 0}, expected_[3] = {0, 0, 0}, accel_[3] = {0, 0, 0};
  double t0_ = 0, last_[3] = {0, 0, 0}, last_time_ = 0;
  bool framed_ = false;
};

// ---------------------------------------------------------------------------------------
// Conveyor: kinematic rollers turning at a set speed carry boxes to a kinematic paddle wheel
// that throws them into a bin; boxes that leave the scene start again at the belt's head.

class Conveyor final : public RigidSample {
 public:
  explicit Conveyor(SampleContext& ctx) : RigidSample(ctx) {
    belt_speed_ = static_cast<float>(OptionNumber(ctx, "belt_speed", 2, 0, 10));
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Conveyor>(ctx); }

  void Build() override {
    rigid_scenes::ground(bodies_, 0.6);
    rollers_.clear();
    boxes_.clear();
    // fourteen rollers of radius 0.15 m, 2 cm apart, along x at 1.5 m height, axes along z:
    // the surface speed of a roller turning at w about -z is w r along +x
    for (int i = 0; i < 14; ++i)
      rollers_.push_back(bodies_.create(
          {.name = "roller", .type = BodyType::Kinematic, .pose = {{-6 + 0.32 * i, 1.5, 0}, glm::angleAxis(kPi / 2, Vec3(1, 0, 0))},
           .shapes = {{.shape = ColliderShape::capsule(0.6, 0.15), .material = {.restitution = 0, .friction = 0.9}}}}));
    // the paddle wheel: two crossed paddles turning about z past the belt's end
    paddle_ = bodies_.create({.name = "paddle wheel", .type = BodyType::Kinematic, .pose = {{-1.0, 0.85, 0}},
                              .angular_velocity = {0, 0, -2},
                              .shapes = {box_def({0.8, 0.05, 0.6}), box_def({0.05, 0.8, 0.6})}});
    // a bin beyond the wheel
    for (int side = -1; side <= 1; side += 2)
      bodies_.create({.name = "bin wall", .type = BodyType::Static, .pose = {{1.2 + side * 1.0, 0.4, 0}}, .shapes = {box_def({0.05, 0.4, 1})}});
    random_ = {};
    next_ = 0;
    set_belt();
    ctx_.camera->frame({-2.0f, 1.2f, 0}, 4.8f, 0.35f, 0.35f);
  }

  void AfterStep(double, double) override {
    // a new box on the belt's head every second, up to 24; boxes that left come back
    if (boxes_.size() < 24 && bodies_.time() >= next_) {
      boxes_.push_back(bodies_.create({.name = "parcel", .pose = {{-6, 2.0, 0.3 * (random_.next() - 0.5)}},
                                       .shapes = {box_def(Vec3(0.12 + 0.1 * random_.next()), 0.6, 300)}}));
      next_ = bodies_.time() + 1;
    }
    for (const RigidBodyId b : boxes_)
      if (glm::length(bodies_.center_of_mass(b)) > 14) {
        bodies_.set_pose(b, {{-6, 2.0, 0}});
        bodies_.set_velocity(b, Vec3(0), Vec3(0));
      }
  }

  void Draw(Renderer& r, double alpha) override {
    RigidSample::Draw(r, alpha);
    r.sphere({-6, 2.8, 0}, 0.3, kMarker);  // the belt's head
    r.text({-6, 3.3, 0}, "boxes drop here", colors::white, 0.8f, 0.5f);
  }

  void DrawUI() override {
    SolverControls();
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("belt speed", &belt_speed_, 0, 10, "%.1f m/s")) set_belt();
    Readout();
    ImGui::TextWrapped(
        "Kinematic bodies move at their set velocities whatever hits them (infinite mass) and push the dynamic "
        "ones: the rollers' surface speed drags the parcels by friction, the wheel's paddles hit them. "
        "--option belt_speed=M_PER_S.");
  }

  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  void set_belt() {
    for (const RigidBodyId r : rollers_) bodies_.set_velocity(r, Vec3(0), {0, 0, -belt_speed_ / 0.15});
  }
  float belt_speed_ = 2;
  double next_ = 0;
  std::vector<RigidBodyId> rollers_, boxes_;
  RigidBodyId paddle_{};
  Random random_;
};

const int kRegistered[] = {
    RegisterSample("Rigid bodies", "T-handle", THandle::Create),
    RegisterSample("Rigid bodies", "Bullet", Bullet::Create),
    RegisterSample("Rigid bodies", "Rain", Rain::Create),
    RegisterSample("Rigid bodies", "Dominoes", Dominoes::Create),
    RegisterSample("Rigid bodies", "Mass ratio", MassRatio::Create),
    RegisterSample("Rigid bodies", "Roll and slide", RollSlide::Create),
    RegisterSample("Rigid bodies", "Conveyor", Conveyor::Create),
};

}  // namespace
}  // namespace pba::app
