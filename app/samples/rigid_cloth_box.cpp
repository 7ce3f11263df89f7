// "Rigid bodies/Cloth on a falling box": a World with a rigid box falling onto the ground and
// a cloth (a soft body) falling onto the box (world_scenes::cloth_on_falling_box, the scene of
// the RigidStage.ClothLandsOnAFallingBox test). Each tick the rigid stage moves the box first
// and puts its shape in the tick's collision world, so the cloth meets the box where it is
// in that tick: it lands on the falling box's top and drapes over it. The mouse drags the cloth
// or the box, whichever is nearer under the cursor.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/world_scenes.h"
#include "renderer.h"
#include "rigid_common.h"
#include "soft_common.h"

namespace pba::app {
namespace {

constexpr Color kMarker = colors::yellow;  // the cloth's middle: the self-test finds the colour
constexpr double kMarkerRadius = 0.09;     // m

class ClothOnBoxSample final : public Sample {
 public:
  explicit ClothOnBoxSample(SampleContext& ctx) : Sample(ctx) {
    settings_.solver = RigidSolverOption(ctx);
    n_ = OptionInteger(ctx, "n", 31, 2, 101);
    report_path_ = ctx.option("report", "");
    ctx.settings.stepper.fixed_dt = 1.0 / 60.0;
    ctx.renderer->style.grid_spacing = 0.5f;
    view_.strain = false;
    ctx.camera->frame({0.0f, 0.75f, 0.0f}, 1.9f, 0.5f, 0.38f);
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<ClothOnBoxSample>(ctx); }

  void Step(double, double dt) override {
    world_.rigid().settings() = settings_;
    rigid_grab_.Apply(world_.rigid());
    TickWorld(world_, ctx_.settings, dt);
    Measure();
  }

  void Draw(Renderer& r, double) override {
    DrawRigidBodies(r, world_, ctx_.draw);
    painter_.Draw(r, cloth(), view_, soft_colors::cloth, {}, ctx_.draw);
    // the cloth's middle particle, whose height over the box's top the panel reports: a ball
    // resting on it (centred on it, half the ball was under the cloth, and at 480x270 the
    // visible half covered 3 to 5 pixels, under the 6 the self-test looks for)
    r.sphere(cloth().position(Middle()) + Vec3(0, kMarkerRadius, 0), kMarkerRadius, kMarker);
    rigid_grab_.Draw(r, world_.rigid());
    soft_grab_.Draw(r, Bodies());
    if (++frames_ % 5 == 0) {
      // for the window test: the cloth's centre of mass, and its middle particle's pixel
      const Vec3 c = cloth().center_of_mass(), m = cloth().position(Middle());
      glm::vec2 px(-1, -1);
      if (!r.project(m, &px)) px = glm::vec2(-1, -1);
      char extra[160];
      std::snprintf(extra, sizeof extra, "cloth %.6f %.6f %.6f middle %.6f %.6f %.6f clothpx %.1f %.1f", c.x, c.y, c.z,
                    m.x, m.y, m.z, px.x, px.y);
      WriteRigidReport(report_path_, r, frames_, world_.rigid(), world_.rigid_body_id(scene_.box), rigid_grab_, extra);
    }
  }

  void DrawUI() override {
    RigidSolverKnobs(settings_, world_.rigid().profile().substeps);
    ImGui::Checkbox("sleep", &settings_.sleep);
    ImGui::SameLine();
    if (ImGui::Button("Restart")) Restart();
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderInt("cloth particles", &n_, 8, 61)) Restart();
    if (landed_at_ >= 0) ImGui::Text("the box landed at t = %.2f s", landed_at_);
    if (rest_gap_ >= 0)
      ImGui::Text("the cloth over the top (yellow: its middle): %.1f mm above it (thickness %.0f mm)", 1e3 * rest_gap_,
                  1e3 * def_.cloth.thickness);
    ImGui::Text("t = %.2f s; box %s", world_.time(),
                world_.rigid().awake(world_.rigid_body_id(scene_.box)) ? "awake" : "asleep");
    ProfileReadout(world_);
    ImGui::TextWrapped(
        "A World with a rigid body (the 1 m box, 1000 kg) and a soft body (a 2 m XPBD cloth of 0.2 kg): the "
        "rigid stage steps the box before the soft bodies, so the cloth lands on the falling box where it "
        "is in that tick and drapes over it once both rest. Drag the cloth or the box with the mouse. "
        "--option n=N --option solver=soft|si|tgs|xpbd.");
  }

  void Mouse(int button, bool down, const Vec3& o, const Vec3& d) override {
    if (button != 0) return;
    if (!down) {
      rigid_grab_.Release();
      soft_grab_.Release(Bodies());
      return;
    }
    // the cloth or the box under the cursor, whichever is nearer
    if (soft_grab_.Press(Bodies(), *ctx_.camera, o, d)) {
      const double s = glm::dot(soft_grab_.target() - o, glm::normalize(d));
      if (rigid_grab_.Press(world_.rigid(), o, d, s)) soft_grab_.Release(Bodies());
    } else {
      rigid_grab_.Press(world_.rigid(), o, d);
    }
  }
  void MouseMove(const Vec3& o, const Vec3& d) override {
    rigid_grab_.Move(world_.rigid(), o, d);
    soft_grab_.Move(Bodies(), o, d);
  }
  bool MouseCaptured() const override { return rigid_grab_.held(world_.rigid()) || soft_grab_.held(); }

  FiniteCheck CheckFinite() const override {
    // the World refuses non-finite states itself (tick throws naming the entity); the box
    // and the cloth are checked here for the app's message
    const Vec3 c = world_.pose(scene_.box).position;
    if (!is_finite(c)) return {false, 0, "the box is not finite"};
    const SoftBody& b = cloth();
    for (std::size_t k = 0; k < b.size(); ++k)
      if (!is_finite(b.position(k))) return {false, k, "cloth particle " + std::to_string(k) + " is not finite"};
    return {};
  }
  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    WorldPoints(world_, out, max_points);
  }
  std::vector<Color> ExpectedColors() const override { return {kMarker}; }

 private:
  // the particle nearest the cloth's middle as it starts (size() / 2, taken before, is not
  // the middle on every grid, the particles being in the solver's order: at n = 4 it hung
  // down the box's side)
  std::size_t Middle() const { return middle_; }
  const SoftBody& cloth() const {
    return dynamic_cast<const SoftSystem&>(*world_.find_system(SoftSystem::kName)).body(scene_.cloth);
  }
  std::span<SoftBody* const> Bodies() {
    one_ = &soft_system(world_).body(scene_.cloth);
    return std::span<SoftBody* const>(&one_, 1);
  }

  void Restart() {
    rigid_grab_.Release();
    soft_grab_.Reset();
    world_ = World({.rigid = {.contacts = settings_}});
    def_.cloth_particles = n_;
    def_.cloth = XpbdCloth(12, 0.1);
    def_.cloth.thickness = 0.01;
    def_.cloth.bend_compliance = 1.0;  // a soft fabric (XpbdCloth: 1e-3) drapes rather than tents
    scene_ = world_scenes::cloth_on_falling_box(world_, def_);
    const SoftBody& b = cloth();
    const Vec3 c = b.center_of_mass();
    middle_ = 0;
    for (std::size_t k = 1; k < b.size(); ++k)
      if (glm::length(b.position(k) - c) < glm::length(b.position(middle_) - c)) middle_ = k;
    landed_at_ = rest_gap_ = -1;
    reported_ = false;
  }

  // when the box lands, and from 3 s how far above its top the cloth over the middle of the
  // top face lies (its thickness, when it rests on the box); printed once for the tests
  void Measure() {
    const double t = world_.time(), top = world_.pose(scene_.box).position.y + def_.box_half;
    const RigidBodySystem& rb = world_.rigid();
    const RigidBodyId box = world_.rigid_body_id(scene_.box);
    if (landed_at_ < 0 && top - 2 * def_.box_half < 0.01 && std::abs(rb.linear_velocity(box).y) < 0.05) landed_at_ = t;
    if (t < 3.0 || reported_) return;
    const SoftBody& b = cloth();
    double sum = 0;
    int middle = 0;
    for (std::size_t k = 0; k < b.size(); ++k) {
      const Vec3 p = b.position(k) - world_.pose(scene_.box).position;
      if (std::abs(p.x) >= 0.25 || std::abs(p.z) >= 0.25) continue;
      sum += b.position(k).y - top;
      ++middle;
    }
    // a coarse cloth (n = 2, 4) has no particle over the middle of the top: its middle
    // particle's gap, if it lies over the top (it printed -1000 mm, the "none" mark)
    const Vec3 m = b.position(Middle()) - world_.pose(scene_.box).position;
    if (middle == 0 && std::abs(m.x) < def_.box_half && std::abs(m.z) < def_.box_half) {
      sum = b.position(Middle()).y - top;
      middle = 1;
    }
    rest_gap_ = middle ? sum / middle : -1;
    reported_ = true;
    if (middle == 0)
      std::printf("Cloth on a falling box: the box landed at t = %.2f s; at t = 3 s no cloth particle lies over its "
                  "top (%d particles a side)\n",
                  landed_at_, n_);
    else
      std::printf("Cloth on a falling box: the box landed at t = %.2f s; at t = 3 s the cloth over its top lies %.1f "
                  "mm above it (the cloth is %.0f mm thick); its middle (the marker) %.2f m above the top\n",
                  landed_at_, 1e3 * rest_gap_, 1e3 * def_.cloth.thickness, m.y - def_.box_half);
    std::fflush(stdout);
  }

  ContactSettings settings_{};
  world_scenes::ClothOnBoxDef def_;
  World world_;
  world_scenes::ClothOnBox scene_;
  RigidGrab rigid_grab_;
  SoftGrab soft_grab_;
  SoftBody* one_ = nullptr;
  SoftPainter painter_;
  SoftView view_;
  int n_ = 31;
  std::size_t middle_ = 0;  // the cloth's particle nearest its middle at the start
  std::string report_path_;
  long long frames_ = 0;
  double landed_at_ = -1, rest_gap_ = -1;
  bool reported_ = false;
};

static int reg = RegisterSample("Rigid bodies", "Cloth on a falling box", ClothOnBoxSample::Create);

}  // namespace
}  // namespace pba::app
