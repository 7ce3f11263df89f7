// "Inverse kinematics/Two-bone limb": an arm (ball shoulder, hinge elbow) solved in closed
// form with the law of cosines; the elbow bends toward the purple pole target. Both the
// hand target and the pole are draggable.
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

class IkLimb final : public IkSample {
 public:
  explicit IkLimb(SampleContext& ctx) : IkSample(ctx) {
    // the shared limb (0.3 m upper arm, 0.25 m forearm), its shoulder on a torso
    ik::SkeletonDef def = DefOf(ik::scenes::make_limb());
    def.root_position = kShoulder;
    skel_ = std::make_unique<ik::Skeleton>(def);
    ik::EffectorDef e;
    e.bone = 1;
    e.target = kShoulder + Vec3(0.3, -0.1, 0.2);
    e.pole = kShoulder + Vec3(0.2, -0.4, -0.1);
    skel_->add_effector(e);
    handles_.push_back({e.target, kTargetColors[0], "hand target", 0.03});
    handles_.push_back({*e.pole, kPoleColor, "pole", 0.025});
    solver_ = std::make_unique<ik::Solver>(*skel_, ik::Method::TwoBone);
    ctx.camera->frame({0.1f, 1.02f, 0.0f}, 0.5f, 0.6f, 0.2f);
    Animate(0);
    Solve(0);
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<IkLimb>(ctx); }

  void Draw(Renderer& r, double) override {
    // a torso and head for scale
    r.box(kShoulder + Vec3(-0.16, -0.22, 0), Vec3(0.14, 0.26, 0.09), Quat(1, 0, 0, 0), kBaseColor);
    r.sphere(kShoulder + Vec3(-0.16, 0.16, 0), 0.1, kBaseColor);
    r.box(Vec3(-0.16, 0.5 * (kShoulder.y - 0.48), 0), Vec3(0.05, 0.5 * (kShoulder.y - 0.48), 0.05), Quat(1, 0, 0, 0),
          kBaseColor);
    SkeletonStyle st;
    st.bone_radius = 0.028;
    DrawSkeleton(r, *skel_, st);
    // the elbow leans toward the pole
    const Vec3 elbow = skel_->starts()[1];
    r.line(elbow, handles_[1].pos, Color{kPoleColor.r, kPoleColor.g, kPoleColor.b, 0.8f}, 1.5f);
    // the limb's plane: shoulder, elbow, hand
    const Vec3 sh = skel_->starts()[0], hand = skel_->tips()[1];
    r.line(sh, hand, Color{1, 1, 1, 0.35f}, 1.2f);
    DrawResiduals(r, *skel_);
    DrawHandles(r);
    if (ctx_.settings.show_labels) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "elbow %.0f deg%s", skel_->hinge_angles()[1] * 180 / kPi,
                    glm::length(handles_[0].pos - sh) > skel_->total_length() ? " (out of reach)" : "");
      r.text(elbow + Vec3(0, -0.06, 0), buf, kHingeColor, 0.9f, 0.5f);
    }
    DrawStatus(DragHelp("the red hand target or the purple pole"));
  }

  void DrawUI() override {
    ImGui::TextWrapped("Two-bone IK: the law of cosines gives the elbow angle from the shoulder-to-target "
                       "distance; the shoulder then turns the limb to the target and rolls it so the elbow "
                       "points toward the pole. One step, no iteration.");
    ImGui::SetNextItemWidth(-90);
    if (MethodCombo("solver", &method_, *skel_)) solver_->set_method(method_);
    if (method_ != ik::Method::TwoBone) ImGui::TextDisabled("(iterative solvers ignore the pole)");
    AnimationUI();
    ImGui::Separator();
    const Vec3 sh = skel_->starts()[0];
    ImGui::Text("shoulder to target  %.3f m (reach %.3f m)", glm::length(handles_[0].pos - sh), skel_->total_length());
    ImGui::Text("elbow angle         %.1f deg", skel_->hinge_angles()[1] * 180 / kPi);
    ImGui::Text("residual            %.3g mm", last_.residual * 1000);
    ImGui::Text("time/solve          %.2f us", last_us_);
    ImGui::TextDisabled("elbow range [0, 160] deg: a target too close bends it fully");
  }

  FiniteCheck CheckFinite() const override {
    return check_finite<Vec3>(skel_->tips(), skel_->starts(), "limb bone", time_, 0);
  }
  std::vector<Color> ExpectedColors() const override { return {kTargetColors[0], kPoleColor, kHingeColor}; }

 protected:
  void Animate(double t) override {
    handles_[0].pos = Lissajous(kShoulder + Vec3(0.26, -0.12, 0.13), Vec3(0.13, 0.15, 0.11), t);
    // the pole swings slowly from behind to in front of the arm
    handles_[1].pos = kShoulder + Vec3(0.24, -0.34, 0.32 * std::sin(0.3 * t));
  }

  void Solve(double) override {
    skel_->set_target(0, handles_[0].pos);
    skel_->set_pole(0, handles_[1].pos);
    const pba::Stopwatch sw;
    last_ = solver_->solve();
    last_us_ = 1e6 * sw.seconds();
  }

  bool ReportEffector(Vec3* e, double* res) const override {
    *e = skel_->tips()[1];
    *res = skel_->effector_error(0);
    return true;
  }

 private:
  static constexpr Vec3 kShoulder{0.0, 1.15, 0.0};
  std::unique_ptr<ik::Skeleton> skel_;
  std::unique_ptr<ik::Solver> solver_;
  ik::Method method_ = ik::Method::TwoBone;
  ik::SolveResult last_;
  double last_us_ = 0;
};

static int reg = RegisterSample("Inverse kinematics", "Two-bone limb", IkLimb::Create);

}  // namespace
}  // namespace pba::app
