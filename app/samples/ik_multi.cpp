// "Inverse kinematics/Y tree" and "Inverse kinematics/Humanoid reach": several
// end-effectors on one skeleton, solved together. The Y tree has a target per branch; the
// humanoid reaches with both hands and both feet. Every target is draggable.
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

enum class Figure { YTree, Humanoid };

class IkMulti final : public IkSample {
 public:
  IkMulti(SampleContext& ctx, Figure fig) : IkSample(ctx), fig_(fig) {
    const std::string sv = ctx.option("solver", "");
    if (!sv.empty()) method_ = ik::parse_method(sv, "--option solver");
    if (fig == Figure::YTree) {
      // the shared Y, on a short post
      ik::SkeletonDef def = DefOf(ik::scenes::make_y_tree(false));
      def.root_position = Vec3(0, 0.1, 0);
      skel_ = std::make_unique<ik::Skeleton>(def);
      skel_->forward_kinematics();
      const int leaves[2] = {skel_->index_of(9), skel_->index_of(10)};
      const char* names[2] = {"branch A", "branch B"};
      for (int k = 0; k < 2; ++k) {
        home_.push_back(skel_->tips()[leaves[k]]);
        skel_->add_effector(leaves[k], home_.back());
        handles_.push_back({home_.back(), kTargetColors[k], names[k], 0.022});
      }
      ctx.camera->frame({0.0f, 0.45f, 0.0f}, 0.42f, 0.35f, 0.2f);
    } else {
      // the shared humanoid: hands and ankles pulled toward four targets
      // the spine stays upright unless asked (--option spine=1 or the check box)
      const std::string sp = ctx.option("spine", g_spine ? "1" : "0");
      if (sp != "0" && sp != "1") throw Error("--option spine=" + sp + ": expected 0 or 1");
      spine_ = sp == "1";
      ik::SkeletonDef def = DefOf(ik::scenes::make_humanoid(Vec3(0, 0.95, 0)));
      if (!spine_)
        for (ik::BoneDef& b : def.bones)
          if (b.name.rfind("spine", 0) == 0 || b.name == "neck") b.joint = ik::JointType::Fixed;
      skel_ = std::make_unique<ik::Skeleton>(def);
      if (sv.empty()) method_ = ik::Method::Dls;
      skel_->forward_kinematics();
      const char* bones[4] = {"hand_l", "hand_r", "shin_l", "shin_r"};
      const char* names[4] = {"left hand", "right hand", "left foot", "right foot"};
      for (int k = 0; k < 4; ++k) {
        const int b = skel_->find(bones[k]);
        if (b < 0) throw Error(std::string("humanoid has no bone ") + bones[k]);
        home_.push_back(skel_->tips()[b]);
        skel_->add_effector(b, home_.back());
        handles_.push_back({home_.back(), kTargetColors[k], names[k], 0.035});
      }
      // feet stand under the hips, a little bent
      for (int k = 0; k < 2; ++k) {
        const Vec3 hip = skel_->starts()[skel_->find(k == 0 ? "thigh_l" : "thigh_r")];
        home_[2 + k] = Vec3(hip.x * 1.2, 0.17, 0.02);
      }
      shoulder_[0] = skel_->starts()[skel_->find("upper_arm_l")];
      shoulder_[1] = skel_->starts()[skel_->find("upper_arm_r")];
      ctx.camera->frame({0.0f, 0.92f, 0.0f}, 0.92f, 0.45f, 0.16f);
    }
    ik::SolverSettings set;
    set.method = method_;
    solver_ = std::make_unique<ik::Solver>(*skel_, set);
    Animate(0);
  }
  static std::unique_ptr<Sample> CreateTree(SampleContext& ctx) { return std::make_unique<IkMulti>(ctx, Figure::YTree); }
  static std::unique_ptr<Sample> CreateHumanoid(SampleContext& ctx) {
    return std::make_unique<IkMulti>(ctx, Figure::Humanoid);
  }

  void Draw(Renderer& r, double) override {
    SkeletonStyle st;
    if (fig_ == Figure::YTree) {
      DrawPedestal(r, skel_->root_position(), 0.04);
      st.bone_radius = 0.014;
    } else {
      st.bone_radius = 0.022;
      // the head as a ball on the head bone
      const int head = skel_->find("head");
      r.sphere(skel_->tips()[head] - 0.4 * (skel_->tips()[head] - skel_->starts()[head]), 0.09, kBoneColor);
    }
    DrawSkeleton(r, *skel_, st);
    DrawResiduals(r, *skel_);
    DrawHandles(r);
    DrawStatus(DragHelp("any coloured target"));
  }

  void DrawUI() override {
    ImGui::TextWrapped(fig_ == Figure::YTree
                           ? "A Y-shaped tree with an end-effector on each branch: the trunk is shared, so the "
                             "solver must find one pose that serves both targets (FABRIK: sub-bases at the fork)."
                           : "A humanoid with fixed pelvis reaching with both hands and both feet at once: ball "
                             "shoulders, wrists and hips, hinge elbows and knees, all within their limits.");
    ImGui::SetNextItemWidth(-90);
    if (MethodCombo("solver", &method_, *skel_)) solver_->set_method(method_);
    if (fig_ == Figure::Humanoid && ImGui::Checkbox("bend the spine", &spine_)) {
      g_spine = spine_;
      ctx_.settings.restart = true;
    }
    AnimationUI();
    ImGui::Separator();
    ImGui::Text("%d bones, %d DOF, %d effectors", skel_->bone_count(), skel_->dof_count(), skel_->effector_count());
    ImGui::Text("iterations  %d%s", last_.iterations, last_.converged ? " (converged)" : "");
    ImGui::Text("time/solve  %.1f us", last_us_);
    for (int k = 0; k < skel_->effector_count(); ++k) {
      const Color c = handles_[k].color;
      ImGui::TextColored(ImVec4(c.r, c.g, c.b, 1), "%-12s", handles_[k].name.c_str());
      ImGui::SameLine(130);
      ImGui::Text("residual %.3g mm", skel_->effector_error(k) * 1000);
    }
    ImGui::TextDisabled("within joint limits: %s", skel_->within_limits(1e-6) ? "yes" : "NO");
  }

  FiniteCheck CheckFinite() const override {
    return check_finite<Vec3>(skel_->tips(), skel_->starts(), "bone", time_, 0);
  }
  std::vector<Color> ExpectedColors() const override {
    std::vector<Color> c;
    for (const DragTarget& h : handles_) c.push_back(h.color);
    return c;
  }

 protected:
  void Animate(double t) override {
    if (fig_ == Figure::YTree) {
      handles_[0].pos = Lissajous(home_[0] + Vec3(0.02, -0.05, 0.0), Vec3(0.1, 0.08, 0.16), t);
      handles_[1].pos = Lissajous(home_[1] + Vec3(-0.02, -0.05, 0.0), Vec3(0.1, 0.08, 0.16), t + 4.0);
      return;
    }
    // hands reach forward and around, feet step in place, out of phase
    for (int k = 0; k < 2; ++k) {
      const double side = shoulder_[k].x > 0 ? 1.0 : -1.0;
      handles_[k].pos = Lissajous(shoulder_[k] + Vec3(side * 0.1, -0.22, 0.3), Vec3(0.1, 0.14, 0.08), t + 3.0 * k);
    }
    for (int k = 2; k < 4; ++k) {
      const double ph = 0.9 * t + (k == 2 ? 0.0 : kPi);
      const double lift = std::max(0.0, std::sin(ph));
      handles_[k].pos = home_[k] + Vec3(0, 0.02 + 0.12 * lift, 0.06 + 0.08 * std::cos(ph));
    }
  }

  void Solve(double) override {
    for (int k = 0; k < skel_->effector_count(); ++k) skel_->set_target(k, handles_[k].pos);
    const pba::Stopwatch sw;
    last_ = solver_->solve();
    last_us_ = 1e6 * sw.seconds();
  }

  bool ReportEffector(Vec3* e, double* res) const override {
    *e = skel_->tips()[skel_->effector(0).bone];
    *res = skel_->effector_error(0);
    return true;
  }

 private:
  static inline bool g_spine = false;
  Figure fig_;
  bool spine_ = false;
  ik::Method method_ = ik::Method::Fabrik;
  std::unique_ptr<ik::Skeleton> skel_;
  std::unique_ptr<ik::Solver> solver_;
  std::vector<Vec3> home_;   // effector tips at the rest pose
  Vec3 shoulder_[2]{};
  ik::SolveResult last_;
  double last_us_ = 0;
};

static int reg_tree = RegisterSample("Inverse kinematics", "Y tree", IkMulti::CreateTree);
static int reg_humanoid = RegisterSample("Inverse kinematics", "Humanoid reach", IkMulti::CreateHumanoid);

}  // namespace
}  // namespace pba::app
