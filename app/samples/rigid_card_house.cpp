// "Rigid bodies/Card house": a tower of thin cards (rigid_scenes::card_house): A-frames of two
// leaning cards, flat cards across their ridges, storey on storey. Friction at the feet and
// the ridges holds it up; the K key (or the Knock button, or --option knock_at=SECONDS) throws
// a heavy ball at its foot, and the mouse grabs and pulls any card.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <GLFW/glfw3.h>
#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/rigid_scenes.h"
#include "renderer.h"
#include "rigid_common.h"

namespace pba::app {
namespace {

constexpr Color kBall = colors::yellow;  // the ball and its launcher: the self-test finds the colour
constexpr Vec3 kLauncher{3.0, 0.45, 0};   // where the ball starts (m)

class CardHouse final : public RigidSample {
 public:
  explicit CardHouse(SampleContext& ctx) : RigidSample(ctx) {
    levels_ = OptionInteger(ctx, "levels", 4, 1, 8);
    knock_at_ = OptionNumber(ctx, "knock_at", -1, -1, 1e6);
    // playing cards: white faces, one red
    palette_ = {Color::hex(0xf4f1ea), Color::hex(0xe8e2d4), Color::hex(0xf4f1ea), Color::hex(0xd9473f)};
    draw_options_.sleep_fade = 0.3f;  // asleep cards stay card-coloured, a little greyer
    Restart();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<CardHouse>(ctx); }

  void Build() override {
    cards_ = rigid_scenes::card_house(bodies_, levels_);
    ball_ = {};
    reference_.clear();
    moved_ = 0;
    knocked_at_ = fell_at_ = -1;
    const double top = bodies_.center_of_mass(cards_.back()).y;
    ctx_.camera->frame({1.0f, static_cast<float>(0.5 * top + 0.15), 0}, static_cast<float>(0.5 * top + 1.0), 0.3f, 0.18f);
  }

  void AfterStep(double, double) override {
    const double t = bodies_.time();
    // the places the cards settled into at 1 s, and how far any card has strayed since
    if (reference_.empty() && t >= 1.0) {
      for (const RigidBodyId c : cards_) reference_.push_back(bodies_.center_of_mass(c));
    } else if (!reference_.empty() && knocked_at_ < 0) {
      for (std::size_t i = 0; i < cards_.size(); ++i)
        moved_ = std::max(moved_, glm::length(bodies_.center_of_mass(cards_[i]) - reference_[i]));
    }
    if (knock_at_ >= 0 && knocked_at_ < 0 && t >= knock_at_) Knock();
    // fallen: the crown half a card below where it settled
    if (knocked_at_ >= 0 && fell_at_ < 0 && !reference_.empty() &&
        bodies_.center_of_mass(cards_.back()).y < reference_.back().y - 0.5) {
      fell_at_ = t;
      std::printf("Card house: fell %.2f s after the knock (the crown half a card down)\n", fell_at_ - knocked_at_);
      std::fflush(stdout);
    }
  }

  void Keyboard(int key, int) override {
    if (key == GLFW_KEY_K) Knock();
  }

  void Draw(Renderer& r, double alpha) override {
    draw_options_.highlight = ball_;
    draw_options_.highlight_color = kBall;
    RigidSample::Draw(r, alpha);
    // the launcher: a post with a yellow knob, beside where the ball starts
    r.box(kLauncher + Vec3(0.45, -0.25, 0), {0.08, 0.2, 0.08}, Quat(1, 0, 0, 0), colors::grey);
    r.sphere(kLauncher + Vec3(0.45, 0, 0), 0.15, kBall);
  }

  void DrawUI() override {
    if (SolverControls()) return;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderInt("levels", &levels_, 1, 8)) Restart();
    if (ImGui::Button("Knock (K)")) Knock();
    if (knocked_at_ < 0 && reference_.empty())
      ImGui::Text("settling");
    else if (knocked_at_ < 0)
      ImGui::Text("standing: every card within %.2f mm of its place at 1 s", 1e3 * moved_);
    else if (fell_at_ < 0)
      ImGui::Text("knocked at %.2f s", knocked_at_);
    else
      ImGui::Text("knocked at %.2f s, fell %.2f s later", knocked_at_, fell_at_ - knocked_at_);
    Readout();
    ImGui::TextWrapped(
        "%zu cards of 1 m x 0.7 m x 2 cm, mu 0.7, leaning 10 degrees in A-frames; flat cards across the "
        "ridges rest on the cards' outer top edges. The soft step and TGS hold it (it falls asleep, drawn "
        "faded); sequential impulses and XPBD let it fold. K throws a 100 kg ball at its foot; drag a card "
        "with the mouse. --option levels=N --option knock_at=SECONDS.",
        cards_.size());
  }

  std::vector<Color> ExpectedColors() const override { return {kBall}; }

 protected:
  RigidBodyId ReportBody() const override { return cards_.empty() ? RigidBodyId{} : cards_.back(); }

 private:
  // a 0.2 m ball of 3000 kg/m^3 (100 kg) thrown from the launcher at the house's foot
  void Knock() {
    if (bodies_.valid(ball_)) return;
    knocked_at_ = bodies_.time();
    if (!reference_.empty() && moved_ < 1e-3)
      std::printf("Card house: stood from 1 s to the knock at %.2f s, every card within %.2f mm of its place\n",
                  knocked_at_, 1e3 * moved_);
    else if (!reference_.empty())
      std::printf("Card house: a card moved %.1f mm between 1 s and the knock at %.2f s\n", 1e3 * moved_, knocked_at_);
    std::fflush(stdout);
    ball_ = bodies_.create({.name = "ball", .pose = {kLauncher}, .linear_velocity = {-8, 1.0, 0},
                            .shapes = {{.shape = ColliderShape::sphere(0.2), .density = 3000,
                                        .material = {.restitution = 0.2, .friction = 0.5}}}});
  }

  int levels_ = 4;
  double knock_at_ = -1;
  std::vector<RigidBodyId> cards_;
  RigidBodyId ball_{};
  std::vector<Vec3> reference_;  // the cards' centres at 1 s (m)
  double moved_ = 0;             // the farthest any card strayed from them before the knock (m)
  double knocked_at_ = -1, fell_at_ = -1;
};

static int reg = RegisterSample("Rigid bodies", "Card house", CardHouse::Create);

}  // namespace
}  // namespace pba::app
