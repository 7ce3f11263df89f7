// "Soft bodies/Rope and chain": three XPBD chains with a heavy load, released at 45 degrees,
// each given the same work per step (substeps x iterations constraint sweeps) split a
// different way: all iterations (1 x N), the split chosen in the panel, and all substeps
// (N x 1). Macklin et al. 2019 ("Small Steps in Physics Simulation") show that substeps
// beat iterations for the same cost: the stretch read out over each chain says so. Grab
// any link with the mouse; pin both ends to make a bridge.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/gtx/quaternion.hpp>
#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"
#include "soft_common.h"

namespace pba::app {
namespace {

constexpr int kLanes = 3;
// lane colours; strain tints a link towards red
constexpr std::array<Color, kLanes> kLaneColors = {Color::hex(0x8e4ec6), Color::hex(0x00a2c7), Color::hex(0x46a758)};
constexpr double kLength = 2.0;  // rest length of a chain (m)
constexpr double kTop = 3.0;     // height of the pins (m)

// one chain: its body, the split of its work, its stretch
struct Lane {
  SoftBody body;
  int substeps = 1, iterations = 1;
  double stretch = 0;       // (length / rest length - 1)
  double ms = 0;            // wall-clock ms of the last step
};

class RopeSample final : public SoftSample {
 public:
  explicit RopeSample(SampleContext& ctx) : SoftSample(ctx) {
    // --option segments=N load=RATIO substeps=N iterations=N both=0|1
    segments_ = OptionInteger(ctx, "segments", segments_, 2, 400);
    load_ratio_ = OptionNumber(ctx, "load", load_ratio_, 1, 1000);
    substeps_ = OptionInteger(ctx, "substeps", substeps_, 1, 200);
    iterations_ = OptionInteger(ctx, "iterations", iterations_, 1, 200);
    both_ends_ = OptionFlag(ctx, "both", false);
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.1f, 1.8f, 0.0f}, 3.4f, 0.0f, 0.12f);
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<RopeSample>(ctx); }

  void Step(double, double dt) override {
    if (auto_release_ && t_ >= 8.0 && !grab_.held()) build();
    // every lane steps with its own split of the same budget
    for (Lane& l : lanes_) {
      l.body.settings().stretch_compliance = compliance_;
      l.body.step(t_, dt, colliders_);
      l.ms = 1e3 * l.body.profile().total;
      l.stretch = length(l.body) / kLength - 1;
    }
    t_ += dt;
    // the stretch history (%)
    hist_.Push(t_, {100 * lanes_[0].stretch, 100 * lanes_[1].stretch, 100 * lanes_[2].stretch});
  }

  void Draw(Renderer& r, double) override {
    for (int k = 0; k < kLanes; ++k) {
      const Lane& l = lanes_[k];
      const SoftBody& b = l.body;
      const Color c = kLaneColors[k];
      // links as capsules, reddened by their strain (fully red at 100 %)
      for (std::size_t i = 0; i + 1 < b.size(); ++i) {
        const Vec3 p = b.position(i), q = b.position(i + 1);
        const double e = std::abs(glm::length(q - p) / rest_ - 1);
        const float u = static_cast<float>(std::min(1.0, e));
        // a lit box per link (cheap on a software rasteriser, unlike a capsule's spheres)
        const Vec3 dq = q - p;
        const double len = glm::length(dq);
        if (!(len > 1e-9)) continue;
        const Quat rot = glm::rotation(Vec3(0, 1, 0), dq / len);
        r.box(0.5 * (p + q), Vec3(0.016, 0.5 * len, 0.016), rot,
              Color{c.r + (colors::red.r - c.r) * u, c.g + (colors::red.g - c.g) * u, c.b + (colors::red.b - c.b) * u, 1});
      }
      // the load and the pins
      r.sphere(b.position(load_index()), 0.09, Color::hex(0x4b5563));
      for (std::uint32_t p : b.pins())
        if (p != b.grabbed()) r.box(b.position(p) + Vec3(0, 0.03, 0), {0.06, 0.05, 0.06}, Quat(1, 0, 0, 0), soft_colors::pole);
      if (ctx_.settings.show_labels) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%d x %d: %+.1f %%", l.substeps, l.iterations, 100 * l.stretch);
        r.text(anchor(k) + Vec3(0, 0.25, 0), buf, c, 1.0f, 0.5f);
      }
    }
    // the grab
    grab_.Draw(r, Bodies());
    DrawBanner(ctx_, "Same work per step, split three ways (substeps x iterations). Drag any link with the mouse.");
  }

  void DrawUI() override {
    // the split of the middle chain; the outer ones take the same budget one way
    bool rebuild = false;
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("substeps", &substeps_, 1, 40);
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("iterations", &iterations_, 1, 40);
    ImGui::TextDisabled("budget: %d sweeps per step for each chain", substeps_ * iterations_);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("load / link", &load_ratio_f_, 1.0f, 1000.0f, "%.0f x", ImGuiSliderFlags_Logarithmic)) {
      load_ratio_ = load_ratio_f_;
      rebuild = true;
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("mass of the load over the mass of one link");
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("links", &segments_, 4, 100);
    ComplianceSlider("compliance", &compliance_, 1e-7, 1e-2);
    rebuild |= ImGui::Checkbox("long-range attachments", &tethers_);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("tethers (Kim et al. 2012): no link may drift further from the pin than it was built; "
                        "they hide the solver's stretch, so they start off here");
    rebuild |= ImGui::Checkbox("pin both ends", &both_ends_);
    ImGui::SameLine();
    ImGui::Checkbox("release every 8 s", &auto_release_);
    if (ImGui::Button("Release again") || rebuild) build();

    // per chain: split, stretch, cost
    if (ImGui::BeginTable("lanes", 4, ImGuiTableFlags_SizingStretchProp | ImGuiTableFlags_RowBg)) {
      ImGui::TableSetupColumn("split", ImGuiTableColumnFlags_WidthStretch, 1.3f);
      ImGui::TableSetupColumn("stretch", ImGuiTableColumnFlags_WidthStretch, 1.0f);
      ImGui::TableSetupColumn("max strain", ImGuiTableColumnFlags_WidthStretch, 1.2f);
      ImGui::TableSetupColumn("ms/step", ImGuiTableColumnFlags_WidthStretch, 1.0f);
      ImGui::TableHeadersRow();
      for (int k = 0; k < kLanes; ++k) {
        const Lane& l = lanes_[k];
        const Color c = kLaneColors[k];
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::TextColored(ImVec4(c.r, c.g, c.b, 1), "%d x %d", l.substeps, l.iterations);
        ImGui::TableNextColumn();
        ImGui::Text("%+.2f %%", 100 * l.stretch);
        ImGui::TableNextColumn();
        ImGui::Text("%.2f %%", 100 * l.body.strain_stats().max);
        ImGui::TableNextColumn();
        ImGui::Text("%.3f", l.ms);
      }
      ImGui::EndTable();
    }
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "stretch of the chain (%)";
    ax.y_include_zero = true;
    ax.y_min_span = 1.0f;
    hist_.Plot("stretch", kLaneColors, ax, 130);
    ImGui::TextWrapped(
        "Each chain is distance constraints solved by XPBD (Macklin, Mueller & Chentanez 2016) with a heavy load "
        "at the end. Gauss-Seidel iterations converge slowly on a long chain with a large mass ratio, so one "
        "substep with many iterations stretches; many substeps of one iteration (Macklin et al. 2019) shrink the "
        "step, and with it the error, for the same cost.");
  }

  std::vector<Color> ExpectedColors() const override { return {kLaneColors[0], kLaneColors[2]}; }

 private:
  Vec3 anchor(int k) const { return Vec3((k - 1) * 2.4, kTop, 0); }
  double span() const { return 0.8 * kLength; }  // distance between the pins of a bridge
  std::uint32_t load_index() const { return static_cast<std::uint32_t>(both_ends_ ? segments_ / 2 : segments_); }

  std::span<SoftBody* const> Bodies() override {
    for (int k = 0; k < kLanes; ++k) body_ptrs_[k] = &lanes_[k].body;
    return body_ptrs_;
  }

  // the length along the chain (m)
  static double length(const SoftBody& b) {
    double s = 0;
    for (std::size_t i = 0; i + 1 < b.size(); ++i) s += glm::length(b.position(i + 1) - b.position(i));
    return s;
  }

  // three horizontal chains from their pins, a heavy load at the end (or the middle)
  void build() {
    grab_.Reset();
    t_ = 0;
    hist_.Clear();
    load_ratio_f_ = static_cast<float>(load_ratio_);
    const int n = segments_ + 1;
    rest_ = kLength / segments_;
    const int budget = substeps_ * iterations_;
    const int splits[kLanes][2] = {{1, budget}, {substeps_, iterations_}, {budget, 1}};
    colliders_ = {Collider::plane(Vec3(0, 1, 0), 0)};
    for (int k = 0; k < kLanes; ++k) {
      SoftMesh m;
      const Vec3 a = anchor(k);
      // straight, 45 degrees below the horizontal
      const Vec3 dir = glm::normalize(Vec3(1, -1, 0));
      for (int i = 0; i < n; ++i) m.positions.push_back(a + dir * (kLength * i / segments_));
      m.masses.assign(n, 0.01);
      m.masses[load_index()] = 0.01 * load_ratio_;
      for (int i = 0; i + 1 < n; ++i) {
        m.constraints.push_back({.a = std::uint32_t(i), .b = std::uint32_t(i + 1)});
        m.colors.push_back(i % 2);
      }
      m.pinned.push_back(0);
      SoftBodyDef d;
      d.solver = SoftSolver::Xpbd;
      d.substeps = splits[k][0];
      d.iterations = splits[k][1];
      d.stretch_compliance = compliance_;
      d.thickness = 0.02;
      d.tethers = tethers_;
      Lane& l = lanes_[k];
      l.body = SoftBody::from_mesh(m, d, "chain");
      // a bridge: the far end pinned level with the first, so the chain hangs slack
      if (both_ends_) l.body.pin(static_cast<std::size_t>(n - 1), a + Vec3(span(), 0, 0));
      l.substeps = d.substeps, l.iterations = d.iterations;
      l.stretch = 0;
    }
  }

  std::array<Lane, kLanes> lanes_;
  std::array<SoftBody*, kLanes> body_ptrs_{};
  std::vector<Collider> colliders_;
  PlotHistory hist_{kLanes, 10.0};  // each chain's stretch (%) over the last 10 s
  int segments_ = 40, substeps_ = 4, iterations_ = 5;
  double load_ratio_ = 100, compliance_ = 0, rest_ = 0.05, t_ = 0;
  float load_ratio_f_ = 100;
  bool both_ends_ = false, auto_release_ = true, tethers_ = false;
};

static int reg = RegisterSample("Soft bodies", "Rope and chain", RopeSample::Create);

}  // namespace
}  // namespace pba::app
