// "Soft bodies/Tearable cloth": a curtain hanging from its top edge. Grab it with the mouse
// and pull: a constraint whose strain exceeds the tear strain breaks for good, and the
// triangles on it go. Until you grab it, two scripted hands take the bottom edge either
// side of the middle and pull it apart, ripping the curtain open. Strain colours run from
// the cloth's colour to red at the tear strain.
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

constexpr double kTop = 2.7;      // height of the curtain rail (m)
constexpr double kSide = 1.6;     // curtain width and height (m)
constexpr double kPullStart = 0.25, kPullEnd = 3.0, kRestartAt = 6.0;  // the scripted pull (s)
constexpr double kPullSpeed = 0.3;  // speed of each hand (m/s)

class TearSample final : public OneBodySample {
 public:
  explicit TearSample(SampleContext& ctx) : OneBodySample(ctx) {
    // --option tear=STRAIN n=N demo=0|1 pull=down|apart|corners|point (the scripted hands)
    //          solver=xpbd|mass-spring
    def_ = XpbdCloth(12, 0.2);
    def_.tear_strain = OptionNumber(ctx, "tear", 0.3, 0.01, 5);
    n_ = OptionInteger(ctx, "n", n_, 2, 256);
    demo_ = OptionFlag(ctx, "demo", true);
    const std::string pull = ctx.option("pull", "apart");
    if (pull == "down") pull_ = Pull::Down;
    else if (pull == "apart") pull_ = Pull::Apart;
    else if (pull == "corners") pull_ = Pull::Corners;
    else if (pull == "point") pull_ = Pull::Point;
    else throw Error("--option pull=" + pull + ": expected down, apart, corners or point");
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.0f, 1.75f, 0.45f}, 1.75f, 0.5f, 0.12f);
    build();
    SolverFromOption();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<TearSample>(ctx); }

  void Step(double, double dt) override {
    // the scripted hands: take the corners, pull them apart, let go, start again
    if (demo_ && !user_) {
      if (t_ >= kRestartAt) build();
      const double s = t_ - kPullStart;
      if (s >= 0 && t_ < kPullEnd) {
        for (const Hand& h : hands_)
          for (std::size_t k = 0; k < h.particles.size(); ++k) {
            const Vec3 target = h.from[k] + h.direction * (kPullSpeed * s);
            if (!demo_started_) body_.pin(h.particles[k], target);
            else body_.set_pin_target(h.particles[k], target);
          }
        demo_started_ = true;
      } else if (t_ >= kPullEnd && demo_started_) {
        release_hands();
      }
    }
    body_.settings() = def_;
    body_.step(t_, dt);
    t_ += dt;
  }

  void Draw(Renderer& r, double) override {
    // the rail, the curtain (red where it is about to tear) and the pull
    r.capsule(Vec3(-0.55 * kSide, kTop + 0.02, 0), Vec3(0.55 * kSide, kTop + 0.02, 0), 0.025, soft_colors::pole);
    view_.strain_scale = def_.tear_strain;
    painter_.Draw(r, body_, view_, soft_colors::fabric, {}, ctx_.draw);
    grab_.Draw(r, Bodies());
    // the hands: a yellow ball at each held patch
    if (demo_started_) {
      for (const Hand& h : hands_) {
        Vec3 c(0);
        for (std::uint32_t p : h.particles) c += body_.position(p) / static_cast<double>(h.particles.size());
        r.sphere(c + Vec3(0, 0, 0.03), 0.045, soft_colors::grab);
      }
    }
    char buf[128];
    std::snprintf(buf, sizeof buf, "%zu constraints torn.  Grab the cloth with the mouse and pull (tear at %.0f %% strain).",
                  body_.broken_constraints(), 100 * def_.tear_strain);
    DrawBanner(ctx_, buf);
  }

  void DrawUI() override {
    float tear = static_cast<float>(100 * def_.tear_strain);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("tear strain", &tear, 2.0f, 200.0f, "%.0f %%", ImGuiSliderFlags_Logarithmic))
      def_.tear_strain = tear / 100.0;
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("a constraint stretched beyond this breaks for good");
    bool rebuild = false;
    ImGui::SetNextItemWidth(-110);
    rebuild |= ImGui::SliderInt("particles per side", &n_, 8, 96);
    SolverRows();
    if (ImGui::Button("Mend the curtain") || rebuild) build();
    ImGui::SameLine();
    if (ImGui::Checkbox("scripted hands", &demo_)) {
      if (demo_) user_ = false;
      else release_hands();
    }
    ViewRows(false);
    ImGui::Text("torn: %zu of %zu constraints, %zu triangles left", body_.broken_constraints(),
                body_.constraint_count(), body_.triangles().size());
    ImGui::TextWrapped(
        "After each step every intact constraint's strain (l - l0)/l0 is compared with the tear strain; one "
        "beyond it breaks for good and the triangles on it go. XPBD keeps the rest of the cloth stiff, so the "
        "strain gathers where the cloth is held and the tear runs from there.");
  }

  std::vector<Color> ExpectedColors() const override { return {colors::orange}; }

 private:
  // the user takes over from the scripted hands
  void Grabbed() override {
    user_ = true;
    release_hands();
  }

  // the curtain hanging from the rail, top row pinned
  void build() {
    Restart();
    ClothDef c;
    c.origin = Vec3(-0.5 * kSide, kTop, 0);
    c.edge_u = Vec3(kSide, 0, 0);
    c.edge_v = Vec3(0, -kSide, 0);
    c.nx = c.ny = n_;
    c.mass = 0.5;
    c.pins = ClothPins::FirstRow;
    body_ = SoftBody::cloth_grid(c, def_);
    // the scripted hands: each holds a patch of particles (columns i0..i1, rows j0..j1 as
    // fractions of the side) and pulls it along its direction
    hands_.clear();
    auto hand = [&](double i0, double i1, double j0, double j1, const Vec3& dir) {
      Hand h;
      h.direction = glm::normalize(dir);
      const int a0 = static_cast<int>(std::lround(i0 * (n_ - 1))), a1 = static_cast<int>(std::lround(i1 * (n_ - 1)));
      const int b0 = static_cast<int>(std::lround(j0 * (n_ - 1))), b1 = static_cast<int>(std::lround(j1 * (n_ - 1)));
      for (int j = b0; j <= b1; ++j)
        for (int i = a0; i <= a1; ++i) {
          h.particles.push_back(static_cast<std::uint32_t>(j * n_ + i));
          h.from.push_back(body_.position(h.particles.back()));
        }
      hands_.push_back(std::move(h));
    };
    switch (pull_) {
      case Pull::Down: hand(0.38, 0.62, 0.95, 1.0, Vec3(0, -1, 0.4)); break;
      case Pull::Apart:
        hand(0.35, 0.4, 0.75, 1.0, Vec3(-1, 0, 0.2));
        hand(0.6, 0.65, 0.75, 1.0, Vec3(1, 0, 0.2));
        break;
      case Pull::Corners:
        hand(0.0, 0.06, 0.94, 1.0, Vec3(-1, -0.15, 0.25));
        hand(0.94, 1.0, 0.94, 1.0, Vec3(1, -0.15, 0.25));
        break;
      case Pull::Point: hand(0.5, 0.5, 0.6, 0.6, Vec3(0, -0.15, 1)); break;
    }
    demo_started_ = false;
  }

  // the hands let go (the particles keep their velocities)
  void release_hands() {
    if (!demo_started_) return;
    for (const Hand& h : hands_)
      for (std::uint32_t p : h.particles)
        if (body_.grabbed() != p) body_.unpin(p);
    demo_started_ = false;
  }

  enum class Pull { Down, Apart, Corners, Point };

  struct Hand {
    std::vector<std::uint32_t> particles;  // the patch held
    std::vector<Vec3> from;                // where each started (m)
    Vec3 direction{0};                     // the pull (unit)
  };

  int n_ = 40;
  bool demo_ = true, user_ = false, demo_started_ = false;
  std::vector<Hand> hands_;
  Pull pull_ = Pull::Apart;
};

static int reg = RegisterSample("Soft bodies", "Tearable cloth", TearSample::Create);

}  // namespace
}  // namespace pba::app
