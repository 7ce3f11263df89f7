// "Basics/Debug draw": every pba::DebugDraw primitive, and a stress grid of hundreds
// of lit solids to check the renderer keeps its frame rate.
#include <algorithm>
#include <cmath>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

class DebugDrawSample final : public Sample {
 public:
  explicit DebugDrawSample(SampleContext& ctx) : Sample(ctx) {
    // the row of primitives (x in [-4.6, 4.8], z = 0) and the grid behind it (x within
    // +-4.4, z from -3.5 to -11.7 at 300 solids)
    ctx.camera->frame({0.0f, 0.6f, -4.5f}, 7.5f, 0.5f, 0.38f);
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
      const Vec3 p = grid_position(k, side);
      const double x = p.x, y = p.y, z = p.z;
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

  // the primitives and the grid's solids, so the self-test checks that they are drawn where
  // the panels leave them visible
  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    for (double x : {-4.0, -2.0, 0.0, 2.0, 4.0}) out.push_back({x, 0.6, 0});
    const int n = count_, side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
    const int step = std::max(1, n / std::max(1, static_cast<int>(max_points)));
    for (int k = 0; k < n; k += step) out.push_back(grid_position(k, side));
  }

 private:
  // solid k of the stress grid (`side` solids a row), bobbing with the spin
  Vec3 grid_position(int k, int side) const {
    return {((k % side) - 0.5 * (side - 1)) * 0.5, 0.25 + 0.15 * std::sin(angle_ * 2 + k * 0.37), -3.5 - (k / side) * 0.5};
  }

  double angle_ = 0;
  int count_ = 300;
};

static int reg = RegisterSample("Basics", "Debug draw", DebugDrawSample::Create);

}  // namespace
}  // namespace pba::app
