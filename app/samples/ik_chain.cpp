// "Inverse kinematics/Chain solvers": one chain of 2 to 1000 bones reaching for a target
// that follows the mouse, with every solver of pba/ik.h selectable at run time (CCD, the
// Jacobian family, FABRIK), warm start and solve-then-blend, and readouts of iterations,
// residual and time per solve with a plot of the solve times.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <imgui.h>

#include "ik_common.h"
#include "pba/ik_scenes.h"
#include "plot.h"
#include "ui.h"

namespace pba::app {
namespace {

using namespace ik_demo;

class IkChain final : public IkSample {
 public:
  explicit IkChain(SampleContext& ctx) : IkSample(ctx) {
    // --option bones=N, solver=NAME, joint=ball|hinge
    const std::string nb = ctx.option("bones", std::to_string(g_bones));
    char* end = nullptr;
    const long n = std::strtol(nb.c_str(), &end, 10);
    if (end != nb.c_str() + nb.size() || n < 2 || n > 1000) throw Error("--option bones=" + nb + ": expected an integer in [2, 1000]");
    bones_ = static_cast<int>(n);
    const std::string sv = ctx.option("solver", "");
    if (!sv.empty()) {
      method_ = ik::parse_method(sv, "--option solver");
      if (method_ == ik::Method::Analytic1Dof || method_ == ik::Method::Analytic3Dof || method_ == ik::Method::TwoBone)
        throw Error("--option solver=" + sv + ": the chain sample needs an iterative solver (ccd, jt, pinv, dls, sdls, fabrik)");
    } else {
      method_ = g_method;
    }
    const std::string jt = ctx.option("joint", g_hinge ? "hinge" : "ball");
    if (jt != "ball" && jt != "hinge") throw Error("--option joint=" + jt + ": expected ball or hinge");
    hinge_ = jt == "hinge";
    ctx.camera->frame({0.0f, 0.62f, 0.0f}, 0.68f, 0.45f, 0.22f);
    handles_.push_back({Vec3(0.3, 0.9, 0.1), kTargetColors[0], "target", 0.035});
    build();
    Animate(0);
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<IkChain>(ctx); }

  void Draw(Renderer& r, double) override {
    DrawPedestal(r, skel_->root_position(), 0.06);
    SkeletonStyle st;
    st.bone_radius = std::clamp(0.25 * skel_->lengths()[0], 0.007, 0.02);
    DrawSkeleton(r, *skel_, st);
    if (blend_on_) {
      // the goal pose the visible chain blends toward, as a ghost
      SkeletonStyle g = st;
      g.alpha = 0.25f;
      g.joints = false;
      DrawSkeleton(r, blend_->goal(), g);
    }
    DrawResiduals(r, *skel_);
    DrawHandles(r);
    if (ctx_.settings.show_labels) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%s, %d bones: %d iterations, residual %.2g mm", MethodLabel(method_), bones_,
                    last_.iterations, last_.residual * 1000);
      r.text(skel_->root_position() + Vec3(0, -0.08, 0.15), buf, colors::white, 1.0f, 0.5f);
    }
    DrawStatus(DragHelp("the red target") + " Solver and bones: in the panel.");
  }

  void DrawUI() override {
    ImGui::TextWrapped("A chain of bones reaching for the red target. Every solver runs on the same skeleton; "
                       "switch between them while the target moves.");
    ImGui::SetNextItemWidth(-90);
    if (MethodCombo("solver", &method_, *skel_)) {
      g_method = method_;
      settings_.method = method_;
      rebuild_solver();
    }
    ImGui::SetNextItemWidth(-90);
    if (ImGui::SliderInt("bones", &bones_, 2, 1000, "%d", ImGuiSliderFlags_Logarithmic)) {
      bones_ = std::clamp(bones_, 2, 1000);
      g_bones = bones_;
      build();
    }
    int jt = hinge_ ? 1 : 0;
    ImGui::SetNextItemWidth(-90);
    if (ImGui::Combo("joints", &jt, "ball (3 DOF)\0hinge (Z, Y alternating)\0")) {
      hinge_ = g_hinge = jt == 1;
      build();
    }
    // solver settings
    int cap = effective_cap();
    ImGui::SetNextItemWidth(-90);
    if (ImGui::SliderInt("iteration cap", &cap, 1, 5000, "%d", ImGuiSliderFlags_Logarithmic)) {
      settings_.max_iterations = std::clamp(cap, 1, 100000);
      rebuild_solver();
    }
    float tol_mm = static_cast<float>(settings_.tolerance * 1000);
    ImGui::SetNextItemWidth(-90);
    if (ImGui::SliderFloat("tolerance", &tol_mm, 0.01f, 10.0f, "%.2f mm", ImGuiSliderFlags_Logarithmic)) {
      settings_.tolerance = std::max(tol_mm, 0.001f) / 1000.0;
      rebuild_solver();
    }
    if (method_ == ik::Method::Dls || method_ == ik::Method::Sdls) {
      float damp = static_cast<float>(settings_.damping > 0 ? settings_.damping : 0.02);
      ImGui::SetNextItemWidth(-90);
      if (ImGui::SliderFloat("damping", &damp, 0.001f, 0.5f, "%.3f", ImGuiSliderFlags_Logarithmic)) {
        settings_.damping = std::max(damp, 0.0001f);
        rebuild_solver();
      }
    }
    if (settings_.max_iterations == 0 && cap < ik::default_max_iterations(method_))
      ImGui::TextDisabled("(cap lowered from %d for the frame rate)", ik::default_max_iterations(method_));
    if (ImGui::Checkbox("warm start", &settings_.warm_start)) rebuild_solver();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("start each solve from the last frame's pose (off: from the rest pose)");
    ImGui::SameLine();
    if (ImGui::Checkbox("solve, then blend", &blend_on_)) rebuild_solver();
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("move the chain only once a solution is found, blending to it over time (the ghost is the goal)");
    if (blend_on_) {
      int b = slerp_ ? 1 : 0;
      ImGui::SetNextItemWidth(120);
      if (ImGui::Combo("##blend", &b, "lerp\0slerp\0")) slerp_ = b == 1, rebuild_solver();
      ImGui::SameLine();
      ImGui::SetNextItemWidth(-90);
      if (ImGui::SliderFloat("blend rate", &blend_rate_, 0.5f, 40.0f, "%.1f /s", ImGuiSliderFlags_Logarithmic))
        rebuild_solver();
    }
    if (ImGui::Button("Bend (cold start)")) {
      ik::scenes::bent_pose(*skel_);
      rebuild_solver();
    }
    ImGui::SameLine();
    AnimationUI();

    // readouts of the last solve
    ImGui::Separator();
    ImGui::Text("%d bones, %d DOF", skel_->bone_count(), skel_->dof_count());
    ImGui::Text("iterations   %d of %d", last_.iterations, cap);
    ImGui::Text("residual     %.3g mm %s", last_.residual * 1000, last_.converged ? "(converged)" : "(not converged)");
    ImGui::Text("time/solve   %.1f us", last_us_);
    ImGui::Text("time/iter    %.2f us", last_.iterations > 0 ? last_us_ / last_.iterations : 0.0);
    ImGui::TextDisabled("reach %.2f m, target at %.2f m", skel_->total_length(),
                        glm::length(handles_[0].pos - skel_->root_position()));
    // time per solve over the last frames
    float ys[History::kSize], xs[History::kSize];
    const int n = times_.ordered(ys);
    for (int i = 0; i < n; ++i) xs[i] = static_cast<float>(i - n + 1);
    PlotSeries s;
    s.x = xs, s.y = ys, s.count = n, s.color = colors::yellow, s.width = 1.8f;
    PlotAxes ax;
    ax.x_label = "frame";
    ax.y_label = "time per solve (us)";
    ax.y_include_zero = true;
    ax.y_clamp_lo = 0.0f;
    ax.y_min_span = 1.0f;
    ax.y_format = "%.0f";
    LinePlot("solve_time", {s}, ax, 130);
    ImGui::TextWrapped("%s", explanation());
  }

  FiniteCheck CheckFinite() const override {
    return check_finite<Vec3>(skel_->tips(), skel_->starts(), "chain bone", time_, 0);
  }

  std::vector<Color> ExpectedColors() const override {
    // joints are drawn up to 200 bones, orange hinges or cyan balls
    if (bones_ > 200) return {kTargetColors[0]};
    return {kTargetColors[0], hinge_ ? kHingeColor : kBallColor};
  }

 protected:
  void Animate(double t) override {
    const Vec3 base = skel_ ? skel_->root_position() : Vec3(0, 0.12, 0);
    handles_[0].pos = Lissajous(base + Vec3(0.0, 0.5, 0.0), Vec3(0.42, 0.22, 0.25), t);
  }

  void Solve(double dt) override {
    skel_->set_target(0, handles_[0].pos);
    const pba::Stopwatch sw;
    last_ = blend_on_ ? blend_->update(dt) : solver_->solve();
    last_us_ = 1e6 * sw.seconds();
    times_.push(static_cast<float>(last_us_));
    if (blend_on_) {
      // the readout is the visible chain's error, not the goal's
      if (skel_->kinematics_dirty()) skel_->forward_kinematics();
      last_.residual = skel_->max_effector_error();
    }
  }

  bool ReportEffector(Vec3* e, double* res) const override {
    *e = skel_->tips()[skel_->effector(0).bone];
    *res = skel_->effector_error(0);
    return true;
  }

 private:
  // the chain from the shared scenes (1 m, along +X), stood up on a pedestal
  void build() {
    const ik::Skeleton flat = ik::scenes::make_chain(bones_, hinge_ ? ik::JointType::Hinge : ik::JointType::Ball, false);
    ik::SkeletonDef def = DefOf(flat);
    def.root_position = Vec3(0, 0.12, 0);
    def.root_rotation = glm::angleAxis(0.5 * kPi, Vec3(0, 0, 1));
    blend_.reset();
    solver_.reset();
    skel_ = std::make_unique<ik::Skeleton>(def);
    ik::scenes::bent_pose(*skel_);
    skel_->add_effector(skel_->bone_count() - 1, handles_[0].pos);
    settings_.method = method_;
    rebuild_solver();
    times_ = History{};
  }

  // the iteration cap the solver gets: the user's, else the method's default lowered on
  // long chains so a frame stays interactive (the solve continues next frame: warm start)
  int effective_cap() const {
    if (settings_.max_iterations > 0) return settings_.max_iterations;
    return std::min(ik::default_max_iterations(method_), std::max(10, 50000 / bones_));
  }

  void rebuild_solver() {
    blend_.reset();
    ik::SolverSettings set = settings_;
    set.method = method_;
    set.max_iterations = effective_cap();
    solver_ = std::make_unique<ik::Solver>(*skel_, set);
    if (blend_on_)
      blend_ = std::make_unique<ik::SolveThenBlend>(*skel_, set, slerp_ ? ik::Blend::Slerp : ik::Blend::Lerp,
                                                   blend_rate_);
  }

  const char* explanation() const {
    switch (method_) {
      case ik::Method::Ccd:
        return "CCD turns one joint at a time, from the tip to the root, to aim the effector at the target. "
               "Cheap per step, but the tip bones do most of the work, so long chains curl.";
      case ik::Method::JacobianTranspose:
        return "Jacobian transpose: dtheta = alpha J^T e. No inversion, so each iteration is cheap, but it "
               "needs many of them near the target.";
      case ik::Method::PseudoInverse:
        return "Pseudo-inverse: dtheta = J^T (J J^T)^-1 e, the smallest joint change that moves the effector "
               "by e. Fast to converge, unstable near singular (straight) poses.";
      case ik::Method::Dls:
        return "Damped least squares: J^T (J J^T + lambda^2 I)^-1 e. The damping keeps it stable near "
               "singularities and for unreachable targets, at the cost of slower convergence.";
      case ik::Method::Sdls:
        return "Selectively damped least squares (Buss and Kim): damps each singular direction of J by how "
               "much it would move the joints.";
      case ik::Method::Fabrik:
        return "FABRIK works on positions: drag the tip to the target and the chain behind it, then pin the "
               "root and drag forward again; joint rotations are read back at the end.";
      default: return "";
    }
  }

  // the user's choices survive a restart (R) and a sample switch
  static inline int g_bones = 10;
  static inline ik::Method g_method = ik::Method::Fabrik;
  static inline bool g_hinge = false;

  int bones_ = 10;
  bool hinge_ = false;
  ik::Method method_ = ik::Method::Fabrik;
  ik::SolverSettings settings_;
  bool blend_on_ = false, slerp_ = true;
  float blend_rate_ = 8.0f;
  std::unique_ptr<ik::Skeleton> skel_;
  std::unique_ptr<ik::Solver> solver_;
  std::unique_ptr<ik::SolveThenBlend> blend_;
  ik::SolveResult last_;
  double last_us_ = 0;
  History times_;
};

static int reg = RegisterSample("Inverse kinematics", "Chain solvers", IkChain::Create);

}  // namespace
}  // namespace pba::app
