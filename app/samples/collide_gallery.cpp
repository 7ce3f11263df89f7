// "Collision/Shape gallery": drag one shape against another and see the narrow phase's
// manifold: contact points on both surfaces, the normal, each point's depth and feature id;
// box and hull pairs switch between separating axes and GJK/EPA.
//
// Options: a=sphere|capsule|box|hull, b=..., method=sat|gjk, margin=METRES, spin=0|1.
#include <cmath>
#include <cstdio>

#include <imgui.h>

#include "camera.h"
#include "collide_common.h"
#include "sample.h"

namespace pba::app {
namespace {

class CollideGallery final : public Sample {
 public:
  explicit CollideGallery(SampleContext& ctx) : Sample(ctx), hull_(demo_hull()) {
    shape_a_ = shape_index(ctx.option("a", "box"), "a");
    shape_b_ = shape_index(ctx.option("b", "box"), "b");
    const std::string m = ctx.option("method", "sat");
    if (m != "sat" && m != "gjk") throw Error("--option method=" + m + ": expected sat or gjk");
    settings_.method = m == "sat" ? ConvexMethod::Sat : ConvexMethod::GjkEpa;
    const std::string mg = ctx.option("margin", "0.05");
    char* end = nullptr;
    settings_.speculative_margin = std::strtod(mg.c_str(), &end);
    if (end == mg.c_str() || *end || !(settings_.speculative_margin >= 0 && settings_.speculative_margin <= 0.5))
      throw Error("--option margin=" + mg + ": expected a number in [0, 0.5]");
    const std::string sp = ctx.option("spin", "1");
    if (sp != "0" && sp != "1") throw Error("--option spin=" + sp + ": expected 0 or 1");
    spin_ = sp == "1";
    ctx.camera->frame({0.1f, 1.4f, 0.0f}, 1.3f, 0.25f, 0.45f);
    ctx.renderer->style.grid_spacing = 0.1f;
    ctx.renderer->style.ground_extent = 6.0f;
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<CollideGallery>(ctx); }
  bool OwnsTime() const override { return true; }

  void Update(double frame_dt) override {
    Settings& s = ctx_.settings;
    const bool step_once = s.paused && s.single_step;
    s.single_step = false;
    if ((!s.paused || step_once) && spin_) time_ += step_once ? 1.0 / 60 : std::clamp(frame_dt, 0.0, 0.1);
    // A stands still; B rests on it, turning about the vertical and rocking a little, and
    // until dragged drifts over A's top
    pose_a_ = {Vec3(0, 1, 0), glm::angleAxis(0.05, Vec3(1, 0, 0))};
    const Quat qb = glm::normalize(glm::angleAxis(0.5 * time_, Vec3(0, 1, 0)) *
                                   glm::angleAxis(0.04 * std::sin(0.9 * time_), glm::normalize(Vec3(1, 0, 1))));
    a_ = demo_shape(shape_a_, hull_);
    b_ = demo_shape(shape_b_, hull_);
    if (!dragged_) {
      // B's lowest point 15 +- 20 mm below A's highest (the supports along the vertical)
      const Vec3 up(0, 1, 0);
      const double top = glm::dot(ConvexProxy::of(a_, pose_a_).support(up), up) + core_radius_of(a_);
      const ConvexProxy b0 = ConvexProxy::of(b_, {Vec3(0), qb});
      const double below = -glm::dot(b0.support(-up), up) + core_radius_of(b_);
      pos_b_ = Vec3(0.2 + 0.15 * std::sin(0.7 * time_), top + below - 0.015 + 0.02 * std::sin(1.1 * time_), 0.05);
    }
    pose_b_ = {pos_b_, qb};
    manifold_ = collide(a_, pose_a_, b_, pose_b_, settings_, &cache_);
  }

  void Draw(Renderer& r, double) override {
    const bool touching = manifold_.count > 0;
    // the manifold's normal also beside the pair, where no shape hides it
    if (touching) {
      const Vec3 g(-0.75, 1.9, 0);
      r.arrow(g, g + 0.3 * manifold_.normal, 0.06, colors::green);
      r.text(g + Vec3(0, -0.08, 0), "normal", colors::white, 0.8f, 0.5f);
    }
    draw_shape(r, a_, pose_a_, Color::hex(0x6e7f99, 0.45f));
    draw_shape(r, b_, pose_b_, touching ? Color::hex(0xf76b15, 0.45f) : Color::hex(0xc2a06b, 0.45f));
    r.shadow(pose_a_.position, 0.5);
    r.shadow(pose_b_.position, 0.5);
    // every contact: the points on A and B, the normal at their midpoint, the depth
    for (int i = 0; i < manifold_.count; ++i) {
      const ContactPoint& c = manifold_.points[std::size_t(i)];
      const Color pc = c.depth >= 0 ? colors::yellow : colors::cyan;
      r.point(c.point_a, 11.0f, pc);
      r.point(c.point_b, 8.0f, colors::pink);
      r.line(c.point_a, c.point_b, colors::white);
      r.arrow(c.position(), c.position() + 0.3 * manifold_.normal, 0.06, colors::green);
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f mm", 1e3 * c.depth);
      r.text(c.position() + 0.06 * manifold_.normal, buf, colors::white, 0.8f, 0.0f);
    }
  }

  void DrawUI() override {
    ImGui::TextWrapped("Drag the orange shape (left mouse). Yellow: points on A (penetrating), cyan: "
                       "speculative (within the margin), pink: points on B; green: the normal from A to B.");
    ImGui::Combo("shape A", &shape_a_, kShapeNames.data(), int(kShapeNames.size()));
    ImGui::Combo("shape B", &shape_b_, kShapeNames.data(), int(kShapeNames.size()));
    int m = settings_.method == ConvexMethod::Sat ? 0 : 1;
    if (ImGui::RadioButton("SAT", m == 0)) m = 0;
    ImGui::SameLine();
    if (ImGui::RadioButton("GJK/EPA", m == 1)) m = 1;
    settings_.method = m == 0 ? ConvexMethod::Sat : ConvexMethod::GjkEpa;
    ImGui::TextDisabled("(the method applies to box and hull pairs)");
    float margin = float(settings_.speculative_margin);
    if (ImGui::SliderFloat("margin (m)", &margin, 0.0f, 0.2f)) settings_.speculative_margin = margin;
    ImGui::Checkbox("spin", &spin_);
    if (dragged_ && ImGui::SmallButton("release to the script")) dragged_ = false;
    ImGui::Separator();
    ImGui::Text("%d point%s, normal (%.3f, %.3f, %.3f)", manifold_.count, manifold_.count == 1 ? "" : "s",
                manifold_.normal.x, manifold_.normal.y, manifold_.normal.z);
    for (int i = 0; i < manifold_.count; ++i)
      ImGui::Text("  depth %+8.2f mm   id %08x", 1e3 * manifold_.points[std::size_t(i)].depth,
                  manifold_.points[std::size_t(i)].id);
  }

  // left press near B grabs it; it then follows the cursor on a plane facing the camera
  void Mouse(int button, bool down, const Vec3& o, const Vec3& d) override {
    if (button != 0) return;
    if (!down) {
      grabbing_ = false;
      return;
    }
    const double t = glm::dot(pos_b_ - o, d);
    if (t <= 0 || glm::length(pos_b_ - o - t * d) > 0.6) return;
    grabbing_ = dragged_ = true;
    plane_n_ = forward();
    grab_offset_ = pos_b_ - on_plane(o, d);
  }
  void MouseMove(const Vec3& o, const Vec3& d) override {
    if (!grabbing_) return;
    if (!ImGui::GetIO().MouseDown[0]) {
      grabbing_ = false;
      return;
    }
    if (std::abs(glm::dot(d, plane_n_)) > 1e-6) pos_b_ = on_plane(o, d) + grab_offset_;
  }
  bool MouseCaptured() const override { return grabbing_; }

  // the normals are green while the shapes touch (the default placement keeps them touching)
  std::vector<Color> ExpectedColors() const override {
    return manifold_.count > 0 ? std::vector<Color>{colors::green} : std::vector<Color>{};
  }

 private:
  static double core_radius_of(const ColliderShape& s) {
    return s.type == ShapeType::Sphere || s.type == ShapeType::Capsule ? s.radius : 0.0;
  }
  Vec3 forward() const {
    const Camera& c = *ctx_.camera;
    return glm::normalize(Vec3(c.target) - Vec3(c.eye()));
  }
  Vec3 on_plane(const Vec3& o, const Vec3& d) const {
    const double t = glm::dot(pos_b_ - o, plane_n_) / glm::dot(d, plane_n_);
    return o + t * d;
  }

  std::shared_ptr<const ConvexHull> hull_;
  int shape_a_ = 2, shape_b_ = 3;
  NarrowPhaseSettings settings_{};
  NarrowPhaseCache cache_{};
  ColliderShape a_{}, b_{};
  Pose pose_a_{}, pose_b_{};
  Vec3 pos_b_{0.2, 1.685, 0.05};
  Manifold manifold_{};
  double time_ = 0;
  bool spin_ = true, dragged_ = false, grabbing_ = false;
  Vec3 plane_n_{0, 0, 1}, grab_offset_{0, 0, 0};
};

static int reg = RegisterSample("Collision", "Shape gallery", CollideGallery::Create);

}  // namespace
}  // namespace pba::app
