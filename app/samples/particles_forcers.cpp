// "Particles/Forcer volumes" (workbook 4.1): the shared scene builder
// pba::scenes::forcer_stream: a jet of particles through a fan (or a pulsing air cannon),
// a vortex and an attractor that circles on a Kinematic path. The volumes are drawn with
// arrows that sample their force field; strengths and the emission rate change live.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/scene.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

class Forcers final : public Sample {
 public:
  explicit Forcers(SampleContext& ctx) : Sample(ctx) {
    // --option cannon=0|1 rate=N fan=MN vortex=MN attractor=MN (strengths in millinewtons)
    params_.air_cannon = OptionFlag(ctx, "cannon", false);
    params_.rate = OptionNumber(ctx, "rate", 3000, 0, 50000);
    params_.fan_strength = 1e-3 * OptionNumber(ctx, "fan", 40, -60, 60);
    params_.vortex_strength = 1e-3 * OptionNumber(ctx, "vortex", 10, -60, 60);
    params_.attractor_strength = 1e-3 * OptionNumber(ctx, "attractor", 10, -60, 60);
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.4f, 1.3f, 0.0f}, 3.9f, 0.3f, 0.5f);
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Forcers>(ctx); }

  void Step(double, double dt) override {
    apply();
    TickWorld(world_, ctx_.settings, dt);
  }

  void Draw(Renderer& r, double) override {
    // the nozzle and its aim
    const Vec3 o = world_.pose(world_.find("stream")).position;
    const Vec3 aim = glm::normalize(Vec3(1, 0.25, 0));
    if (ctx_.draw.forcers) r.capsule(o - 0.18 * aim, o, 0.05, Color::hex(0x5a606b));
    // the volumes, then the stream as points
    for (const Forcer& f : world_.forcers()) DrawForcer(r, f, world_.time(), ctx_.draw);
    DrawParticles(r, world_.particles(), ctx_.draw, 3.0f, 0, 0);
    if (!ctx_.settings.show_labels || !ctx_.draw.forcers) return;
    for (const Forcer& f : world_.forcers()) {
      const double top = f.shape == ForcerShape::Box ? f.half_extents.y : (f.shape == ForcerShape::Cylinder ? f.half_height : f.radius);
      const char* name = f.kind == ForcerKind::Fan ? (f.pulse_period > 0 ? "air cannon" : "fan")
                         : f.kind == ForcerKind::Vortex ? "vortex" : "attractor";
      r.text(f.pose.position + Vec3(0, top + 0.15, 0), name, ForcerColor(f.kind), 1.0f, 0.5f);
    }
  }

  void DrawUI() override {
    float rate = static_cast<float>(params_.rate);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("rate", &rate, 0.0f, 20000.0f, "%.0f /s")) params_.rate = rate;
    slider("fan", &params_.fan_strength, ForcerKind::Fan);
    slider("vortex", &params_.vortex_strength, ForcerKind::Vortex);
    slider("attractor", &params_.attractor_strength, ForcerKind::Attractor);
    ImGui::Checkbox("air cannon (fan on 0.3 s of every 1 s)", &params_.air_cannon);
    if (ImGui::Button("Restart the stream")) build();
    ImGui::Text("live particles: %s", Thousands(static_cast<long long>(world_.particles().size())).c_str());
    ProfileReadout(world_);
    ImGui::TextWrapped(
        "Forcer volumes add a force (newtons) to every particle inside them: the green fan pushes up along its "
        "arrow, the yellow vortex swirls particles around its axis and pulls them in, the pink attractor (riding a "
        "Kinematic circle) pulls toward its centre, fading inside its softening radius. Light particles are pushed "
        "hardest (a = F / m; these weigh 1 g). Negative strengths reverse a forcer.");
  }

  std::vector<Color> ExpectedColors() const override {
    return {particle_colors::fan, particle_colors::vortex, particle_colors::attractor, colors::cyan};
  }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    WorldPoints(world_, out, max_points);
  }

 private:
  void slider(const char* name, double* v, ForcerKind k) {
    const Color c = ForcerColor(k);
    float x = static_cast<float>(*v * 1e3);
    ImGui::PushStyleColor(ImGuiCol_SliderGrab, ImVec4(c.r, c.g, c.b, 1));
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat(name, &x, -60.0f, 60.0f, "%.1f mN")) *v = x * 1e-3;
    ImGui::PopStyleColor();
  }

  // the panel's values into the world's forcers and emitter (between ticks)
  void apply() {
    world_.forcer(world_.find("fan")).strength = params_.fan_strength;
    Forcer& fan = world_.forcer(world_.find("fan"));
    fan.pulse_period = params_.air_cannon ? 1.0 : 0.0;
    fan.pulse_duration = params_.air_cannon ? 0.3 : 0.0;
    Forcer& vortex = world_.forcer(world_.find("vortex"));
    vortex.strength = params_.vortex_strength;
    vortex.pull = 0.3 * params_.vortex_strength;
    world_.forcer(world_.find("attractor")).strength = params_.attractor_strength;
    world_.particles().emitter(world_.emitter(world_.find("stream"))).rate = params_.rate;
  }

  // a fresh world, run for 3 s so the stream is established
  void build() {
    world_ = World(WorldDef{.particles = {.capacity = 16384}});
    scenes::forcer_stream(world_, params_);
    const double dt = ctx_.settings.stepper.fixed_dt;
    for (int i = 0; i < static_cast<int>(std::ceil(3.0 / dt)); ++i) {
      apply();
      TickWorld(world_, ctx_.settings, dt);
    }
  }

  scenes::ForcerStreamParams params_;
  World world_;
};

static int reg = RegisterSample("Particles", "Forcer volumes", Forcers::Create);

}  // namespace
}  // namespace pba::app
