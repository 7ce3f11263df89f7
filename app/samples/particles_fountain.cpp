// "Particles/Fountain" (issue 4): the shared scene builder pba::scenes::fountain, an
// emitter keeping about 100k particles alive (20 000 per second for 5 s), or sparks. Rate,
// lifetime, speed, spread and the colours over life change live; the panel shows the live
// count and the step time. Particles are drawn as screen-space points.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/scene.h"
#include "plot.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

class Fountain final : public Sample {
 public:
  explicit Fountain(SampleContext& ctx) : Sample(ctx) {
    // --option sparks=0|1 rate=N lifetime=S prewarm=0|1 point=PX
    params_.sparks = OptionFlag(ctx, "sparks", false);
    preset(params_.sparks);
    params_.rate = OptionNumber(ctx, "rate", params_.rate, 0, 200000);
    params_.lifetime = OptionNumber(ctx, "lifetime", params_.lifetime, 0.05, 20);
    prewarm_ = OptionFlag(ctx, "prewarm", true);
    point_px_ = static_cast<float>(OptionNumber(ctx, "point", point_px_, 1, 8));
    ctx.renderer->style.grid_spacing = 0.5f;
    ctx.camera->frame({0.0f, 1.5f, 0.0f}, 4.2f, 0.35f, 0.28f);
    build();
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<Fountain>(ctx); }

  void Step(double, double dt) override {
    TickWorld(world_, ctx_.settings, dt);
    step_ms_.push_back(static_cast<float>(1e3 * world_.profile().total));
    if (step_ms_.size() > 240) step_ms_.erase(step_ms_.begin());
  }

  void Draw(Renderer& r, double) override {
    // the nozzle, then every live particle as a point
    const Vec3 o = world_.pose(emitter_entity_).position;
    if (ctx_.draw.forcers) r.box(o - Vec3(0, 0.03, 0), {0.06, 0.04, 0.06}, Quat(1, 0, 0, 0), Color::hex(0x5a606b));
    DrawParticles(r, world_.particles(), ctx_.draw, point_px_, 0, 0);
    if (ctx_.settings.show_labels) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s live particles", Thousands(static_cast<long long>(world_.particles().size())).c_str());
      r.text(o + Vec3(0, -0.25, 0.6), buf, colors::white, 1.1f, 0.5f);
    }
  }

  void DrawUI() override {
    ParticleSystem& ps = world_.particles();
    EmitterDef& d = ps.emitter(emitter_);
    // live figures
    const WorldProfile& p = world_.profile();
    ImGui::Text("live particles: %s", Thousands(static_cast<long long>(ps.size())).c_str());
    ImGui::Text("emitted: %s", Thousands(ps.emitted(emitter_)).c_str());
    ImGui::Text("step: %.2f ms (%.0f M particle-steps/s)", 1e3 * p.total,
                p.total > 0 ? 1e-6 * static_cast<double>(ps.size()) / p.total : 0.0);
    ProfileReadout(world_);
    if (!step_ms_.empty()) {
      std::vector<float> xs(step_ms_.size());
      for (std::size_t i = 0; i < xs.size(); ++i) xs[i] = static_cast<float>(i);
      PlotAxes ax;
      ax.y_label = "step (ms)";
      ax.y_lo = 0;
      ax.y_hi = std::max(1.0f, 1.25f * *std::max_element(step_ms_.begin(), step_ms_.end()));
      ax.y_format = "%.1f";
      LinePlot("step", {Series(xs.data(), step_ms_.data(), static_cast<int>(xs.size()), colors::cyan, 1.5f)}, ax, 80);
    }

    // the emitter, edited live (validated by the library at the next step)
    ImGui::Spacing();
    float rate = static_cast<float>(d.rate), life = static_cast<float>(d.lifetime), speed = static_cast<float>(d.speed),
          spread = static_cast<float>(d.spread);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("rate", &rate, 0.0f, 60000.0f, "%.0f /s")) d.rate = rate;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("lifetime", &life, 0.1f, 8.0f, "%.2f s")) d.lifetime = life;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("speed", &speed, 0.5f, 16.0f, "%.1f m/s")) d.speed = speed;
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("spread", &spread, 0.0f, 1.5f, "%.2f rad")) d.spread = spread;
    ImGui::TextDisabled("steady state: rate x lifetime = %s live", Thousands(static_cast<long long>(d.rate * d.lifetime)).c_str());
    float c0[4] = {d.start_color.r, d.start_color.g, d.start_color.b, d.start_color.a};
    float c1[4] = {d.end_color.r, d.end_color.g, d.end_color.b, d.end_color.a};
    ImGui::SetNextItemWidth(-110);
    if (ImGui::ColorEdit4("colour at birth", c0, ImGuiColorEditFlags_NoInputs)) d.start_color = {c0[0], c0[1], c0[2], c0[3]};
    ImGui::SameLine();
    ImGui::SetNextItemWidth(-110);
    if (ImGui::ColorEdit4("at death", c1, ImGuiColorEditFlags_NoInputs)) d.end_color = {c1[0], c1[1], c1[2], c1[3]};
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderFloat("point size", &point_px_, 1.0f, 6.0f, "%.1f px");
    bool sparks = params_.sparks;
    if (ImGui::Checkbox("sparks", &sparks)) {
      params_.sparks = sparks;
      preset(sparks);
      build();
    }
    ImGui::SameLine();
    if (ImGui::Button("Restart empty")) {
      const bool keep = prewarm_;
      prewarm_ = false;
      sync_params(d);
      build();
      prewarm_ = keep;
    }
    ImGui::TextWrapped(
        "An emitter spawns particles into a cone at a rate, each with a lifetime and a colour blended from birth to "
        "death; dead particles are recycled without allocating. Gravity, quadratic drag and a %s ground act on "
        "them; %s. Every particle is drawn as one point.",
        params_.sparks ? "bouncy" : "sticky",
        params_.sparks ? "sparks are hot and short-lived" : "the water pools on the ground until it dies");
  }

  FiniteCheck CheckFinite() const override { return {}; }  // World::tick throws on a non-finite state
  // the birth colour shows exactly at the centre of points 3 px or larger
  std::vector<Color> ExpectedColors() const override {
    if (point_px_ < 3.0f) return {};
    return {params_.sparks ? Color::hex(0xfff2b0) : Color::hex(0x9fd4ff)};
  }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    WorldPoints(world_, out, max_points);
  }

 private:
  // defaults per mode: about 100k live either way
  void preset(bool sparks) {
    params_.rate = sparks ? 60000 : 20000;
    params_.lifetime = sparks ? 1.7 : 5;
    params_.speed = sparks ? 6.5 : 8;
    params_.spread = sparks ? 0.7 : 0.25;
    point_px_ = sparks ? 2.0f : 3.0f;
  }

  void sync_params(const EmitterDef& d) {
    params_.rate = d.rate, params_.lifetime = d.lifetime, params_.speed = d.speed, params_.spread = d.spread;
  }

  // a fresh world; prewarmed for one lifetime so the fountain starts full
  void build() {
    world_ = World(WorldDef{.particles = {.capacity = static_cast<std::size_t>(params_.rate * params_.lifetime * 1.3) + 1024}});
    emitter_entity_ = scenes::fountain(world_, params_);
    emitter_ = world_.emitter(emitter_entity_);
    step_ms_.clear();
    if (!prewarm_) return;
    const double dt = ctx_.settings.stepper.fixed_dt;
    const int ticks = static_cast<int>(std::ceil(params_.lifetime * 1.2 / dt));
    for (int i = 0; i < ticks; ++i) TickWorld(world_, ctx_.settings, dt);
  }

  scenes::FountainParams params_;
  bool prewarm_ = true;
  World world_;
  EntityId emitter_entity_;
  EmitterId emitter_;
  float point_px_ = 3.0f;
  std::vector<float> step_ms_;
};

static int reg = RegisterSample("Particles", "Fountain", Fountain::Create);

}  // namespace
}  // namespace pba::app
