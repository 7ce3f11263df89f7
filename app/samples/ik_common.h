// Shared pieces of the "Inverse kinematics" samples: draggable targets (picked with the
// mouse ray, dragged on a camera-facing plane through the target, W/S for depth), a
// scripted path when no one drags, skeleton drawing as rigid bodies, a status line, and
// the --option report=FILE hook used by the xdotool test.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <GLFW/glfw3.h>
#include <imgui.h>

#include "camera.h"
#include "pba/ik.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app::ik_demo {


// one colour per role, the same in every IK sample
inline constexpr Color kBoneColor = Color::hex(0xa7b0c0);
inline constexpr Color kHingeColor = Color::hex(0xf76b15);   // orange joints: hinges
inline constexpr Color kBallColor = Color::hex(0x00a2c7);    // cyan joints: ball joints
inline constexpr Color kFixedColor = Color::hex(0x6b7280);   // grey joints: fixed
inline constexpr Color kResidualColor = Color::hex(0xff8dcc); // effector-to-target line
inline constexpr Color kBaseColor = Color::hex(0x4b5160);    // pedestals
// targets: the first is red, then yellow, green, blue; the pole is purple
inline constexpr Color kTargetColors[] = {Color::hex(0xe5484d), Color::hex(0xffc53d), Color::hex(0x46a758),
                                          Color::hex(0x3e63dd)};
inline constexpr Color kPoleColor = Color::hex(0x8e4ec6);

/// A point the user can drag: an IK target or a pole (not a pba::Handle, the library's
/// generation-checked id).
struct DragTarget {
  Vec3 pos{0};
  Color color = kTargetColors[0];
  std::string name;      // shown next to it
  double radius = 0.04;  // drawn and picked size (m)
};

/// How a skeleton is drawn.
struct SkeletonStyle {
  double bone_radius = 0.0;  // capsule radius (m); 0 picks 8% of each bone, at least min_radius
  double min_radius = 0.006;
  Color bone = kBoneColor;
  bool joints = true;        // spheres at joints
  float alpha = 1.0f;        // < 1 for a ghost
};

/// Draws bones as capsules and joints as spheres coloured by type (hinge orange, ball cyan,
/// fixed grey). Very long chains skip the joint spheres (they would hide the bones).
inline void DrawSkeleton(Renderer& r, const ik::Skeleton& s, const SkeletonStyle& st = {}) {
  const auto starts = s.starts(), tips = s.tips();
  const auto types = s.joint_types();
  const int n = s.bone_count();
  const bool joints = st.joints && n <= 200;
  // a long chain is drawn as fewer capsules, each spanning a few bones (a software
  // rasteriser slows down with a thousand overlapping solids and shadows)
  bool chain = n > 150;
  for (int i = 1; chain && i < n; ++i) chain = s.parents()[i] == i - 1;
  if (chain) {
    const int group = (n + 119) / 120;
    Color c = st.bone;
    c.a = st.alpha;
    const double rad = st.bone_radius > 0 ? st.bone_radius : st.min_radius;
    for (int i = 0; i < n; i += group) r.capsule(starts[i], tips[std::min(i + group, n) - 1], rad, c);
    return;
  }
  for (int i = 0; i < n; ++i) {
    const double def_r = s.bone_def(i).radius;
    const double rad = st.bone_radius > 0 ? st.bone_radius
                                          : std::max(def_r > 0 ? def_r : 0.08 * s.lengths()[i], st.min_radius);
    Color c = st.bone;
    c.a = st.alpha;
    r.capsule(starts[i], tips[i], rad, c);
    if (!joints) continue;
    Color j = types[i] == ik::JointType::Hinge ? kHingeColor : types[i] == ik::JointType::Ball ? kBallColor : kFixedColor;
    j.a = st.alpha;
    r.sphere(starts[i], 1.35 * rad, j);
  }
}

/// The residual of every effector: a line from the bone tip to its target.
inline void DrawResiduals(Renderer& r, const ik::Skeleton& s) {
  for (int k = 0; k < s.effector_count(); ++k) {
    const ik::EffectorDef& e = s.effector(k);
    const Vec3 tip = s.tips()[e.bone];
    if (glm::length(tip - e.target) > 1e-4) r.line(tip, e.target, kResidualColor, 2.5f);
  }
}

/// A slow Lissajous curve around `center` with amplitudes `amp` (m) at time t (s).
inline Vec3 Lissajous(const Vec3& center, const Vec3& amp, double t, double speed = 1.0) {
  const double w = 0.55 * speed;
  return center + Vec3(amp.x * std::sin(w * t), amp.y * std::sin(1.7 * w * t + 0.6), amp.z * std::sin(0.8 * w * t + 1.3));
}

/// Base of the IK samples: owns the draggable handles, the scripted motion, the depth keys,
/// the status line and the report file. Subclasses set the handles, Animate() them along a
/// path, Solve() each frame and Draw() the scene.
class IkSample : public Sample {
 public:
  explicit IkSample(SampleContext& ctx) : Sample(ctx) {
    // --option animate=0 keeps the targets still until dragged; report=FILE writes the state
    const std::string a = ctx.option("animate", "1");
    if (a != "0" && a != "1") throw Error("--option animate=" + a + ": expected 0 or 1");
    animate_ = a == "1";
    report_path_ = ctx.option("report", "");
    ctx.renderer->style.grid_spacing = 0.1f;
    ctx.renderer->style.ground_extent = 6.0f;
  }
  bool OwnsTime() const override { return true; }

  // one frame: scripted targets, depth keys, then the sample's solve
  void Update(double frame_dt) override {
    Settings& s = ctx_.settings;
    const bool step_once = s.paused && s.single_step;
    s.single_step = false;
    const double dt = std::clamp(frame_dt, 0.0, 0.1);
    if (!s.paused || step_once) {
      time_ += step_once ? 1.0 / 60 : dt;
      if (animate_ && !user_took_over_) Animate(time_);
    }
    depth_keys(dt);
    if (!s.paused || step_once || grabbed_ >= 0 || moved_by_key_) Solve(dt);
    moved_by_key_ = false;
    ++frames_;
    if (frames_ % 5 == 0) write_report();
  }

  // left press: grab the handle under the cursor (nearest to the eye)
  void Mouse(int button, bool down, const Vec3& o, const Vec3& d) override {
    if (button != 0) return;
    if (!down) {
      grabbed_ = -1;
      return;
    }
    int best = -1;
    double best_t = 1e30;
    for (int i = 0; i < static_cast<int>(handles_.size()); ++i) {
      const Vec3 rel = handles_[i].pos - o;
      const double t = glm::dot(rel, d);
      if (t <= 0) continue;
      // generous pick radius: the sphere, at least ~14 px on screen
      const double px = pixel_size(handles_[i].pos);
      const double pick = std::max(1.6 * handles_[i].radius, 14.0 * px);
      if (glm::length(rel - t * d) <= pick && t < best_t) best = i, best_t = t;
    }
    if (best < 0) return;
    grabbed_ = active_ = best;
    user_took_over_ = true;
    ++grabs_;
    // the drag plane faces the camera and goes through the target
    plane_normal_ = camera_forward();
    plane_point_ = handles_[best].pos;
    const Vec3 hit = ray_plane(o, d);
    grab_offset_ = handles_[best].pos - hit;
  }

  void MouseMove(const Vec3& o, const Vec3& d) override {
    if (grabbed_ < 0) return;
    if (!ImGui::GetIO().MouseDown[0]) {  // the release happened over a panel
      grabbed_ = -1;
      return;
    }
    if (std::abs(glm::dot(d, plane_normal_)) < 1e-6) return;
    handles_[grabbed_].pos = ray_plane(o, d) + grab_offset_;
    HandleMoved(grabbed_);
  }

  bool MouseCaptured() const override { return grabbed_ >= 0; }

  // Tab picks the next handle for the depth keys
  void Keyboard(int key, int) override {
    if (key == GLFW_KEY_TAB && !handles_.empty()) active_ = (active_ + 1) % static_cast<int>(handles_.size());
  }

 protected:
  /// Moves the handles along their scripted paths (time t in seconds).
  virtual void Animate(double t) { (void)t; }
  /// Runs the solvers for this frame (dt seconds).
  virtual void Solve(double dt) { (void)dt; }
  /// Called when handle i moved by the mouse or keys.
  virtual void HandleMoved(int i) { (void)i; }
  /// Position and residual of the effector reported by --option report (the first one).
  virtual bool ReportEffector(Vec3* effector, double* residual) const {
    (void)effector, (void)residual;
    return false;
  }

  /// Draws every handle as a coloured sphere with its name; the active one has a ring.
  void DrawHandles(Renderer& r) {
    for (int i = 0; i < static_cast<int>(handles_.size()); ++i) {
      const DragTarget& h = handles_[i];
      const double grow = i == grabbed_ ? 1.25 : 1.0;
      r.sphere(h.pos, h.radius * grow, h.color);
      if (i == active_ && handles_.size() > 1) {
        // a ring facing the camera marks the handle W/S moves
        const Vec3 f = camera_forward();
        Vec3 u = glm::normalize(glm::cross(f, std::abs(f.y) < 0.9 ? Vec3(0, 1, 0) : Vec3(1, 0, 0)));
        const Vec3 v = glm::cross(f, u);
        std::vector<Vec3> ring;
        for (int k = 0; k <= 32; ++k) {
          const double a = 2 * kPi * k / 32;
          ring.push_back(h.pos + 1.7 * h.radius * (std::cos(a) * u + std::sin(a) * v));
        }
        r.polyline(ring, Color{1, 1, 1, 0.8f}, 1.5f);
      }
      if (ctx_.settings.show_labels && !h.name.empty())
        r.text(h.pos + Vec3(0, 2.2 * h.radius, 0), h.name, h.color, 0.9f, 0.5f);
    }
  }

  /// A line of help at the bottom of the view (part of the labels layer).
  void DrawStatus(const std::string& text) {
    if (!ctx_.settings.show_labels) return;
    ImDrawList* dl = ImGui::GetBackgroundDrawList();
    const ImVec2 size = ImGui::GetIO().DisplaySize;
    const float cx = 0.5f * (1.0f + ctx_.camera->shift_x) * size.x;
    const ImVec2 ts = ImGui::CalcTextSize(text.c_str());
    const ImVec2 p(cx - 0.5f * ts.x, size.y - ts.y - 14);
    dl->AddRectFilled(ImVec2(p.x - 8, p.y - 4), ImVec2(p.x + ts.x + 8, p.y + ts.y + 4), IM_COL32(20, 22, 26, 190), 4);
    dl->AddText(p, IM_COL32(235, 237, 240, 255), text.c_str());
  }

  /// The usual status text for dragging handles (two lines).
  std::string DragHelp(const char* what) const {
    std::string s = std::string("Drag ") + what + " with the left mouse button.\nW/S moves ";
    s += handles_.size() > 1 ? "the ringed one in depth, Tab picks which." : "it in depth.";
    return s;
  }

  /// Common panel rows: animation toggle and a reset of the user's drags.
  void AnimationUI() {
    if (ImGui::Checkbox("animate targets", &animate_) && animate_) user_took_over_ = false;
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("targets follow a slow scripted path until you grab one");
    if (user_took_over_ && animate_) {
      ImGui::SameLine();
      if (ImGui::SmallButton("resume path")) user_took_over_ = false;
    }
  }

  Vec3 camera_forward() const {
    const Camera& c = *ctx_.camera;
    return glm::normalize(Vec3(c.target) - Vec3(c.eye()));
  }

  // metres per pixel at point p (for pick radii)
  double pixel_size(const Vec3& p) const {
    const Camera& c = *ctx_.camera;
    const double depth = std::max(glm::dot(p - Vec3(c.eye()), camera_forward()), 1e-3);
    const double h = std::max(ImGui::GetIO().DisplaySize.y, 1.0f);
    return 2.0 * depth * std::tan(0.5 * c.fov_y) / h;
  }

  std::vector<DragTarget> handles_;
  int grabbed_ = -1;              // handle held by the mouse, -1 for none
  int active_ = 0;                // handle moved by W/S
  bool animate_ = true;           // scripted motion when no one drags
  bool user_took_over_ = false;   // a drag or key moved a handle: the script stops
  double time_ = 0;               // scripted time (s), stops while paused
  double depth_speed_ = 0.5;      // W/S speed (m/s)

 private:
  Vec3 ray_plane(const Vec3& o, const Vec3& d) const {
    const double den = glm::dot(d, plane_normal_);
    const double t = std::abs(den) < 1e-9 ? 0.0 : glm::dot(plane_point_ - o, plane_normal_) / den;
    return o + t * d;
  }

  // W and S (held) push the active handle away from and toward the camera
  void depth_keys(double dt) {
    if (ctx_.virtual_time || handles_.empty() || ImGui::GetIO().WantCaptureKeyboard) return;
    const double dir = (ImGui::IsKeyDown(GLFW_KEY_W) ? 1.0 : 0.0) - (ImGui::IsKeyDown(GLFW_KEY_S) ? 1.0 : 0.0);
    if (dir == 0) return;
    const int i = grabbed_ >= 0 ? grabbed_ : std::clamp(active_, 0, static_cast<int>(handles_.size()) - 1);
    handles_[i].pos += dir * depth_speed_ * std::max(dt, 1.0 / 240) * camera_forward();
    if (grabbed_ >= 0) plane_point_ = handles_[i].pos;
    user_took_over_ = true;
    moved_by_key_ = true;
    HandleMoved(i);
  }

  // the test hook: frame, grabs, handle 0 (world and pixels), effector, residual
  void write_report() {
    if (report_path_.empty() || handles_.empty()) return;
    Vec3 eff{0};
    double res = -1;
    ReportEffector(&eff, &res);
    const Vec3& t = handles_[0].pos;
    glm::vec2 px(-1, -1);
    if (!ctx_.renderer->project(t, &px)) px = glm::vec2(-1, -1);
    const std::string tmp = report_path_ + ".tmp";
    FILE* f = std::fopen(tmp.c_str(), "w");
    if (!f) return;
    std::fprintf(f, "frame %lld grabs %d target %.6f %.6f %.6f pixel %.1f %.1f effector %.6f %.6f %.6f residual %.6f\n",
                 frames_, grabs_, t.x, t.y, t.z, px.x, px.y, eff.x, eff.y, eff.z, res);
    std::fclose(f);
    std::rename(tmp.c_str(), report_path_.c_str());
  }

  Vec3 plane_normal_{0, 0, -1}, plane_point_{0}, grab_offset_{0};
  bool moved_by_key_ = false;
  long long frames_ = 0;
  int grabs_ = 0;
  std::string report_path_;
};

/// The solver methods that can run `s` as set up, in the library's order.
inline std::vector<ik::Method> UsableMethods(const ik::Skeleton& s) {
  std::vector<ik::Method> out;
  for (ik::Method m : ik::kAllMethods)
    if (ik::supports(m, s)) out.push_back(m);
  return out;
}

/// Long names for the solver menu.
inline const char* MethodLabel(ik::Method m) {
  switch (m) {
    case ik::Method::Analytic1Dof: return "analytic 1-DOF";
    case ik::Method::Analytic3Dof: return "analytic 3-DOF";
    case ik::Method::TwoBone: return "two-bone (law of cosines)";
    case ik::Method::Ccd: return "CCD";
    case ik::Method::JacobianTranspose: return "Jacobian transpose";
    case ik::Method::PseudoInverse: return "pseudo-inverse";
    case ik::Method::Dls: return "damped least squares";
    case ik::Method::Sdls: return "SVD damped least squares";
    case ik::Method::Fabrik: return "FABRIK";
  }
  return "?";
}

/// A solver combo: every method of the library, those that cannot run `s` greyed out with
/// the reason as a tooltip. Returns true when `m` changed.
inline bool MethodCombo(const char* label, ik::Method* m, const ik::Skeleton& s) {
  bool changed = false;
  if (ImGui::BeginCombo(label, MethodLabel(*m))) {
    for (ik::Method k : ik::kAllMethods) {
      std::string why;
      const bool ok = ik::supports(k, s, &why);
      if (!ok) ImGui::BeginDisabled();
      if (ImGui::Selectable(MethodLabel(k), k == *m) && ok) *m = k, changed = true;
      if (!ok) ImGui::EndDisabled();
      if (!ok && ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled)) ImGui::SetTooltip("%s", why.c_str());
    }
    ImGui::EndCombo();
  }
  return changed;
}

/// A skeleton definition copied from a built skeleton (to move its root or change bones).
inline ik::SkeletonDef DefOf(const ik::Skeleton& s) {
  ik::SkeletonDef d;
  for (int i = 0; i < s.bone_count(); ++i) d.bones.push_back(s.bone_def(i));
  d.root_position = s.root_position();
  d.root_rotation = s.root_rotation();
  d.root_free = s.root_free();
  return d;
}

/// A pedestal under a root joint.
inline void DrawPedestal(Renderer& r, const Vec3& top, double half = 0.07) {
  if (top.y <= 0.001) return;
  r.box(Vec3(top.x, 0.5 * top.y, top.z), Vec3(half, 0.5 * top.y, half), Quat(1, 0, 0, 0), kBaseColor);
}

}  // namespace pba::app::ik_demo
