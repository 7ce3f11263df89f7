// "Soft bodies/Jelly cube": a cube of tetrahedra (a mirrored Kuhn lattice, six tets per
// cell) with a compliant distance constraint on every tet edge and a volume constraint per
// tet (XPBD, Macklin, Mueller & Chentanez 2016), dropped slightly tilted onto the ground: it lands,
// bounces and wobbles. Its settings come from an elastic material (Young's modulus, Poisson
// ratio, damping time) through pba::jelly_settings. The panel reads its volume as a
// percentage of the rest volume. Options: young=PA poisson=NU damping_time=S cells=N height=M
// solver=xpbd|mass-spring (a mass-spring network gets the same energies: k = 1 / alpha).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"
#include "soft_common.h"

namespace pba::app {
namespace {

class JellySample final : public OneBodySample {
 public:
  explicit JellySample(SampleContext& ctx) : OneBodySample(ctx) {
    // --option young=PA poisson=NU damping_time=S cells=N height=M solver=xpbd|mass-spring
    for (const char* gone : {"compliance", "volume"})
      if (!ctx.option(gone, "").empty())
        throw Error(std::string("--option ") + gone + "=" + ctx.option(gone, "") +
                    ": no longer read; the jelly's compliances come from young=PA and poisson=NU");
    mat_.young = OptionNumber(ctx, "young", mat_.young, 1e2, 1e6);
    mat_.poisson = OptionNumber(ctx, "poisson", mat_.poisson, 0.27, 0.49);
    mat_.damping_time = OptionNumber(ctx, "damping_time", mat_.damping_time, 0, 0.1);
    cells_ = OptionInteger(ctx, "cells", cells_, 1, 16);
    height_ = OptionNumber(ctx, "height", height_, 0.5, 5);
    def_.friction = 0.6;
    view_.strain = false;
    ctx.renderer->style.grid_spacing = 0.25f;
    ctx.camera->frame({0.0f, 0.5f, -0.2f}, 1.6f, 0.6f, 0.25f);
    rebuild();
    if (SolverOption(ctx, SoftSolver::Xpbd) == SoftSolver::MassSpring) mass_spring();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<JellySample>(ctx); }

  void Step(double, double dt) override {
    if (auto_drop_ && t_ >= 6.0 && !grab_.held()) drop();
    body_.settings() = def_;
    body_.step(t_, dt, colliders_);
    t_ += dt;
    // the volume history
    volume_ = body_.volume() / body_.rest_volume();
    hist_.Push(t_, {100 * volume_});
  }

  void Draw(Renderer& r, double) override {
    painter_.Draw(r, body_, view_, soft_colors::jelly, {}, ctx_.draw);
    const Vec3 c = body_.center_of_mass();
    r.shadow(Vec3(c.x, std::max(c.y, 0.0), c.z), 0.35);
    grab_.Draw(r, Bodies());
    if (ctx_.settings.show_labels) {
      char buf[48];
      std::snprintf(buf, sizeof buf, "volume %.1f %%", 100 * volume_);
      r.text(c + Vec3(0, 0.45, 0), buf, colors::white, 1.0f, 0.5f);
    }
    DrawBanner(ctx_, "Grab the jelly with the mouse and throw it.");
  }

  void DrawUI() override {
    // the material: any change rebuilds the jelly with jelly_settings
    bool remake = false;
    float e = static_cast<float>(mat_.young), nu = static_cast<float>(mat_.poisson);
    float tau = static_cast<float>(1e3 * mat_.damping_time);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("Young's modulus", &e, 5e2f, 5e5f, "%.0f Pa", ImGuiSliderFlags_Logarithmic)) {
      mat_.young = std::clamp(double(e), 1e2, 1e5);
      remake = true;
    }
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("E: gelatin is about 1e3 to 1e4 Pa; stiffer needs more substeps (for the app's step)");
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("Poisson ratio", &nu, 0.27f, 0.49f, "%.3f")) {
      mat_.poisson = std::clamp(double(nu), 0.27, 0.49);
      remake = true;
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("nu: the edges alone give 5/19 = 0.263; 0.5 (incompressible) locks");
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("damping time", &tau, 0.0f, 20.0f, "%.1f ms")) {
      mat_.damping_time = std::max(0.0, 1e-3 * tau);
      remake = true;
    }
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("tau: every edge gets damping c = tau k; a mode of angular frequency omega gets the "
                        "damping ratio tau omega / 2");
    ImGui::SetNextItemWidth(-110);
    remake |= ImGui::SliderInt("cells per side", &cells_, 1, 8);
    ImGui::Text("stretch compliance %.3g m/N (k = %.0f N/m)", derived_.stretch_compliance,
                1 / derived_.stretch_compliance);
    ImGui::Text("volume compliance %.3g m^5/N", derived_.volume_compliance);
    ImGui::Text("spring damping %.3g N s/m, %d substeps", derived_.spring_damping, derived_.substeps);
    if (remake) rebuild();
    ImGui::Separator();
    // the solver rows (they edit def_ until the next rebuild), friction and the drop
    const SoftSolver before = def_.solver;
    SolverRows();
    if (before != def_.solver && def_.solver == SoftSolver::MassSpring) mass_spring();
    if (def_.solver == SoftSolver::MassSpring && def_.method == Method::SemiImplicitEuler && needed_ > def_.substeps)
      ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "needs %.0f substeps to be stable", needed_);
    float mu = static_cast<float>(def_.friction);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("friction", &mu, 0.0f, 1.5f, "%.2f")) def_.friction = mu;
    float h = static_cast<float>(height_);
    ImGui::SetNextItemWidth(-110);
    bool again = ImGui::SliderFloat("drop height", &h, 0.5f, 3.0f, "%.2f m");
    if (again) height_ = h;
    if (ImGui::Button("Drop again") || again) drop();
    ImGui::SameLine();
    ImGui::Checkbox("every 6 s", &auto_drop_);
    ViewControls(view_);
    ImGui::Text("volume: %.2f %% of rest", 100 * volume_);
    SoftReadout(body_);
    ImGui::Text("%zu particles, %zu tets, %zu edges", body_.size(), body_.tets().size(), body_.constraint_count());
    PlotAxes ax;
    ax.x_label = "t (s)";
    ax.y_label = "volume (% of rest)";
    ax.y_min_span = 2;
    hist_.Plot("volume", std::span<const Color>(&soft_colors::jelly, 1), ax, 100);
    ImGui::TextWrapped(
        "Every tet edge is a spring of stiffness k = 4 G a / 3 (G the shear modulus, a the cell edge) and every "
        "tet a volume constraint C = V - V0 of compliance V0 / (K - 16 G / 9), which adds the rest of the bulk "
        "modulus K (Macklin et al. 2016). Softer jelly wobbles and squashes more; a lower Poisson ratio lets it "
        "lose volume on impact; a longer damping time settles it sooner.");
  }

  std::vector<Color> ExpectedColors() const override { return {colors::white}; }

 private:
  // the jelly: a tilted cube above the ground
  JellyDef shape() const {
    JellyDef j;
    j.center = Vec3(0, height_, 0);
    j.size = Vec3(0.5);
    j.rotation = glm::angleAxis(0.1, glm::normalize(Vec3(1, 0.3, 0.8)));
    j.nx = j.ny = j.nz = cells_;
    j.mass = 1.0;
    return j;
  }

  // new settings from the material (keeping the solver and friction), then a new drop
  void rebuild() {
    const JellyDef j = shape();
    derived_ = jelly_settings(j, mat_, ctx_.settings.stepper.fixed_dt);
    const SoftSolver solver = def_.solver;
    const Method method = def_.method;
    const double mu = def_.friction;
    def_ = derived_;
    def_.friction = mu;
    def_.thickness = 0.005;
    // a mass-spring network gets the same energies: k = 1 / alpha per edge and per tet
    def_.stretch_stiffness = 1 / derived_.stretch_compliance;
    def_.volume_stiffness = 1 / derived_.volume_compliance;
    def_.method = method;
    drop();
    if (solver == SoftSolver::MassSpring) mass_spring();
  }

  // def_ becomes the mass-spring settings of body_ (UseMassSpring: substeps for omega_max
  // h, the volume force included), with more substeps if the edge damping c = tau k needs
  // them: semi-implicit Euler on a mode u'' = -omega^2 u - gamma u' with gamma = tau
  // omega^2 (Rayleigh) has an update matrix of determinant 1 - h gamma and trace 2 - h
  // gamma - h^2 omega^2, stable (Jury) for omega^2 h (h + 2 tau) < 4; kept under 80 % of
  // it at omega_max: h <= sqrt(tau^2 + 3.2 / omega^2) - tau
  void mass_spring() {
    const double dt = ctx_.settings.stepper.fixed_dt;
    UseMassSpring(def_, body_, dt);
    needed_ = 0;
    if (def_.method == Method::SemiImplicitEuler && def_.stretch_stiffness > 0) {
      const double omega = MaxAngularFrequency(body_, def_);
      const double tau = def_.spring_damping / def_.stretch_stiffness;
      if (omega > 0) {
        const double h = std::sqrt(tau * tau + 3.2 / (omega * omega)) - tau;
        needed_ = std::ceil(dt / h);
        def_.substeps = std::clamp(static_cast<int>(std::min(needed_, 400.0)), def_.substeps, 400);
      }
    }
    body_.settings() = def_;
  }

  // the same jelly dropped again with the current settings, and the ground
  void drop() {
    Restart();
    hist_.Clear();
    body_ = SoftBody::jelly_box(shape(), def_);
    volume_ = 1;
    colliders_ = {Collider::plane(Vec3(0, 1, 0), 0)};
  }

  std::vector<Collider> colliders_;
  PlotHistory hist_{1, 6.0};  // volume (% of rest) over the last 6 s
  // the material the settings come from: the default but for a damping time of 5 ms (a
  // damping ratio of about 0.08 for the sway), with which the cube dropped from 1.4 m,
  // tilted 0.1 rad, hops 4 cm, rocks and rests 2 cm from where it landed after 3 s (the
  // default 2.5 ms rolls it 1.1 m; measured 2026-12-07, docs/soft-bodies.md)
  JellyMaterial mat_{.damping_time = 5e-3};
  SoftBodyDef derived_;       // jelly_settings(shape(), mat_, the app's dt)
  double needed_ = 0;         // substeps the mass-spring network needs (mass_spring())
  int cells_ = 4;
  double height_ = 1.4, volume_ = 1;
  bool auto_drop_ = true;
};

static int reg = RegisterSample("Soft bodies", "Jelly cube", JellySample::Create);

}  // namespace
}  // namespace pba::app
