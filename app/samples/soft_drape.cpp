// "Soft bodies/Cloth on a sphere": a square XPBD cloth dropped flat, a little off-centre,
// onto a sphere resting on the ground. Contacts project the particles out of the sphere and
// plane and apply Coulomb friction to their sliding (Macklin et al. 2014): with enough
// friction the cloth stays draped, with little it slides off.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "renderer.h"
#include "sample.h"
#include "soft_common.h"

namespace pba::app {
namespace {

constexpr double kOffset = 0.25;  // the cloth's centre is dropped this far off the sphere's (m)

class DrapeSample final : public OneBodySample {
 public:
  explicit DrapeSample(SampleContext& ctx) : OneBodySample(ctx) {
    // --option friction=MU n=N radius=M solver=xpbd|mass-spring
    def_ = XpbdCloth(12, 0.1);
    def_.friction = OptionNumber(ctx, "friction", 0.4, 0, 2);
    n_ = OptionInteger(ctx, "n", n_, 2, 256);
    radius_ = OptionNumber(ctx, "radius", radius_, 0.1, 1.0);
    def_.thickness = 0.012;
    view_.strain = false;
    ctx.renderer->style.grid_spacing = 0.25f;
    ctx.camera->frame({0.0f, 0.45f, 0.0f}, 1.45f, 0.55f, 0.42f);
    build();
    SolverFromOption();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<DrapeSample>(ctx); }

  void Step(double, double dt) override {
    if (auto_drop_ && t_ >= 7.0 && !grab_.held()) build();
    body_.settings() = def_;
    body_.step(t_, dt, colliders_);
    t_ += dt;
  }

  void Draw(Renderer& r, double) override {
    // the sphere (slightly smaller than the contact radius, so the cloth shows over it)
    DrawColliders(r, colliders_, {}, ctx_.draw);
    painter_.Draw(r, body_, view_, soft_colors::cloth, {}, ctx_.draw);
    // a blob shadow under the cloth's centre of mass
    const Vec3 c = body_.center_of_mass();
    r.shadow(Vec3(c.x, std::max(c.y, 0.0), c.z), 0.45);
    grab_.Draw(r, Bodies());
    char buf[96];
    std::snprintf(buf, sizeof buf, "friction %.2f: drag the cloth with the mouse", def_.friction);
    DrawBanner(ctx_, buf);
  }

  void DrawUI() override {
    float mu = static_cast<float>(def_.friction);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("friction", &mu, 0.0f, 1.5f, "%.2f")) def_.friction = mu;
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Coulomb friction coefficient of the contacts with sphere and ground");
    float rad = static_cast<float>(radius_);
    ImGui::SetNextItemWidth(-110);
    bool rebuild = false;
    if (ImGui::SliderFloat("sphere radius", &rad, 0.15f, 0.6f, "%.2f m")) {
      radius_ = rad;
      rebuild = true;
    }
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("particles per side", &n_, 8, 96);
    SolverRows();
    if (ImGui::Button("Drop again") || rebuild) build();
    ImGui::SameLine();
    ImGui::Checkbox("every 7 s", &auto_drop_);
    ViewRows();
    ImGui::Text("%zu particles, %zu constraints in %zu colours", body_.size(), body_.constraint_count(),
                body_.color_count());
    ImGui::TextWrapped(
        "Structural, shear and bend distance constraints (XPBD) keep the cloth's shape; contacts push each "
        "particle out of the sphere and the ground and remove its sliding up to mu times the push (static "
        "friction). Dropped off-centre, the cloth stays draped from friction 0.4, slides off the sphere at 0.2 "
        "and off across the ground at 0.");
  }

  std::vector<Color> ExpectedColors() const override { return {}; }

 private:
  // a flat square cloth above the sphere (its centre 25 cm off the sphere's, so that it
  // slides off unless friction holds it), the sphere and the ground
  void build() {
    Restart();
    const double side = 1.5;
    ClothDef c;
    c.origin = Vec3(-0.5 * side + kOffset, 2 * radius_ + 0.45, -0.5 * side);
    c.edge_u = Vec3(side, 0, 0);
    c.edge_v = Vec3(0, 0, side);
    c.nx = c.ny = n_;
    c.mass = 0.4;
    c.pins = ClothPins::None;
    body_ = SoftBody::cloth_grid(c, def_);
    colliders_ = {Collider::sphere(Vec3(0, radius_, 0), radius_), Collider::plane(Vec3(0, 1, 0), 0)};
  }

  std::vector<Collider> colliders_;
  int n_ = 40;
  double radius_ = 0.35;
  bool auto_drop_ = true;
};

static int reg = RegisterSample("Soft bodies", "Cloth on a sphere", DrapeSample::Create);

}  // namespace
}  // namespace pba::app
