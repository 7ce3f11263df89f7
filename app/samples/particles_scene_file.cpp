// "Particles/Scene file": opens a JSON scene file (docs/scene-format.md) with
// pba::load_scene and runs it with the app's time stepping and integrator. Pick one of the
// files in scenes/, type a path, or start with `--scene FILE` (or --option file=FILE). A
// bad file shows the library's message, naming the file and the JSON path of the bad
// field, instead of a scene.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "pba/scene.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {
namespace {

namespace fs = std::filesystem;

// the scenes/ directory: under the working directory, else next to the executable or above it
fs::path FindScenesDir() {
  std::error_code ec;
  if (fs::is_directory("scenes", ec)) return fs::path("scenes");
  char self[4096];
  const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) return {};
  self[n] = '\0';
  fs::path dir = fs::path(self).parent_path();
  for (int up = 0; up < 5 && !dir.empty(); ++up, dir = dir.parent_path()) {
    if (fs::is_directory(dir / "scenes", ec)) return dir / "scenes";
    if (dir == dir.parent_path()) break;
  }
  return {};
}

// the .json files of a directory, sorted
std::vector<fs::path> SceneFiles(const fs::path& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  if (dir.empty() || !fs::is_directory(dir, ec)) return out;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && e.path().extension() == ".json") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

class SceneFile final : public Sample {
 public:
  explicit SceneFile(SampleContext& ctx) : Sample(ctx) {
    dir_ = FindScenesDir();
    files_ = SceneFiles(dir_);
    // the file: --option file=..., else the last one opened, else sparks.json
    std::string file = ctx.option("file", "");
    if (!file.empty() && !options_read_) g_file = file;
    options_read_ = true;
    if (g_file.empty()) {
      g_file = files_.empty() ? "scenes/sparks.json" : files_.front().string();
      for (const fs::path& f : files_)
        if (f.filename() == "sparks.json") g_file = f.string();
    }
    std::snprintf(path_, sizeof path_, "%s", g_file.c_str());
    ctx.renderer->style.grid_spacing = 0.5f;
    load(g_file, true);
  }
  static std::unique_ptr<Sample> Create(SampleContext& ctx) { return std::make_unique<SceneFile>(ctx); }

  void Step(double, double dt) override {
    if (scene_) TickWorld(scene_->world, ctx_.settings, dt);
  }

  void Draw(Renderer& r, double) override {
    if (!scene_) {
      // the error, in the view too
      const Vec3 at(ctx_.camera->target);
      r.text(at + Vec3(0, 0.3, 0), "could not open the scene file:", colors::red, 1.2f, 0.5f);
      r.text(at, error_, colors::red, 1.0f, 0.5f);
      return;
    }
    const World& w = scene_->world;
    DrawColliders(r, w.colliders(), {}, ctx_.draw_flags);
    for (const Forcer& f : w.forcers()) DrawForcer(r, f, w.time());
    DrawParticles(r, w.particles(), 3.0f, 0.008 * view_radius_);
  }

  void DrawUI() override {
    // pick a file from scenes/, or type a path
    const std::string current = fs::path(g_file).filename().string();
    ImGui::SetNextItemWidth(-70);
    if (ImGui::BeginCombo("scenes/", current.c_str())) {
      for (const fs::path& f : files_)
        if (ImGui::Selectable(f.filename().c_str(), f.string() == g_file)) {
          std::snprintf(path_, sizeof path_, "%s", f.string().c_str());
          load(f.string(), true);
        }
      ImGui::EndCombo();
    }
    ImGui::SetNextItemWidth(-70);
    const bool enter = ImGui::InputText("file", path_, sizeof path_, ImGuiInputTextFlags_EnterReturnsTrue);
    if (ImGui::Button("Open") || enter) load(path_, true);
    ImGui::SameLine();
    if (ImGui::Button("Reload")) load(g_file, false);
    ImGui::SameLine();
    if (ImGui::Button("Frame")) frame_camera();

    ImGui::Spacing();
    if (!scene_) {
      ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(1.0f, 0.45f, 0.42f, 1.0f));
      ImGui::TextWrapped("%s", error_.c_str());
      ImGui::PopStyleColor();
      ImGui::TextWrapped("The file is checked field by field; the message names the file, the JSON path of the "
                         "first bad field and what is wrong. See docs/scene-format.md.");
      return;
    }
    const World& w = scene_->world;
    ImGui::Text("%s", scene_->name.c_str());
    if (!scene_->description.empty()) ImGui::TextWrapped("%s", scene_->description.c_str());
    ImGui::Text("entities %zu, colliders %zu, forcers %zu, emitters %zu", w.entity_count(), w.colliders().size(),
                w.forcers().size(), w.particles().emitter_count());
    ImGui::Text("live particles: %s", Thousands(static_cast<long long>(w.particles().size())).c_str());
    ImGui::Text("t = %.2f s, %lld ticks", w.time(), w.ticks());
    ProfileReadout(w);
    ImGui::TextWrapped("The file's dt and integrator were copied to the Simulation panel when it was opened; change "
                       "them there. Reload starts the scene again.");
  }

  std::vector<Color> ExpectedColors() const override { return {}; }

 private:
  static inline std::string g_file;          // survives a restart (R) and a sample switch
  static inline bool options_read_ = false;  // --option file applies to the first load only

  void load(const std::string& file, bool adopt_settings) {
    g_file = file;
    scene_.reset();
    error_.clear();
    try {
      scene_ = std::make_unique<Scene>(load_scene(file));
    } catch (const std::exception& e) {
      error_ = e.what();
      std::fprintf(stderr, "pba_samples: Particles/Scene file: %s\n", error_.c_str());
      return;
    }
    // the file's step and integrator become the app's (the panel can change them)
    if (adopt_settings) {
      ctx_.settings.stepper.fixed_dt = scene_->world.stepper().settings().fixed_dt;
      ctx_.settings.method = scene_->world.particles().method();
    }
    frame_camera();
  }

  // frame what the scene shows in its first seconds: a second copy runs ahead for 2 s
  void frame_camera() {
    Vec3 lo(1e30), hi(-1e30);
    auto grow = [&](const Vec3& p) { lo = glm::min(lo, p), hi = glm::max(hi, p); };
    try {
      Scene preview = load_scene(g_file);
      World& w = preview.world;
      const double dt = w.stepper().settings().fixed_dt;
      for (int i = 0; i <= 240 && i * dt <= 2.0; ++i) {
        const ParticleSystem& ps = w.particles();
        const std::size_t step = std::max<std::size_t>(1, ps.size() / 2000);
        for (std::size_t k = 0; k < ps.size(); k += step) grow(ps.position(k));
        for (const Collider& c : w.colliders())
          if (c.shape.type != ShapeType::Plane) grow(c.end.position);
        for (const Forcer& f : w.forcers()) grow(f.pose.position);
        if (i % 20 == 0 && ps.size() == 0 && w.colliders().empty()) break;
        w.tick(w.time(), dt);
      }
    } catch (const std::exception&) {
      // a scene that fails while running still gets a default view
    }
    if (lo.x > hi.x) lo = Vec3(-2, 0, -2), hi = Vec3(2, 2, 2);
    lo.y = std::min(lo.y, 0.0);
    const Vec3 c = 0.5 * (lo + hi);
    view_radius_ = std::clamp(0.6 * glm::length(hi - lo), 1.5, 200.0);
    ctx_.camera->frame(glm::vec3(c), static_cast<float>(view_radius_), 0.3f, 0.3f);
  }

  fs::path dir_;
  std::vector<fs::path> files_;
  char path_[1024] = {};
  std::unique_ptr<Scene> scene_;
  std::string error_;
  double view_radius_ = 3;
};

static int reg = RegisterSample("Particles", "Scene file", SceneFile::Create);

}  // namespace
}  // namespace pba::app
