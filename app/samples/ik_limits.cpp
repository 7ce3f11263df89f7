// "Inverse kinematics/Joint limits": a chain whose hinges (or ball joints) have limits,
// drawn on the joints (hinge arcs, swing cones), next to a free chain chasing the same
// target as a ghost. Joints of the free chain that leave the limits turn red.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <imgui.h>

#include "ik_common.h"
#include "pba/ik_scenes.h"

namespace pba::app {
namespace {

using namespace ik_demo;

constexpr Color kViolation = Color::hex(0xff3b30);

class IkLimits final : public IkSample {
 public:
  explicit IkLimits(SampleContext& ctx) : IkSample(ctx) {
    const std::string jt = ctx.option("joint", g_ball ? "ball" : "hinge");
    if (jt != "ball" && jt != "hinge") throw Error("--option joint=" + jt + ": expected ball or hinge");
    ball_ = jt == "ball";
    const std::string sv = ctx.option("solver", "");
    method_ = sv.empty() ? g_method : ik::parse_method(sv, "--option solver");
    handles_.push_back({Vec3(0.3, 0.7, 0.2), kTargetColors[0], "target", 0.03});
    ctx.camera->frame({0.0f, 0.55f, 0.0f}, 0.62f, 0.3f, 0.22f);
    build();
    Animate(0);
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<IkLimits>(ctx); }

  void Draw(Renderer& r, double) override {
    DrawPedestal(r, kRoot, 0.05);
    SkeletonStyle st;
    st.bone_radius = 0.016;
    if (compare_) {
      // the free chain as a ghost, its joints beyond the limits in red
      SkeletonStyle g = st;
      g.alpha = 0.3f;
      g.joints = false;
      DrawSkeleton(r, *free_, g);
      for (int i = 0; i < free_->bone_count(); ++i)
        if (excess(*free_, i) > 1e-3) r.sphere(free_->starts()[i], 0.026, kViolation);
    }
    DrawSkeleton(r, *skel_, st);
    // the limits on the joints: the library's arcs and cones, drawn thick
    ik::SkeletonDrawOptions o;
    o.bones = o.joints = o.targets = false;
    o.limits = true;
    r.set_line_width(2.5f);
    skel_->draw(r, o);
    r.set_line_width(1.5f);
    DrawResiduals(r, *skel_);
    DrawHandles(r);
    DrawStatus(DragHelp("the red target") +
               "\nSolid: the limited chain (yellow: its limits). Ghost: the free chain, red where it breaks them.");
  }

  void DrawUI() override {
    ImGui::TextWrapped("Each joint may only move inside its limits (yellow: hinge arcs of +-%.0f deg, or swing "
                       "cones of %.0f deg). The ghost is the same chain without limits chasing the same target; "
                       "its joints that leave the limits turn red.",
                       ik::scenes::kHingeLimit * 180 / kPi, ik::scenes::kSwingLimit * 180 / kPi);
    if (ImGui::Checkbox("limits on", &limited_)) build();
    ImGui::SameLine();
    ImGui::Checkbox("compare with the free chain", &compare_);
    int jt = ball_ ? 1 : 0;
    ImGui::SetNextItemWidth(-90);
    if (ImGui::Combo("joints", &jt, "hinge (Z, Y alternating)\0ball (cone + twist)\0")) {
      ball_ = g_ball = jt == 1;
      build();
    }
    ImGui::SetNextItemWidth(-90);
    if (ImGui::SliderInt("bones", &bones_, 2, 24)) build();
    ImGui::SetNextItemWidth(-90);
    if (MethodCombo("solver", &method_, *skel_)) {
      g_method = method_;
      build();
    }
    AnimationUI();
    ImGui::Separator();
    int bad = -1;
    const bool ok = skel_->within_limits(1e-6, &bad);
    ImGui::Text("chain:      residual %.3g mm, %d iterations", last_.residual * 1000, last_.iterations);
    ImGui::Text("            within limits: %s", ok ? "yes" : "NO");
    int count = 0;
    double worst = 0;
    for (int i = 0; i < free_->bone_count(); ++i) {
      const double e = excess(*free_, i);
      if (e > 1e-3) ++count, worst = std::max(worst, e);
    }
    ImGui::Text("free chain: residual %.3g mm", free_last_.residual * 1000);
    ImGui::Text("            %d joint%s beyond the limits (worst by %.0f deg)", count, count == 1 ? "" : "s", worst * 180 / kPi);
  }

  FiniteCheck CheckFinite() const override {
    return check_finite<Vec3>(skel_->tips(), free_->tips(), "chain bone", time_, 0);
  }
  std::vector<Color> ExpectedColors() const override {
    if (!limited_) return {kTargetColors[0]};
    return {kTargetColors[0], colors::yellow};
  }

 protected:
  void Animate(double t) override {
    // a path that needs sharp bends near the base, where the limits bite
    handles_[0].pos = Lissajous(kRoot + Vec3(0.0, 0.42, 0.0), Vec3(0.5, 0.28, 0.3), t, 0.8);
  }

  void Solve(double) override {
    skel_->set_target(0, handles_[0].pos);
    free_->set_target(0, handles_[0].pos);
    last_ = solver_->solve();
    free_last_ = free_solver_->solve();
  }

  bool ReportEffector(Vec3* e, double* res) const override {
    *e = skel_->tips().back();
    *res = skel_->effector_error(0);
    return true;
  }

 private:
  static constexpr Vec3 kRoot{0.0, 0.1, 0.0};

  std::unique_ptr<ik::Skeleton> make(bool limited) const {
    ik::SkeletonDef def =
        DefOf(ik::scenes::make_chain(bones_, ball_ ? ik::JointType::Ball : ik::JointType::Hinge, limited));
    def.root_position = kRoot;
    def.root_rotation = glm::angleAxis(0.5 * kPi, Vec3(0, 0, 1));
    auto s = std::make_unique<ik::Skeleton>(def);
    ik::scenes::bent_pose(*s);
    s->add_effector(s->bone_count() - 1, handles_[0].pos);
    return s;
  }

  void build() {
    solver_.reset();
    free_solver_.reset();
    skel_ = make(limited_);
    free_ = make(false);
    solver_ = std::make_unique<ik::Solver>(*skel_, method_);
    free_solver_ = std::make_unique<ik::Solver>(*free_, method_);
  }

  // how far joint i of `s` is outside the limits of the shared limited chain (rad)
  double excess(const ik::Skeleton& s, int i) const {
    if (s.joint_types()[i] == ik::JointType::Hinge)
      return std::max(0.0, std::abs(s.hinge_angles()[i]) - ik::scenes::kHingeLimit);
    if (s.joint_types()[i] == ik::JointType::Ball) {
      const Vec3 d = s.joint_rotations()[i] * Vec3(1, 0, 0);
      const double swing = std::acos(std::clamp(d.x, -1.0, 1.0));
      return std::max(0.0, swing - ik::scenes::kSwingLimit);
    }
    return 0;
  }

  static inline bool g_ball = false;
  static inline ik::Method g_method = ik::Method::Fabrik;

  int bones_ = 6;
  bool ball_ = false, limited_ = true, compare_ = true;
  ik::Method method_ = ik::Method::Fabrik;
  std::unique_ptr<ik::Skeleton> skel_, free_;
  std::unique_ptr<ik::Solver> solver_, free_solver_;
  ik::SolveResult last_, free_last_;
};

static int reg = RegisterSample("Inverse kinematics", "Joint limits", IkLimits::Create);

}  // namespace
}  // namespace pba::app
