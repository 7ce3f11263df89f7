// ImGui panels of the samples app.
#include "ui.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>

#include <imgui.h>

#include "plot.h"

namespace pba::app {

void History::push(float v) {
  values[next] = v;
  next = (next + 1) % kSize;
  count = std::min(count + 1, kSize);
}

int History::ordered(float* out) const {
  const int start = count < kSize ? 0 : next;
  for (int i = 0; i < count; ++i) out[i] = values[(start + i) % kSize];
  return count;
}

float History::mean() const {
  if (!count) return 0;
  float s = 0;
  for (int i = 0; i < count; ++i) s += values[i];
  return s / count;
}

float History::max() const {
  float m = 0;
  for (int i = 0; i < count; ++i) m = std::max(m, values[i]);
  return m;
}

void PanelWidths(const UiState& ui, const Settings& s, float width, float* left, float* right) {
  if (!s.show_ui) {
    *left = *right = 0;
    return;
  }
  // shrink the panels on small windows so the view keeps at least half the width
  const float k = std::min(1.0f, 0.5f * width / (ui.left_width + ui.right_width));
  *left = ui.left_width * k;
  *right = ui.right_width * k;
}

ScreenRect ViewRegion(const UiState& ui, const Settings& s, float width, float height) {
  float left = 0, right = 0;
  PanelWidths(ui, s, width, &left, &right);
  ScreenRect r;
  r.x0 = left;
  r.x1 = std::max(left + 1, width - right);
  r.y0 = s.show_ui ? ui.menu_height : 0;
  r.y1 = std::max(r.y0 + 1, height);
  return r;
}

namespace {

bool contains_ci(const std::string& hay, const char* needle) {
  std::string h = hay, n = needle;
  for (char& c : h) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return h.find(n) != std::string::npos;
}

// the samples menu: a search box, then the categories (or the matches when searching)
void samples_menu(UiState& ui, const UiFrame& f, UiActions& act) {
  if (!ImGui::BeginMenu("Samples")) return;
  if (ImGui::IsWindowAppearing()) ImGui::SetKeyboardFocusHere();
  ImGui::SetNextItemWidth(220);
  ImGui::InputTextWithHint("##search", "search", ui.search, sizeof ui.search);
  ImGui::Separator();
  const auto all = Samples();
  if (ui.search[0]) {
    for (std::size_t i = 0; i < all.size(); ++i)
      if (contains_ci(all[i].full_name(), ui.search) &&
          ImGui::MenuItem(all[i].full_name().c_str(), nullptr, static_cast<int>(i) == f.sample_index))
        act.select = static_cast<int>(i);
  } else {
    std::size_t i = 0;
    while (i < all.size()) {
      const std::string& cat = all[i].category;
      std::size_t j = i;
      while (j < all.size() && all[j].category == cat) ++j;
      if (ImGui::BeginMenu(cat.c_str())) {
        for (std::size_t k = i; k < j; ++k)
          if (ImGui::MenuItem(all[k].name.c_str(), nullptr, static_cast<int>(k) == f.sample_index))
            act.select = static_cast<int>(k);
        ImGui::EndMenu();
      }
      i = j;
    }
  }
  ImGui::EndMenu();
}

// the time-stepping and integrator settings
void simulation_panel(SampleContext& ctx, const UiFrame& f, UiActions& act) {
  Settings& s = ctx.settings;
  // run controls
  // three buttons sharing the panel's width
  const float bw = (ImGui::GetContentRegionAvail().x - 2 * ImGui::GetStyle().ItemSpacing.x) / 3;
  if (ImGui::Button(s.paused ? "Run (P)" : "Pause (P)", ImVec2(bw, 0))) s.paused = !s.paused;
  ImGui::SameLine();
  if (ImGui::Button("Step (O)", ImVec2(bw, 0))) s.paused = true, s.single_step = true;
  ImGui::SameLine();
  if (ImGui::Button("Restart (R)", ImVec2(-1, 0))) act.restart = true;

  const bool own = f.sample && f.sample->OwnsTime();
  if (own) ImGui::TextDisabled("this sample runs its own steppers");
  ImGui::BeginDisabled(own);
  // strategy
  StepperSettings& st = s.stepper;
  ImGui::SetNextItemWidth(-90);
  if (ImGui::BeginCombo("strategy", std::string(strategy_name(st.strategy)).c_str())) {
    for (Strategy k : kStrategies) {
      if (ImGui::Selectable(std::string(strategy_name(k)).c_str(), k == st.strategy)) st.strategy = k;
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", std::string(strategy_description(k)).c_str());
    }
    ImGui::EndCombo();
  }
  // step rate as Hz, stored as fixed_dt
  float hz = static_cast<float>(1.0 / st.fixed_dt);
  ImGui::SetNextItemWidth(-90);
  if (ImGui::SliderFloat("step rate", &hz, 5.0f, 1000.0f, "%.0f Hz", ImGuiSliderFlags_Logarithmic))
    st.fixed_dt = 1.0 / std::clamp(hz, 1.0f, 100000.0f);
  if (st.strategy == Strategy::PerFrame) {
    ImGui::SetNextItemWidth(-90);
    ImGui::SliderInt("ticks/frame", &st.ticks_per_frame, 1, 64);
  }
  if (st.strategy == Strategy::MaxStep) {
    float max_ms = static_cast<float>(st.max_dt * 1000);
    ImGui::SetNextItemWidth(-90);
    if (ImGui::SliderFloat("max dt", &max_ms, 0.1f, 100.0f, "%.2f ms", ImGuiSliderFlags_Logarithmic))
      st.max_dt = std::max(max_ms, 0.001f) / 1000.0;
  }
  ImGui::SetNextItemWidth(-90);
  ImGui::SliderInt("substeps", &s.substeps, 1, 32);
  s.substeps = std::clamp(s.substeps, 1, 1000);
  ImGui::EndDisabled();
  // integrator (used by samples that run their own steppers, too; not by the rigid bodies')
  if (!f.sample || f.sample->UsesIntegrator()) {
    ImGui::SetNextItemWidth(-90);
    if (ImGui::BeginCombo("integrator", std::string(label(s.method)).c_str())) {
      for (Method m : kAllMethods)
        if (ImGui::Selectable(std::string(label(m)).c_str(), m == s.method)) s.method = m;
      ImGui::EndCombo();
    }
  }
  ImGui::BeginDisabled(own);
  float scale = static_cast<float>(st.time_scale);
  ImGui::SetNextItemWidth(-90);
  if (ImGui::SliderFloat("time scale", &scale, 0.05f, 4.0f, "%.2fx", ImGuiSliderFlags_Logarithmic))
    st.time_scale = std::clamp(scale, 0.01f, 1000.0f);
  // stall guard
  if (ImGui::TreeNode("stall guard")) {
    ImGui::SetNextItemWidth(-110);
    ImGui::SliderInt("max ticks/frame", &st.max_ticks_per_frame, 1, 1000, "%d", ImGuiSliderFlags_Logarithmic);
    float mf = static_cast<float>(st.max_frame_dt * 1000);
    ImGui::SetNextItemWidth(-110);
    if (ImGui::SliderFloat("max frame", &mf, 10.0f, 2000.0f, "%.0f ms", ImGuiSliderFlags_Logarithmic))
      st.max_frame_dt = std::max(mf, 1.0f) / 1000.0;
    ImGui::TreePop();
  }
  ImGui::EndDisabled();
}

// frame time, physics time per step, ticks per frame and dropped time, with histories
void profiler_panel(UiState& ui, const UiFrame& f) {
  const PhysicsReadout& p = *f.physics;
  float buf[History::kSize];
  auto row = [&](const char* name, const History& h, const char* unit, float now) {
    const int n = h.ordered(buf);
    char overlay[64];
    std::snprintf(overlay, sizeof overlay, "%s %.2f %s (max %.2f)", name, now, unit, h.max());
    ImGui::PlotLines("##p", buf, n, 0, overlay, 0.0f, std::max(h.max() * 1.15f, 1e-3f),
                     ImVec2(ImGui::GetContentRegionAvail().x, 34));
  };
  ImGui::PushID("frame");
  row("frame", ui.frame_ms, "ms", static_cast<float>(f.frame_dt * 1000));
  ImGui::PopID();
  if (f.sample && f.sample->OwnsTime()) {
    ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
    ImGui::TextWrapped("this sample shows its physics timing in its own panel");
    ImGui::PopStyleColor();
    return;
  }
  ImGui::PushID("phys");
  row("physics", ui.physics_ms, "ms", ui.physics_ms.count ? ui.physics_ms.values[(ui.physics_ms.next + History::kSize - 1) % History::kSize] : 0);
  ImGui::PopID();
  ImGui::PushID("ticks");
  row("ticks/frame", ui.ticks, "", static_cast<float>(p.ticks));
  ImGui::PopID();
  ImGui::PushID("drop");
  row("dropped", ui.dropped_ms, "ms", static_cast<float>(p.dropped * 1000));
  ImGui::PopID();
  ImGui::Text("tick %.2f ms, median wall %.2f ms", p.tick_dt * 1000, p.tick_wall * 1000);
  ImGui::Text("sim time %.2f s, dropped %.3f s", p.sim_time, p.dropped_total);
  if (p.lag > 0) ImGui::Text("thread lag %.1f ms", p.lag * 1000);
  if (f.draw)
    ImGui::TextDisabled("%d solids, %d triangles, %d lines, %d points, %d labels", f.draw->solids,
                        f.draw->triangles, f.draw->lines, f.draw->points, f.draw->labels);
}

}  // namespace

UiActions DrawUi(UiState& ui, SampleContext& ctx, const UiFrame& f) {
  UiActions act;
  Settings& s = ctx.settings;
  const ImGuiIO& io = ImGui::GetIO();
  const auto all = Samples();
  const int n = static_cast<int>(all.size());

  // menu bar: picker, previous / next, view toggles
  float menu_h = 0;
  if (ImGui::BeginMainMenuBar()) {
    samples_menu(ui, f, act);
    if (ImGui::BeginMenu("View")) {
      ImGui::MenuItem("Panels", "F1", &s.show_ui);
      ImGui::MenuItem("Labels", nullptr, &s.show_labels);
      ImGui::MenuItem("Ground grid", nullptr, &s.show_grid);
      ImGui::MenuItem("Profiler", nullptr, &s.show_profiler);
      if (ImGui::MenuItem("Screenshot", "F12")) act.screenshot = true;
      // the debug-draw toggles every sample reads (pba::DrawFlags)
      ImGui::Separator();
      ImGui::TextDisabled("debug draw");
      DrawFlags& d = ctx.draw;
      ImGui::MenuItem("Shapes", nullptr, &d.shapes);
      ImGui::MenuItem("Bounding boxes", nullptr, &d.aabbs);
      ImGui::MenuItem("Broad-phase tree", nullptr, &d.tree);
      ImGui::MenuItem("Contact points", nullptr, &d.contacts);
      ImGui::MenuItem("Contact normals", nullptr, &d.normals);
      ImGui::MenuItem("Particles", nullptr, &d.particles);
      ImGui::MenuItem("Forcers and emitters", nullptr, &d.forcers);
      ImGui::MenuItem("Constraints", nullptr, &d.constraints);
      ImGui::EndMenu();
    }
    if (ImGui::MenuItem("Quit", "Esc")) act.quit = true;
    ImGui::Separator();
    if (ImGui::SmallButton("<")) act.select = (f.sample_index + n - 1) % n;
    ImGui::SameLine();
    if (ImGui::SmallButton(">")) act.select = (f.sample_index + 1) % n;
    ImGui::SameLine();
    ImGui::Text("%s", all[f.sample_index].full_name().c_str());
    if (s.paused) {
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(1.0f, 0.77f, 0.24f, 1.0f), "  PAUSED");
    }
    if (!ui.status.empty() && ImGui::GetTime() < ui.status_until) {
      ImGui::SameLine();
      ImGui::TextDisabled("  %s", ui.status.c_str());
    }
    menu_h = ImGui::GetWindowSize().y;
    ui.menu_height = menu_h;
    ImGui::EndMainMenuBar();
  }

  float left = 0, right = 0;
  PanelWidths(ui, s, io.DisplaySize.x, &left, &right);
  const float pad = 6;

  // left: simulation settings and profiler
  ImGui::SetNextWindowPos(ImVec2(pad, menu_h + pad), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(left - pad, io.DisplaySize.y - menu_h - 2 * pad), ImGuiCond_Always);
  ImGui::Begin("Simulation", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoTitleBar);
  ImGui::PushItemWidth(-1);
  // text wraps at the panel's edge instead of being cut off
  ImGui::PushTextWrapPos(0.0f);
  if (ImGui::CollapsingHeader("Simulation", ImGuiTreeNodeFlags_DefaultOpen)) simulation_panel(ctx, f, act);
  if (s.show_profiler && ImGui::CollapsingHeader("Profiler", ImGuiTreeNodeFlags_DefaultOpen)) profiler_panel(ui, f);
  if (!f.headless && ImGui::CollapsingHeader("Controls")) {
    ImGui::TextWrapped("P or Space pause, O step, R restart, [ ] or PgUp/PgDn previous/next sample, F1 panels, "
                       "F12 screenshot, Esc close the menu or quit.");
    ImGui::TextWrapped("Left-drag orbit, right/middle-drag or shift+left pan, wheel zoom.");
    ImGui::TextWrapped("Drop a scene file (.json) on the window to open it.");
  }
  ImGui::PopTextWrapPos();
  ImGui::PopItemWidth();
  ImGui::End();

  // right: the sample's own panel
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - right, menu_h + pad), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(right - pad, io.DisplaySize.y - menu_h - 2 * pad), ImGuiCond_Always);
  ImGui::Begin(all[f.sample_index].name.c_str(), nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::PushTextWrapPos(0.0f);
  if (f.sample) f.sample->DrawUI();
  ImGui::PopTextWrapPos();
  ImGui::End();
  return act;
}

UiActions DrawDiverged(const std::string& message, bool headless, const ScreenRect& view) {
  UiActions act;
  // centred in the free region and no wider than it
  ImGui::SetNextWindowPos(ImVec2(view.center_x(), view.y0 + 0.4f * view.height()), ImGuiCond_Always,
                          ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(std::clamp(view.width() - 24, 160.0f, 560.0f), 0), ImGuiCond_Always);
  ImGui::PushStyleColor(ImGuiCol_WindowBg, ImVec4(0.35f, 0.08f, 0.09f, 0.95f));
  ImGui::Begin("Simulation stopped", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::TextWrapped("The state became non-finite, so the simulation is paused instead of drawing garbage:");
  ImGui::Spacing();
  ImGui::TextWrapped("%s", message.c_str());
  ImGui::Spacing();
  if (!headless) {
    ImGui::TextWrapped("Try a smaller step (higher step rate), more substeps or another integrator.");
    if (ImGui::Button("Restart (R)")) act.restart = true;
  }
  ImGui::End();
  ImGui::PopStyleColor();
  return act;
}

}  // namespace pba::app
