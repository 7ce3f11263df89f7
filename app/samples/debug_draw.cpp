// "Basics/Debug draw": every pba::DebugDraw primitive, and a stress grid of hundreds
// of lit solids to check the renderer keeps its frame rate.
#include <cmath>

#include <imgui.h>

#include "camera.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

class DebugDrawSample final : public Sample {
 public:
  explicit DebugDrawSample(SampleContext& ctx) : Sample(ctx) {
    ctx.camera->frame({0.0f, 1.2f, 0.0f}, 5.0f, 0.5f, 0.38f);
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<DebugDrawSample>(ctx); }

  // a slow spin so every frame differs
  void Step(double, double dt) override { angle_ += 0.6 * dt; }

  void Draw(Renderer& r, double) override {
    const Quat spin = glm::angleAxis(angle_, Vec3(0, 1, 0));
    // one of each primitive along a row
    r.sphere({-4, 0.6, 0}, 0.6, colors::red);
    r.box({-2, 0.6, 0}, {0.5, 0.6, 0.4}, spin, colors::orange);
    r.capsule(Vec3(0, 0.4, -0.5) , Vec3(0, 0.4, 0) + spin * Vec3(0, 0.8, 0.5), 0.35, colors::green);
    r.arrow({2, 0.05, 0}, Vec3(2, 0.05, 0) + spin * Vec3(1.2, 1.2, 0), 0.3, colors::cyan);
    r.plane(Vec3(0, 1, 0), 2.5, 0.8, Color::hex(0x3e63dd, 0.45f));
    for (int i = 0; i < 24; ++i) {
      const double a = angle_ + i * 0.2618;
      r.point(Vec3(4 + 0.8 * std::cos(a), 0.8 + 0.4 * std::sin(3 * a), 0.8 * std::sin(a)), 7.0f, colors::yellow);
    }
    r.line({-5, 0.01, 1.5}, {5, 0.01, 1.5}, colors::grey);
    const char* names[] = {"sphere", "box", "capsule", "arrow", "points"};
    for (int i = 0; i < 5; ++i) r.text(Vec3(-4 + 2 * i, 1.7, 0), names[i], colors::white, 1.0f, 0.5f);
    r.text(Vec3(0, 2.75, 0), "plane", colors::white, 1.0f, 0.5f);
    // the stress grid behind
    const int n = count_;
    const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
    for (int k = 0; k < n; ++k) {
      const double x = ((k % side) - 0.5 * (side - 1)) * 0.5, z = -3.5 - (k / side) * 0.5;
      const double y = 0.25 + 0.15 * std::sin(angle_ * 2 + k * 0.37);
      const Color c = Color::rgb(0.35f + 0.5f * float(k % 7) / 7, 0.45f, 0.75f - 0.4f * float(k % 5) / 5);
      if (k % 3 == 0) r.sphere({x, y, z}, 0.18, c);
      else if (k % 3 == 1) r.box({x, y, z}, {0.15, 0.15, 0.15}, spin, c);
      else r.capsule({x - 0.12, y, z}, {x + 0.12, y, z}, 0.1, c);
    }
  }

  void DrawUI() override {
    ImGui::TextWrapped("Each primitive of pba::DebugDraw, and a grid of lit solids to check the "
                       "renderer keeps up (instanced drawing: one draw call per shape kind).");
    ImGui::SliderInt("solids", &count_, 0, 2000);
  }

  std::vector<Color> ExpectedColors() const override { return {colors::yellow}; }

 private:
  double angle_ = 0;
  int count_ = 300;
};

static int reg = RegisterSample("Basics", "Debug draw", DebugDrawSample::Create);

}  // namespace
}  // namespace pba::app
