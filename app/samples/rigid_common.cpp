// The rigid-body samples' shared base (see rigid_common.h).
#include "rigid_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <imgui.h>

#include "renderer.h"

namespace pba::app {

RigidSolverType RigidSolverOption(const SampleContext& ctx) {
  // the short keys, in RigidSolverType's order, or the library's names
  static constexpr const char* kKeys[] = {"soft", "si", "tgs", "xpbd"};
  const std::string solver = ctx.option("solver", "soft");
  for (std::size_t i = 0; i < kRigidSolvers.size(); ++i)
    if (solver == kKeys[i] || solver == to_string(kRigidSolvers[i])) return kRigidSolvers[i];
  throw Error("--option solver: expected soft, si, tgs or xpbd, got '" + solver + "'");
}

void RigidSolverKnobs(ContactSettings& s, int in_use) {
  static constexpr const char* kNames[] = {"soft step", "sequential impulses", "TGS", "XPBD"};
  int solver = static_cast<int>(s.solver);
  ImGui::SetNextItemWidth(-110);
  if (ImGui::Combo("solver", &solver, kNames, 4)) s.solver = static_cast<RigidSolverType>(solver);
  // each solver's own knobs (the substeps are shared by the three that substep)
  if (s.solver != RigidSolverType::SequentialImpulse) {
    ImGui::SetNextItemWidth(-110);
    // a substep count picked by hand is taken exactly (auto_substeps off)
    if (ImGui::SliderInt("substeps", &s.substeps, 1, 64)) s.auto_substeps = false;
  }
  if (s.solver == RigidSolverType::SoftStep) {
    // the count in use in the checkbox's own label: a text on the same line wrapped a character
    // a line in a narrow panel (a blank block at 640x360)
    char label[64];
    if (in_use > 0)
      std::snprintf(label, sizeof label, "adapt to the pile (%d in use)###auto_substeps", in_use);
    else
      std::snprintf(label, sizeof label, "adapt to the pile###auto_substeps");
    ImGui::Checkbox(label, &s.auto_substeps);
    if (s.auto_substeps) {
      // the halving where the bodies allow it: its sag budgets, a percentage of each body's
      // size (auto_substeps_sag_fraction, on by default) and millimetres (auto_substeps_sag);
      // each 0: none, both 0: never halved
      float percent = static_cast<float>(100 * s.auto_substeps_sag_fraction);
      ImGui::SetNextItemWidth(-110);
      if (ImGui::SliderFloat("halve: sag % size", &percent, 0, 10, percent > 0 ? "%.1f%% of size" : "off"))
        s.auto_substeps_sag_fraction = 0.01 * std::clamp(percent, 0.0f, 100.0f);
      float mm = static_cast<float>(1e3 * s.auto_substeps_sag);
      ImGui::SetNextItemWidth(-110);
      if (ImGui::SliderFloat("halve: sag mm", &mm, 0, 20, mm > 0 ? "%.1f mm" : "off"))
        s.auto_substeps_sag = 1e-3 * std::max(0.0f, mm);
      // the ladder's floor below the halving (8 -> 4 -> 3 at the default 3)
      ImGui::SetNextItemWidth(-110);
      ImGui::SliderInt("fewest substeps", &s.auto_substeps_least, 1, 64);
      s.auto_substeps_least = std::clamp(s.auto_substeps_least, 1, 64);
    }
  }
  if (s.solver == RigidSolverType::SoftStep) {
    float hz = static_cast<float>(s.contact_hertz);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("contact Hz", &hz, 5, 240, "%.0f Hz")) s.contact_hertz = hz;
  } else if (s.solver == RigidSolverType::SequentialImpulse) {
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("iterations", &s.iterations, 1, 100);
  } else {
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("iterations / substep", &s.substep_iterations, 1, 16);
  }
  if (s.solver == RigidSolverType::Tgs) {
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("relax / substep", &s.relax_iterations, 0, 16);
  }
  if (s.solver == RigidSolverType::Xpbd) {
    // compliance on a log slider, 0 (rigid) to 1e-4 m/N
    float c = static_cast<float>(s.contact_compliance);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("compliance", &c, 0.0f, 1e-4f, "%.1e m/N", ImGuiSliderFlags_Logarithmic))
      s.contact_compliance = c;
  }
  ImGui::SetNextItemWidth(-110);
  ImGui::SliderInt("manifold sweeps", &s.manifold_iterations, 1, 16);
  // XPBD's multipliers start at zero each substep: nothing to warm-start
  if (s.solver != RigidSolverType::Xpbd) ImGui::Checkbox("warm starting", &s.warm_starting);
}

bool RigidGrab::Press(RigidBodySystem& bodies, const Vec3& o, const Vec3& d, double max_distance) {
  grab_ = {};
  // the nearest shape under the cursor, of any body: a static wall or a kinematic paddle in
  // front hides what is behind it, so a press on it grabs nothing (it used to reach through
  // to the nearest dynamic body behind)
  const Ray ray{o, glm::normalize(d), max_distance};
  double best = ray.max_distance;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const RigidBodyId id = bodies.id_at(i);
    const Pose body = bodies.pose(id);
    for (const RigidShapeDef& s : bodies.shapes(id)) {
      const RayHit hit = ray_cast(s.shape, compose(body, s.local), ray);
      if (hit.hit && hit.distance < best) {
        best = hit.distance;
        grab_ = {id, apply_inverse(body, hit.point), hit.point, hit.distance};
      }
    }
  }
  // only a dynamic body can be pulled
  if (bodies.valid(grab_.body) && bodies.type(grab_.body) != BodyType::Dynamic) grab_ = {};
  if (!bodies.valid(grab_.body)) return false;
  bodies.wake(grab_.body);
  ++grabs_;
  return true;
}

void RigidGrab::Move(const RigidBodySystem& bodies, const Vec3& o, const Vec3& d) {
  if (bodies.valid(grab_.body)) grab_.target = o + grab_.depth * glm::normalize(d);
}

void RigidGrab::Apply(RigidBodySystem& bodies) const {
  if (!bodies.valid(grab_.body)) return;
  // a 3 Hz critically damped spring on the grabbed point, scaled by the body's mass and
  // capped at 50 times its weight
  const Vec3 at = apply(bodies.pose(grab_.body), grab_.local);
  const double m = bodies.mass(grab_.body), w = 2 * kPi * 3.0;
  Vec3 f = m * (w * w * (grab_.target - at) - 2 * w * bodies.velocity_at(grab_.body, at));
  const double cap = 50 * m * 9.81, len = glm::length(f);
  if (len > cap) f *= cap / len;
  bodies.apply_force(grab_.body, f, at);
}

void RigidGrab::Draw(Renderer& r, const RigidBodySystem& bodies) const {
  if (!bodies.valid(grab_.body)) return;
  const Vec3 at = apply(bodies.pose(grab_.body), grab_.local);
  r.line(at, grab_.target, colors::yellow);
  r.point(grab_.target, 8.0f, colors::yellow);
}

void WriteRigidReport(const std::string& path, const Renderer& r, long long frame, const RigidBodySystem& bodies,
                      RigidBodyId id, const RigidGrab& grab, const std::string& extra) {
  if (path.empty() || !bodies.valid(id)) return;
  const Vec3 c = bodies.center_of_mass(id), v = bodies.linear_velocity(id);
  glm::vec2 px(-1, -1);
  if (!r.project(c, &px)) px = glm::vec2(-1, -1);
  // written whole, then renamed, so a reader never sees half a line
  const std::string tmp = path + ".tmp";
  FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) return;
  std::fprintf(f, "frame %lld grabs %d held %d body %.6f %.6f %.6f pixel %.1f %.1f velocity %.6f %.6f %.6f%s%s\n", frame,
               grab.grabs(), grab.held(bodies) ? 1 : 0, c.x, c.y, c.z, px.x, px.y, v.x, v.y, v.z, extra.empty() ? "" : " ",
               extra.c_str());
  std::fclose(f);
  std::rename(tmp.c_str(), path.c_str());
}

RigidSample::RigidSample(SampleContext& ctx) : Sample(ctx) {
  settings_.solver = RigidSolverOption(ctx);
  palette_ = {colors::blue, colors::cyan, colors::purple, colors::pink, colors::green};
  draw_options_.horizontal_planes = false;  // the app draws its own ground grid
  ctx.settings.stepper.fixed_dt = 1.0 / 60.0;
  report_path_ = ctx.option("report", "");
}

void RigidSample::Restart() {
  grab_.Release();
  bodies_ = RigidBodySystem({.capacity = 1024, .contacts = settings_});
  Build();
}

void RigidSample::Step(double t, double dt) {
  bodies_.settings() = settings_;
  grab_.Apply(bodies_);
  bodies_.step(dt, gravity_);
  AfterStep(t, dt);
}

void RigidSample::Draw(Renderer& r, double) {
  draw_options_.palette = palette_;
  bodies_.draw(r, ctx_.draw, draw_options_);
  grab_.Draw(r, bodies_);
  if (++frames_ % 5 == 0 && !report_path_.empty()) {
    // the tick length, so a test sees which step rate the sample runs at
    char dt[48];
    std::snprintf(dt, sizeof dt, "dt %.9g", ctx_.settings.stepper.fixed_dt);
    const std::string extra = ReportExtra();
    WriteRigidReport(report_path_, r, frames_, bodies_, ReportBody(), grab_, extra.empty() ? dt : dt + (" " + extra));
  }
}

RigidBodyId RigidSample::ReportBody() const {
  for (std::size_t i = 0; i < bodies_.size(); ++i)
    if (bodies_.type(bodies_.id_at(i)) == BodyType::Dynamic) return bodies_.id_at(i);
  return {};
}

void RigidSample::Mouse(int button, bool down, const Vec3& o, const Vec3& d) {
  if (button != 0) return;
  if (!down) {
    grab_.Release();  // the body keeps the velocity the spring gave it: thrown
    return;
  }
  grab_.Press(bodies_, o, d);
}

void RigidSample::MouseMove(const Vec3& o, const Vec3& d) { grab_.Move(bodies_, o, d); }

FiniteCheck RigidSample::CheckFinite() const {
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const RigidBodyId id = bodies_.id_at(i);
    if (bodies_.type(id) == BodyType::Dynamic && !is_finite(bodies_.center_of_mass(id)))
      return {false, id.index, "rigid body " + std::to_string(id.index) + " '" + bodies_.name(id) + "' is not finite"};
  }
  return {};
}

void RigidSample::SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const {
  for (std::size_t i = 0; i < bodies_.size() && out.size() < max_points; ++i)
    if (bodies_.type(bodies_.id_at(i)) == BodyType::Dynamic) out.push_back(bodies_.center_of_mass(bodies_.id_at(i)));
}

bool RigidSample::SolverControls() {
  RigidSolverKnobs(settings_, bodies_.profile().substeps);
  ImGui::Checkbox("sleep", &settings_.sleep);
  ImGui::SameLine();
  const bool restart = ImGui::Button("Restart");
  if (restart) Restart();
  return restart;
}

void RigidSample::Readout() const {
  const RigidProfile& p = bodies_.profile();
  ImGui::Text("%zu bodies, %zu awake, %zu manifolds", bodies_.size(), bodies_.awake_count(), bodies_.manifold_count());
  ImGui::Text("step %.2f ms: pairs+manifolds %.2f, solve %.2f", 1e3 * p.total, 1e3 * p.collide, 1e3 * p.solve);
  ImGui::TextDisabled("drag a body with the left mouse button; release to throw it");
}

}  // namespace pba::app
