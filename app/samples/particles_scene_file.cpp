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

#include <glm/gtx/quaternion.hpp>

#include <unistd.h>

#include <imgui.h>

#include "camera.h"
#include "particles_common.h"
#include "soft_common.h"
#include "pba/scene.h"
#include "pba/soft.h"
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
      // the error, in the view too: wrapped inside the region the panels leave free
      DrawMessage("could not open the scene file:", error_);
      return;
    }
    const World& w = scene_->world;
    const DrawFlags& f = ctx_.draw;
    DrawColliders(r, w.colliders(), {}, f);
    DrawRigidBodies(r, w, f);
    if (f.forcers)
      for (const Forcer& fc : w.forcers()) DrawForcer(r, fc, w.time(), f);
    DrawParticles(r, w.particles(), f, 3.0f, 0.008 * view_radius_);
    // the soft bodies: cloth and jelly as shaded surfaces, ropes and springs as links and nodes
    if (const SoftSystem* soft = Soft(w))
      for (std::size_t b = 0; b < soft->size(); ++b) DrawSoftBody(r, soft->at(b), b, f);
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
    // the entities' rigid bodies (the colliders' stand-ins are static or kinematic, never awake)
    std::size_t bodies = 0;
    for (std::size_t i = 0; i < w.rigid().size(); ++i) bodies += w.valid(w.rigid().id_at(i));
    if (bodies > 0)
      ImGui::Text("rigid bodies: %zu, %zu awake (%s)", bodies, w.rigid().awake_count(),
                  std::string(to_string(w.rigid().settings().solver)).c_str());
    ImGui::Text("t = %.2f s, %lld ticks", w.time(), w.ticks());
    ProfileReadout(w);
    ImGui::TextWrapped("The file's dt and integrator were copied to the Simulation panel when it was opened; change "
                       "them there. Reload starts the scene again.");
  }

  std::vector<Color> ExpectedColors() const override { return {}; }
  std::string LoadError() const override { return scene_ ? std::string() : error_; }

  bool OpenFile(const std::string& path) override {
    // a scene file dropped on the window opens here; anything else is not ours
    if (fs::path(path).extension() != ".json") return false;
    std::snprintf(path_, sizeof path_, "%s", path.c_str());
    load(path, true);
    return true;
  }

  void SimulatedPoints(std::vector<Vec3>& out, std::size_t max_points) const override {
    if (scene_) WorldPoints(scene_->world, out, max_points);
  }

 private:
  static inline std::string g_file;          // survives a restart (R) and a sample switch
  static inline bool options_read_ = false;  // --option file applies to the first load only

  // the world's soft bodies, if it has any
  static const SoftSystem* Soft(const World& w) {
    return dynamic_cast<const SoftSystem*>(w.find_system(SoftSystem::kName));
  }

  // soft body `index` as the flags say: a surface when it has triangles (jelly green with
  // tets, cloth blue without), else its stretch links as thin lit sticks (constraints) and its
  // nodes as spheres (particles), sized from its mean link length
  void DrawSoftBody(Renderer& r, const SoftBody& b, std::size_t index, const DrawFlags& f) {
    if (b.size() == 0) return;
    // ropes and springs: one colour per body, so side-by-side bodies tell apart
    static constexpr Color kLinkColors[] = {soft_colors::fabric, colors::cyan, colors::green, colors::purple};
    const Color color = kLinkColors[index % 4];
    if (!b.triangles().empty()) {
      SoftView v;
      v.edges = false;
      v.strain = false;
      painter_.Draw(r, b, v, b.tets().empty() ? soft_colors::cloth : soft_colors::jelly);
      return;
    }
    double mean = 0;
    std::size_t links = 0;
    for (std::size_t c = 0; c < b.constraint_count(); ++c) {
      const SoftConstraint k = b.constraint(c);
      if (k.kind == SoftConstraintKind::Stretch) mean += k.rest_length, ++links;
    }
    mean = links ? mean / links : 0.1 * view_radius_;
    const double stick = std::clamp(0.06 * mean, 0.002 * view_radius_, 0.006 * view_radius_);
    const double node = std::clamp(0.35 * mean, 0.006 * view_radius_, 0.04 * view_radius_);
    if (f.constraints)
      for (std::size_t c = 0; c < b.constraint_count(); ++c) {
        const SoftConstraint k = b.constraint(c);
        if (k.broken || k.kind != SoftConstraintKind::Stretch) continue;
        const Vec3 p = b.position(k.a), q = b.position(k.b);
        const double len = glm::length(q - p);
        if (!(len > 1e-9)) continue;
        r.box(0.5 * (p + q), Vec3(stick, 0.5 * len, stick), glm::rotation(Vec3(0, 1, 0), (q - p) / len), color);
      }
    if (f.particles)
      for (std::size_t i = 0; i < b.size(); ++i) {
        if (b.is_pinned(i)) r.box(b.position(i), Vec3(1.2 * node), Quat(1, 0, 0, 0), soft_colors::pole);
        else r.sphere(b.position(i), node, color);
      }
  }

  // a message (title and wrapped text) centred in the region the panels leave free
  void DrawMessage(const char* title, const std::string& text) const {
    if (!ImGui::GetCurrentContext()) return;
    ImDrawList* dl = ImGui::GetBackgroundDrawList();
    const ScreenRect& v = ctx_.view;
    const float wrap = std::max(120.0f, v.width() - 48);
    const ImVec2 ts = ImGui::CalcTextSize(title), tm = ImGui::CalcTextSize(text.c_str(), nullptr, false, wrap);
    const float wbox = std::max(ts.x, tm.x), hbox = ts.y + 6 + tm.y;
    const ImVec2 p(v.center_x() - 0.5f * wbox, v.y0 + 0.45f * v.height() - 0.5f * hbox);
    dl->AddRectFilled(ImVec2(p.x - 10, p.y - 8), ImVec2(p.x + wbox + 10, p.y + hbox + 8), IM_COL32(20, 22, 26, 215), 4);
    const ImU32 red = ImGui::ColorConvertFloat4ToU32(ImVec4(colors::red.r, colors::red.g, colors::red.b, 1));
    dl->AddText(p, red, title);
    dl->AddText(ImGui::GetFont(), ImGui::GetFontSize(), ImVec2(p.x, p.y + ts.y + 6), red, text.c_str(), nullptr, wrap);
  }

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
    // say what opened (a dropped file has no other echo)
    std::printf("pba_samples: Particles/Scene file: opened %s\n", fs::absolute(file).lexically_normal().c_str());
    std::fflush(stdout);
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
        for (const Collider& c : w.body_colliders())
          if (c.shape.type != ShapeType::Plane) grow(c.end.position);
        std::size_t soft_nodes = 0;
        if (const SoftSystem* soft = Soft(w))
          for (std::size_t b = 0; b < soft->size(); ++b) {
            const SoftBody& body = soft->at(b);
            soft_nodes += body.size();
            for (std::size_t k = 0; k < body.size(); k += std::max<std::size_t>(1, body.size() / 500))
              grow(body.position(k));
          }
        if (i % 20 == 0 && ps.size() == 0 && soft_nodes == 0 && w.colliders().empty()) break;
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
  SoftPainter painter_;
};

static int reg = RegisterSample("Particles", "Scene file", SceneFile::Create);

}  // namespace
}  // namespace pba::app
