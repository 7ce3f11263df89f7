// "Collision/GJK stepper": GJK one iteration at a time, for students. Left: the two shapes.
// Right: their Minkowski difference A - B as a cloud of support points (the origin is
// inside exactly when the shapes overlap), the current simplex, its point closest to the
// origin v, and the newest support point w along -v. Step advances one iteration; when the
// run ends inside, EPA's penetration vector is drawn from the origin.
//
// Options: a=sphere|capsule|box|hull, b=..., auto=0|1 (step by itself every 0.25 s).
#include <cmath>
#include <cstdio>
#include <optional>

#include <imgui.h>

#include "camera.h"
#include "collide_common.h"
#include "sample.h"

namespace pba::app {
namespace {

// where the Minkowski difference is drawn: its origin sits here
const Vec3 kDiffOrigin(1.5, 1.2, 0);

class CollideGjk final : public Sample {
 public:
  explicit CollideGjk(SampleContext& ctx) : Sample(ctx), hull_(demo_hull()) {
    shape_a_ = shape_index(ctx.option("a", "box"), "a");
    shape_b_ = shape_index(ctx.option("b", "hull"), "b");
    const std::string au = ctx.option("auto", "1");
    if (au != "0" && au != "1") throw Error("--option auto=" + au + ": expected 0 or 1");
    auto_ = au == "1";
    ctx.camera->frame({0.0f, 1.1f, 0.0f}, 2.6f, 0.0f, 0.25f);
    ctx.renderer->style.grid_spacing = 0.1f;
    ctx.renderer->style.ground_extent = 6.0f;
    restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<CollideGjk>(ctx); }
  bool OwnsTime() const override { return true; }

  void Update(double frame_dt) override {
    Settings& s = ctx_.settings;
    const bool step_once = s.paused && s.single_step;
    s.single_step = false;
    if (!s.paused || step_once) {
      clock_ += step_once ? 1.0 / 60 : std::clamp(frame_dt, 0.0, 0.1);
      if (auto_ && clock_ >= 0.25) {
        clock_ = 0;
        // one iteration; after the end, a pause, then the next placement
        if (!stepper_->done()) do_step();
        else if (++rest_ >= 2) {
          rest_ = 0;
          ++placement_;
          restart();
        }
      }
    }
  }

  void Draw(Renderer& r, double) override {
    // the shapes, on the left
    draw_shape(r, a_, pose_a_, Color::hex(0x6e7f99, 0.8f));
    draw_shape(r, b_, pose_b_, Color::hex(0xf76b15, 0.7f));
    // the Minkowski difference as points, the origin as a white cross
    // (a polytope as its edges, a rounded one as three great circles of support points, so
    // the simplex inside stays visible)
    if (rings_.empty()) {
      const auto dv = diff_->vertices();
      const auto de = diff_->edges();
      for (std::size_t i = 0; i < de.size(); i += 2)
        r.line(kDiffOrigin + dv[de[i].origin], kDiffOrigin + dv[de[i + 1].origin], Color::hex(0x8a8f98));
      for (const Vec3& w : dv) r.point(kDiffOrigin + w, 3.0f, Color::hex(0xb0b4ba));
    } else {
      for (std::size_t i = 0; i < rings_.size(); ++i)
        r.line(kDiffOrigin + rings_[i], kDiffOrigin + rings_[i % 64 == 63 ? i - 63 : i + 1], Color::hex(0x8a8f98));
    }
    const double c = 0.06;
    r.line(kDiffOrigin - Vec3(c, 0, 0), kDiffOrigin + Vec3(c, 0, 0), colors::white);
    r.line(kDiffOrigin - Vec3(0, c, 0), kDiffOrigin + Vec3(0, c, 0), colors::white);
    r.line(kDiffOrigin - Vec3(0, 0, c), kDiffOrigin + Vec3(0, 0, c), colors::white);
    r.text(kDiffOrigin + Vec3(0, -0.12, 0), "origin", colors::white, 0.8f, 0.5f);
    // the simplex: vertices, edges and (translucent) faces
    const auto s = stepper_->simplex();
    for (std::size_t i = 0; i < s.size(); ++i) {
      r.point(kDiffOrigin + s[i].w, 16.0f, colors::yellow);
      // the support points on the shapes that made this vertex
      r.point(s[i].a, 7.0f, colors::yellow);
      r.point(s[i].b, 7.0f, colors::yellow);
      for (std::size_t j = i + 1; j < s.size(); ++j) r.line(kDiffOrigin + s[i].w, kDiffOrigin + s[j].w, colors::yellow);
    }
    if (s.size() >= 3)
      for (std::size_t i = 0; i < s.size(); ++i)
        for (std::size_t j = i + 1; j < s.size(); ++j)
          for (std::size_t k = j + 1; k < s.size(); ++k)
            r.triangle(kDiffOrigin + s[i].w, kDiffOrigin + s[j].w, kDiffOrigin + s[k].w, Color::hex(0xffc53d, 0.25f));
    // v, the closest point so far, and the last support point w
    const Vec3 v = stepper_->closest();
    // (stopping short of v, whose simplex point stays visible)
    const double lv = glm::length(v);
    if (lv > 0.12) r.arrow(kDiffOrigin, kDiffOrigin + (1 - 0.08 / lv) * v, 0.04, colors::green);
    // (not when it is already a simplex vertex: the run then stops without progress)
    bool known = false;
    for (const SimplexVertex& x : s) known = known || x.w == stepper_->last_support().w;
    if (stepper_->iterations() > 0 && !known) r.point(kDiffOrigin + stepper_->last_support().w, 7.0f, colors::pink);
    if (stepper_->done() && !stepper_->overlap()) {
      // the closest points of the cores, and the text that says the run is over
      Vec3 pa, pb;
      stepper_->closest_points(pa, pb);
      r.line(pa, pb, colors::green);
      r.point(pa, 9.0f, colors::green);
      r.point(pb, 9.0f, colors::green);
    }
    if (stepper_->done())
      r.text(kDiffOrigin + Vec3(0, 0.9, 0), stepper_->overlap() ? "overlap" : "converged", colors::white, 1.0f, 0.5f);
    if (epa_.ok) r.arrow(kDiffOrigin, kDiffOrigin + epa_.depth * epa_.normal, 0.05, colors::red);
  }

  void DrawUI() override {
    ImGui::TextWrapped("GJK looks for the point of A - B closest to the origin. Grey: A - B (the hull of its "
                       "support points); yellow: the simplex; green arrow: v, its closest point; pink: the new "
                       "support point w along -v. The shapes overlap when the origin is inside A - B; "
                       "then EPA's penetration vector is red. Spheres and capsules: GJK runs on their cores "
                       "(a point, a segment), so the simplex lies inside the drawn difference by the radii.");
    bool changed = ImGui::Combo("shape A", &shape_a_, kShapeNames.data(), int(kShapeNames.size()));
    changed |= ImGui::Combo("shape B", &shape_b_, kShapeNames.data(), int(kShapeNames.size()));
    if (ImGui::Button("Step") && !stepper_->done()) do_step();
    ImGui::SameLine();
    if (ImGui::Button("Restart")) changed = true;
    ImGui::SameLine();
    if (ImGui::Button("New placement")) ++placement_, changed = true;
    ImGui::Checkbox("auto step", &auto_);
    if (changed) restart();
    ImGui::Separator();
    ImGui::Text("iteration %d, simplex of %d", stepper_->iterations(), int(stepper_->simplex().size()));
    ImGui::Text("|v| = %.6f m (upper bound of the core distance)", glm::length(stepper_->closest()));
    if (stepper_->iterations() > 0) ImGui::Text("gap |v| - v.w/|v| = %.3g m", stepper_->gap());
    if (stepper_->done())
      ImGui::Text(stepper_->overlap() ? "done: the origin is inside, overlap (EPA depth %.4f m)" : "done: distance %.6f m",
                  stepper_->overlap() ? epa_.depth : std::max(0.0, glm::length(stepper_->closest()) - core_radii_));
  }

  std::vector<Color> ExpectedColors() const override { return {colors::yellow}; }

 private:
  void restart() {
    a_ = demo_shape(shape_a_, hull_);
    b_ = demo_shape(shape_b_, hull_);
    // placements alternate between apart and overlapping
    const double k = placement_;
    pose_a_ = {Vec3(-1.6, 1.1, 0), glm::normalize(glm::angleAxis(0.4 + 0.7 * k, glm::normalize(Vec3(1, 0.3, 0.2))))};
    const double gap = placement_ % 2 == 0 ? 1.05 : 0.55;
    pose_b_ = {Vec3(-1.6 + gap * std::cos(0.9 * k), 1.1 + 0.3 * std::sin(1.3 * k), 0.2 * std::sin(0.7 * k)),
               glm::normalize(glm::angleAxis(1.1 + 0.5 * k, glm::normalize(Vec3(0.2, 1, 0.4))))};
    pa_ = ConvexProxy::of(a_, pose_a_);
    pb_ = ConvexProxy::of(b_, pose_b_);
    core_radii_ = pa_.radius + pb_.radius;
    stepper_.emplace(pa_, pb_);
    epa_ = {};
    rest_ = 0;
    // the Minkowski difference A - B: support points along a sphere of directions
    // (Fibonacci lattice) pushed out by the summed radii, and their convex hull
    cloud_.clear();
    const int n = 900;
    for (int i = 0; i < n; ++i) {
      const double z = 1 - (2.0 * i + 1) / n, rr = std::sqrt(1 - z * z), phi = i * 2.399963229728653;
      const Vec3 d(rr * std::cos(phi), rr * std::sin(phi), z);
      cloud_.push_back(pa_.support(d) - pb_.support(-d) + core_radii_ * d);
    }
    diff_ = ConvexHull::build(cloud_, "Minkowski difference");
    rings_.clear();
    if (diff_->vertices().size() > 200) {
      for (int axis = 0; axis < 3; ++axis)
        for (int k = 0; k < 64; ++k) {
          const double ang = 2 * kPi * k / 64;
          Vec3 d(0.0);
          d[(axis + 1) % 3] = std::cos(ang);
          d[(axis + 2) % 3] = std::sin(ang);
          rings_.push_back(pa_.support(d) - pb_.support(-d) + core_radii_ * d);
        }
    }
  }
  void do_step() {
    stepper_->step();
    if (stepper_->done() && stepper_->overlap()) epa_ = epa_penetration(pa_, pb_);
  }

  std::shared_ptr<const ConvexHull> hull_;
  int shape_a_ = 2, shape_b_ = 3;
  ColliderShape a_{}, b_{};
  Pose pose_a_{}, pose_b_{};
  ConvexProxy pa_{}, pb_{};
  double core_radii_ = 0;
  std::optional<GjkStepper> stepper_;
  PenetrationResult epa_{};
  std::vector<Vec3> cloud_;
  std::shared_ptr<const ConvexHull> diff_;
  std::vector<Vec3> rings_;  // great circles of a rounded difference (empty for polytopes)
  double clock_ = 0;
  int rest_ = 0, placement_ = 0;
  bool auto_ = true;
};

static int reg = RegisterSample("Collision", "GJK stepper", CollideGjk::Create);

}  // namespace
}  // namespace pba::app
