// "Soft bodies/Mass-spring vs XPBD": the same cloth (20 x 20 particles, 1 kg, pinned along
// one edge, released horizontal) twice, side by side. Left: a mass-spring network (Hooke
// springs on the structural, shear and bend edges) under an explicit integrator; right:
// XPBD distance constraints. Soft springs stretch; stiff springs need a step below
// 2 / omega_max (semi-implicit Euler), and past it the network explodes, while XPBD stays
// stiff and stable at any step. Both read out their strain and cost.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "method_colors.h"
#include "particles_common.h"
#include "renderer.h"
#include "sample.h"
#include "soft_common.h"

namespace pba::app {
namespace {

constexpr double kTop = 2.3;       // height of the pinned edge (m)
constexpr double kExplode = 3.0;   // a lane whose largest strain passes this (300 %) exploded
constexpr std::array<Method, 5> kExplicit = {Method::ExplicitEuler, Method::SemiImplicitEuler, Method::PositionVerlet,
                                             Method::VelocityVerlet, Method::Rk4};

// one cloth: its body, the last finite shape, and why it stopped (if it did)
struct Lane {
  SoftBody body;
  std::vector<Vec3f> last;     // positions after the last good step
  std::string status;          // empty while running
  StrainStats strain;          // now
  double peak = 0;             // largest max strain since the release
  double ms = 0;               // wall-clock ms of the last step
};

class CompareSample final : public SoftSample {
 public:
  explicit CompareSample(SampleContext& ctx) : SoftSample(ctx) {
    // --option k=N/M substeps=N n=N
    k_ = OptionNumber(ctx, "k", k_, 1, 1e6);
    ms_substeps_ = OptionInteger(ctx, "substeps", ms_substeps_, 1, 1000);
    n_ = OptionInteger(ctx, "n", n_, 2, 64);
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.0f, 1.75f, 0.25f}, 1.3f, 0.3f, 0.36f);
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<CompareSample>(ctx); }

  void Step(double, double dt) override {
    if (auto_release_ && t_ >= 6.0 && !grab_.held()) build();
    // the panel's settings apply from this step
    SoftBodyDef& ms = lanes_[0].body.settings();
    ms.method = method_, ms.substeps = ms_substeps_;
    ms.stretch_stiffness = ms.shear_stiffness = k_;
    ms.bend_stiffness = 0.1 * k_;
    SoftBodyDef& xp = lanes_[1].body.settings();
    xp.substeps = xpbd_substeps_, xp.iterations = xpbd_iterations_;
    xp.stretch_compliance = xp.shear_compliance = compliance_;
    xp.tethers = tethers_;
    for (Lane& l : lanes_) {
      if (!l.status.empty()) continue;
      try {
        l.body.step(t_, dt);
      } catch (const Error& e) {
        l.status = std::string("stopped: ") + e.what();
        continue;
      }
      l.ms = 1e3 * l.body.profile().total;
      l.strain = l.body.strain_stats();
      l.peak = std::max(l.peak, l.strain.max);
      // an exploded network stops with the reason; it is drawn as it was before the step
      // (within one step of 10 substeps the explosion grows by orders of magnitude)
      if (l.strain.max > kExplode) {
        char buf[200];
        const double lim = StabilityLimit(method_);
        if (lim > 0)
          std::snprintf(buf, sizeof buf, "exploded at t = %.2f s: omega_max h = %.2f is past the limit %.2f", t_ + dt,
                        omega_max_ * dt / ms_substeps_, lim);
        else
          std::snprintf(buf, sizeof buf, "exploded at t = %.2f s: explicit Euler gains energy at every step", t_ + dt);
        l.status = buf;
        continue;
      }
      l.last.resize(l.body.size());
      l.body.copy_positions(l.last);
    }
    t_ += dt;
  }

  void Draw(Renderer& r, double) override {
    const Color lane_colors[2] = {soft_colors::mass_spring, soft_colors::xpbd};
    for (int k = 0; k < 2; ++k) {
      Lane& l = lanes_[k];
      const Vec3 o = origin(k);
      // the bar the edge hangs from
      r.capsule(o + Vec3(-0.03, 0.02, 0), o + Vec3(1.03, 0.02, 0), 0.02, soft_colors::pole);
      // the cloth: live, or reddened in its last good shape once it stopped
      if (l.status.empty()) painter_.Draw(r, l.body, view_, soft_colors::cloth, {}, ctx_.draw);
      else if (!l.last.empty())
        painter_.DrawSurface(r, l.last, l.body.triangles(), Color::hex(0x9b3b4a), {}, {}, view_.strain_scale);
      if (ctx_.settings.show_labels) {
        char buf[160];
        if (k == 0) std::snprintf(buf, sizeof buf, "mass-spring, k = %.0f N/m", k_);
        else if (compliance_ > 0) std::snprintf(buf, sizeof buf, "XPBD, alpha = %.1e m/N", compliance_);
        else std::snprintf(buf, sizeof buf, "XPBD, rigid");
        r.text(o + Vec3(0.5, 0.24, 0), buf, lane_colors[k], 1.0f, 0.5f);
        if (l.status.empty())
          std::snprintf(buf, sizeof buf, "strain %.2f %% (max %.1f %%)", 100 * l.strain.mean, 100 * l.strain.max);
        else
          std::snprintf(buf, sizeof buf, "%s", l.status.rfind("exploded", 0) == 0 ? "EXPLODED" : "stopped");
        r.text(o + Vec3(0.5, 0.1, 0), buf, l.status.empty() ? colors::white : colors::red, 0.95f, 0.5f);
      }
    }
    grab_.Draw(r, Bodies());
    DrawBanner(ctx_, "Raise k until the mass-spring cloth stops stretching... and explodes. Drag either cloth.");
  }

  void DrawUI() override {
    bool rebuild = false;
    // the mass-spring lane
    ImGui::TextColored(ImVec4(soft_colors::mass_spring.r, soft_colors::mass_spring.g, soft_colors::mass_spring.b, 1),
                       "mass-spring network");
    ImGui::SetNextItemWidth(-110);
    if (ImGui::BeginCombo("integrator", std::string(label(method_)).c_str())) {
      for (Method m : kExplicit)
        if (ImGui::Selectable(std::string(label(m)).c_str(), m == method_)) {
          method_ = m;
          rebuild = true;
        }
      ImGui::EndCombo();
    }
    float k = static_cast<float>(k_);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("stiffness k", &k, 10.0f, 1e5f, "%.0f N/m", ImGuiSliderFlags_Logarithmic)) {
      k_ = k;
      rebuild = true;
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("structural and shear springs; bend springs get k/10");
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("substeps##ms", &ms_substeps_, 1, 200, "%d", ImGuiSliderFlags_Logarithmic);
    const double dt = ctx_.settings.stepper.fixed_dt, h = dt / ms_substeps_, lim = StabilityLimit(method_);
    ImGui::Text("h = %.3f ms, omega_max = %.0f rad/s", 1e3 * h, omega_max_);
    if (lim > 0) {
      const bool ok = omega_max_ * h < lim;
      ImGui::TextColored(ok ? ImVec4(0.6f, 0.85f, 0.6f, 1) : ImVec4(1, 0.45f, 0.4f, 1),
                         "omega_max h = %.2f %s %.2f: %s", omega_max_ * h, ok ? "<" : ">", lim,
                         ok ? "stable" : "unstable");
      ImGui::TextDisabled("needs >= %d substeps at this k", static_cast<int>(std::ceil(omega_max_ * dt / lim)));
    } else {
      ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "explicit Euler gains energy at every h");
    }
    lane_readout(lanes_[0]);

    // the XPBD lane
    ImGui::Separator();
    ImGui::TextColored(ImVec4(soft_colors::xpbd.r, soft_colors::xpbd.g, soft_colors::xpbd.b, 1), "XPBD");
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("substeps##xpbd", &xpbd_substeps_, 1, 60, "%d", ImGuiSliderFlags_Logarithmic);
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("iterations##xpbd", &xpbd_iterations_, 1, 20);
    ComplianceSlider("compliance", &compliance_, 1e-8, 1e-2);
    ImGui::Checkbox("long-range attachments", &tethers_);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("tethers (Kim et al. 2012) keep each particle within its built distance of the pinned edge");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("alpha = 1/k per constraint: 1/k of the mass-spring lane is %.1e", 1 / k_);
    lane_readout(lanes_[1]);

    ImGui::Separator();
    if (ImGui::Button("Release again") || rebuild) build();
    ImGui::SameLine();
    ImGui::Checkbox("every 6 s", &auto_release_);
    ViewControls(view_);
    ImGui::TextWrapped(
        "A mass-spring network is a stiff ODE: its fastest mode has omega_max ~ sqrt(k/m) times a factor of the "
        "mesh, and semi-implicit Euler is stable only while omega_max h < 2. Soft springs keep h legal but "
        "stretch under the cloth's weight; stiff springs need ever smaller steps. XPBD solves the constraints "
        "instead of integrating their forces: compliance alpha = 1/k enters as alpha/h^2, so a rigid "
        "constraint (alpha = 0) is stable at any step.");
  }

  std::vector<Color> ExpectedColors() const override { return {soft_colors::mass_spring, soft_colors::xpbd}; }

 private:
  Vec3 origin(int k) const { return Vec3(k == 0 ? -1.15 : 0.15, kTop, 0); }

  // a stopped lane cannot be grabbed
  std::span<SoftBody* const> Bodies() override {
    for (int k = 0; k < 2; ++k) ptrs_[k] = lanes_[k].status.empty() ? &lanes_[k].body : nullptr;
    return ptrs_;
  }

  void lane_readout(const Lane& l) {
    if (!l.status.empty()) {
      ImGui::PushTextWrapPos(0);
      ImGui::TextColored(ImVec4(1, 0.45f, 0.4f, 1), "%s", l.status.c_str());
      ImGui::PopTextWrapPos();
      return;
    }
    ImGui::Text("strain: mean %.2f %%, max %.2f %% (peak %.1f %%)", 100 * l.strain.mean, 100 * l.strain.max,
                100 * l.peak);
    ImGui::Text("step %.3f ms", l.ms);
  }

  // both cloths horizontal, pinned along their far edge
  void build() {
    grab_.Reset();
    t_ = 0;
    for (int k = 0; k < 2; ++k) {
      ClothDef c;
      c.origin = origin(k);
      c.edge_u = Vec3(1, 0, 0);
      c.edge_v = Vec3(0, 0, 1);
      c.nx = c.ny = n_;
      c.mass = 1;
      c.pins = ClothPins::FirstRow;
      SoftBodyDef d;
      d.damping = 0.1;
      if (k == 0) {
        d.solver = SoftSolver::MassSpring;
        d.method = method_;
        d.substeps = ms_substeps_;
        d.stretch_stiffness = d.shear_stiffness = k_;
        d.bend_stiffness = 0.1 * k_;
      } else {
        d.solver = SoftSolver::Xpbd;
        d.substeps = xpbd_substeps_;
        d.iterations = xpbd_iterations_;
        d.stretch_compliance = d.shear_compliance = compliance_;
        d.bend_compliance = 1e-3;
        d.tethers = tethers_;
      }
      Lane& l = lanes_[k];
      l.body = SoftBody::cloth_grid(c, d);
      l.status.clear();
      l.strain = {};
      l.peak = 0;
      l.last.resize(l.body.size());
      l.body.copy_positions(l.last);
    }
    omega_max_ = MaxAngularFrequency(lanes_[0].body);
  }

  std::array<Lane, 2> lanes_;
  std::array<SoftBody*, 2> ptrs_{};
  SoftPainter painter_;
  SoftView view_{.strain = true, .strain_scale = 0.1};
  Method method_ = Method::SemiImplicitEuler;
  double k_ = 300, compliance_ = 0, omega_max_ = 0, t_ = 0;
  int n_ = 20, ms_substeps_ = 10, xpbd_substeps_ = 10, xpbd_iterations_ = 1;
  bool auto_release_ = true, tethers_ = true;
};

static int reg = RegisterSample("Soft bodies", "Mass-spring vs XPBD", CompareSample::Create);

}  // namespace
}  // namespace pba::app
