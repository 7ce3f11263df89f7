// "Inverse kinematics/1-DOF analytic" and "Inverse kinematics/3-DOF arm" (workbook 2.3,
// exercises ik_1dof and ik_3dof). One hinge aims its bone at the target with a dot product
// (cos) and a cross product (sin); one ball joint turns by the shortest arc, about a x b.
// The 3-DOF arm chains several ball joints, each aimed that way in turn by CCD.
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

enum class Kind { OneDof, ThreeDof };

constexpr Color kArc = Color::hex(0xffc53d);
constexpr Color kAxis = Color::hex(0x46a758);

class IkAnalytic final : public IkSample {
 public:
  IkAnalytic(SampleContext& ctx, Kind kind) : IkSample(ctx), kind_(kind) {
    if (kind == Kind::ThreeDof) {
      const std::string nl = ctx.option("links", std::to_string(g_links));
      char* end = nullptr;
      const long n = std::strtol(nl.c_str(), &end, 10);
      if (end != nl.c_str() + nl.size() || n < 1 || n > 8) throw Error("--option links=" + nl + ": expected 1 to 8");
      links_ = static_cast<int>(n);
    }
    handles_.push_back({kRoot + Vec3(0.35, 0.1, 0.1), kTargetColors[0], "target", 0.03});
    if (kind == Kind::OneDof) ctx.camera->frame({0.0f, 0.72f, 0.0f}, 0.5f, 0.3f, 0.15f);
    else ctx.camera->frame({0.0f, 0.78f, 0.0f}, 0.55f, 0.5f, 0.25f);
    build();
    Animate(0);
  }
  static std::unique_ptr<Sample> CreateOne(SampleContext& ctx) { return std::make_unique<IkAnalytic>(ctx, Kind::OneDof); }
  static std::unique_ptr<Sample> CreateThree(SampleContext& ctx) {
    return std::make_unique<IkAnalytic>(ctx, Kind::ThreeDof);
  }

  void Draw(Renderer& r, double) override {
    // a post behind the joint, clear of the swinging bone, with an axle
    if (kind_ == Kind::OneDof) {
      DrawPedestal(r, kRoot - Vec3(0, 0, 0.09), 0.035);
      r.capsule(kRoot - Vec3(0, 0, 0.09), kRoot, 0.012, kBaseColor);
    } else {
      DrawPedestal(r, kRoot, 0.05);
    }
    SkeletonStyle st;
    st.bone_radius = 0.022;
    DrawSkeleton(r, *skel_, st);
    if (kind_ == Kind::OneDof) draw_one(r);
    else if (links_ == 1) draw_ball(r);
    DrawResiduals(r, *skel_);
    DrawHandles(r);
    DrawStatus(DragHelp("the red target"));
  }

  void DrawUI() override {
    if (kind_ == Kind::OneDof) {
      ImGui::TextWrapped("One hinge about z aims its bone at the target. With a the rest direction of the bone "
                         "and b the direction to the target projected on the hinge plane (both unit):");
      ImGui::BulletText("cos(theta) = a . b");
      ImGui::BulletText("sin(theta) = (a x b) . z");
      ImGui::BulletText("theta = atan2(sin, cos), clamped to the limits");
      ImGui::TextWrapped("Move the target out of the plane (W/S): the bone follows its shadow on the plane.");
      ImGui::Separator();
      ImGui::Text("cos = %+.3f   sin = %+.3f   theta = %+.1f deg", cos_, sin_, theta_ * 180 / kPi);
      ImGui::Text("hinge angle %.1f deg", skel_->hinge_angles()[0] * 180 / kPi);
    } else {
      ImGui::TextWrapped("Ball joints have 3 DOF. One ball joint aims at the target by the shortest arc: it turns "
                         "about a x b by acos(a . b). With several links, CCD does that for each joint in turn, "
                         "from the tip to the root, until the tip reaches the target.");
      ImGui::SetNextItemWidth(-90);
      if (ImGui::SliderInt("links", &links_, 1, 8)) {
        g_links = links_;
        build();
      }
      ImGui::SetNextItemWidth(-90);
      if (MethodCombo("solver", &method_, *skel_)) solver_->set_method(method_);
    }
    AnimationUI();
    ImGui::Separator();
    ImGui::Text("iterations %d, residual %.3g mm, %.2f us", last_.iterations, last_.residual * 1000, last_us_);
    if (last_.residual > 1e-3)
      ImGui::TextDisabled(kind_ == Kind::OneDof ? "(the target is off the plane or out of reach)"
                                                : "(the target is out of reach)");
  }

  FiniteCheck CheckFinite() const override {
    return check_finite<Vec3>(skel_->tips(), skel_->starts(), "arm bone", time_, 0);
  }
  std::vector<Color> ExpectedColors() const override {
    return {kTargetColors[0], kind_ == Kind::OneDof ? kHingeColor : kBallColor};
  }

 protected:
  void Animate(double t) override {
    const double w = 0.5;
    if (kind_ == Kind::OneDof)
      handles_[0].pos = kRoot + Vec3(0.4 * std::cos(w * t), 0.4 * std::sin(w * t), 0.05 * std::sin(0.7 * w * t));
    else
      handles_[0].pos = Lissajous(kRoot + Vec3(0.0, 0.25, 0.0), Vec3(0.35, 0.22, 0.3), t);
  }

  void Solve(double) override {
    skel_->set_target(0, handles_[0].pos);
    if (kind_ == Kind::OneDof) {
      // the construction the solver uses, for the panel and the drawing
      const Vec3 a(1, 0, 0), z(0, 0, 1);
      Vec3 b = handles_[0].pos - kRoot;
      b.z = 0;
      if (glm::length(b) > 1e-9) {
        b = glm::normalize(b);
        cos_ = glm::dot(a, b);
        sin_ = glm::dot(glm::cross(a, b), z);
        theta_ = std::atan2(sin_, cos_);
      }
    }
    const pba::Stopwatch sw;
    last_ = solver_->solve();
    last_us_ = 1e6 * sw.seconds();
  }

  bool ReportEffector(Vec3* e, double* res) const override {
    *e = skel_->tips().back();
    *res = skel_->effector_error(0);
    return true;
  }

 private:
  static constexpr Vec3 kRoot{0.0, 0.62, 0.0};

  void build() {
    solver_.reset();
    ik::SkeletonDef def;
    def.root_position = kRoot;
    if (kind_ == Kind::OneDof) {
      // one hinge about z, the bone along +X at zero
      ik::BoneDef b;
      b.length = 0.4;
      b.joint = ik::JointType::Hinge;
      b.axis = Vec3(0, 0, 1);
      def.bones.push_back(b);
      method_ = ik::Method::Analytic1Dof;
    } else {
      // links of ball joints, 0.6 m in all, standing up
      def.root_rotation = glm::angleAxis(0.5 * kPi, Vec3(0, 0, 1));
      for (int i = 0; i < links_; ++i) {
        ik::BoneDef b;
        b.parent = i - 1;
        b.length = 0.6 / links_;
        b.joint = ik::JointType::Ball;
        def.bones.push_back(b);
      }
      method_ = links_ == 1 ? ik::Method::Analytic3Dof : ik::Method::Ccd;
    }
    skel_ = std::make_unique<ik::Skeleton>(def);
    if (kind_ == Kind::ThreeDof && links_ > 1) ik::scenes::bent_pose(*skel_);
    skel_->add_effector(skel_->bone_count() - 1, handles_[0].pos);
    solver_ = std::make_unique<ik::Solver>(*skel_, method_);
  }

  // an arc of radius `rad` around `c` from unit `from` turning about unit `axis` by `angle`
  static void arc(Renderer& r, const Vec3& c, const Vec3& from, const Vec3& axis, double angle, double rad, Color col) {
    std::vector<Vec3> pts;
    for (int k = 0; k <= 32; ++k) pts.push_back(c + rad * (glm::angleAxis(angle * k / 32, axis) * from));
    r.polyline(pts, col, 2.5f);
  }

  void draw_one(Renderer& r) {
    const Vec3 a(1, 0, 0), z(0, 0, 1);
    // the rest direction a, the projected target direction b and the angle between them
    r.line(kRoot, kRoot + 0.45 * a, Color{1, 1, 1, 0.45f}, 1.5f);
    Vec3 proj = handles_[0].pos;
    proj.z = kRoot.z;
    r.line(handles_[0].pos, proj, Color{1, 1, 1, 0.35f}, 1.2f);
    r.sphere(proj, 0.008, Color{1, 1, 1, 0.6f});
    arc(r, kRoot, a, z, theta_, 0.12, kArc);
    r.arrow(kRoot, kRoot + 0.12 * z, 0.03, kAxis);
    if (ctx_.settings.show_labels) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "theta %.0f deg", theta_ * 180 / kPi);
      r.text(kRoot + 0.17 * (glm::angleAxis(0.5 * theta_, z) * a), buf, kArc, 0.9f, 0.5f);
      r.text(kRoot + 0.45 * a + Vec3(0.02, 0, 0), "a (rest)", Color{1, 1, 1, 0.7f}, 0.85f, 0.0f);
      r.text(kRoot + 0.14 * z + Vec3(0, 0.02, 0), "z (hinge axis)", kAxis, 0.85f, 0.5f);
      std::snprintf(buf, sizeof buf, "a.b = %+.2f   (a x b).z = %+.2f", cos_, sin_);
      r.text(kRoot + Vec3(0, -0.12, 0.05), buf, colors::white, 1.0f, 0.5f);
    }
  }

  void draw_ball(Renderer& r) {
    // the shortest arc from the rest direction a to the bone's direction b: about a x b
    const Vec3 rest = skel_->root_rotation() * Vec3(1, 0, 0);
    const Vec3 now = glm::normalize(skel_->tips()[0] - kRoot);
    r.line(kRoot, kRoot + 0.3 * rest, Color{1, 1, 1, 0.45f}, 1.5f);
    const Vec3 ax = glm::cross(rest, now);
    if (glm::length(ax) < 1e-6) return;
    const Vec3 n = glm::normalize(ax);
    r.arrow(kRoot, kRoot + 0.18 * n, 0.035, kAxis);
    const double angle = std::acos(std::clamp(glm::dot(rest, now), -1.0, 1.0));
    arc(r, kRoot, rest, n, angle, 0.14, kArc);
    if (ctx_.settings.show_labels) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "acos(a.b) = %.0f deg", angle * 180 / kPi);
      r.text(kRoot + 0.2 * n + Vec3(0, 0.02, 0), "a x b", kAxis, 0.9f, 0.5f);
      r.text(kRoot + 0.3 * rest + Vec3(0.02, 0, 0), buf, kArc, 0.9f, 0.0f);
    }
  }

  static inline int g_links = 3;
  Kind kind_;
  int links_ = 3;
  ik::Method method_ = ik::Method::Ccd;
  std::unique_ptr<ik::Skeleton> skel_;
  std::unique_ptr<ik::Solver> solver_;
  ik::SolveResult last_;
  double last_us_ = 0;
  double cos_ = 1, sin_ = 0, theta_ = 0;
};

static int reg_one = RegisterSample("Inverse kinematics", "1-DOF analytic", IkAnalytic::CreateOne);
static int reg_three = RegisterSample("Inverse kinematics", "3-DOF arm", IkAnalytic::CreateThree);

}  // namespace
}  // namespace pba::app
