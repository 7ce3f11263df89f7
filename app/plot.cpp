// Line plot with a frame, grid lines, tick labels and clipped curves.
#include "plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <imgui.h>

namespace pba::app {

namespace {
ImU32 u32(Color c) { return ImGui::ColorConvertFloat4ToU32(ImVec4(c.r, c.g, c.b, c.a)); }
}  // namespace

void LinePlot(const char* id, const std::vector<PlotSeries>& series, const PlotAxes& axes, float height) {
  ImGui::PushID(id);
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  const float width = std::max(ImGui::GetContentRegionAvail().x, 50.0f);
  ImGui::InvisibleButton("plot", ImVec2(width, height));
  ImDrawList* dl = ImGui::GetWindowDrawList();

  // fit the ranges that were left open
  float x_lo = axes.x_lo, x_hi = axes.x_hi, y_lo = axes.y_lo, y_hi = axes.y_hi;
  const bool fit_x = !(x_hi > x_lo), fit_y = !(y_hi > y_lo);
  if (fit_x) x_lo = 1e30f, x_hi = -1e30f;
  if (fit_y) y_lo = 1e30f, y_hi = -1e30f;
  for (const PlotSeries& s : series)
    for (int i = 0; i < s.count; ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      if (fit_x) x_lo = std::min(x_lo, s.x[i]), x_hi = std::max(x_hi, s.x[i]);
      if (fit_y) y_lo = std::min(y_lo, s.y[i]), y_hi = std::max(y_hi, s.y[i]);
    }
  if (fit_x && !(x_hi > x_lo)) x_lo = 0, x_hi = 1;
  if (fit_y) {
    if (y_lo > y_hi) y_lo = 0, y_hi = 1;
    if (axes.y_include_zero) y_lo = std::min(y_lo, 0.0f), y_hi = std::max(y_hi, 0.0f);
    y_lo = std::max(y_lo, axes.y_clamp_lo);
    y_hi = std::min(y_hi, axes.y_clamp_hi);
    if (y_hi - y_lo < axes.y_min_span) {
      const float c = 0.5f * (y_lo + y_hi);
      y_lo = c - 0.5f * axes.y_min_span, y_hi = c + 0.5f * axes.y_min_span;
    }
    const float pad = 0.08f * (y_hi - y_lo);
    y_lo -= pad, y_hi += pad;
  }

  // frame: room on the left for tick labels, below for the x label
  const float left = 52.0f, bottom = axes.x_label.empty() ? 4.0f : 16.0f;
  const ImVec2 p0(origin.x + left, origin.y + 4.0f);
  const ImVec2 p1(origin.x + width - 4.0f, origin.y + height - bottom);
  dl->AddRectFilled(p0, p1, IM_COL32(24, 26, 30, 230), 3.0f);
  auto sx = [&](float x) { return p0.x + (x - x_lo) / (x_hi - x_lo) * (p1.x - p0.x); };
  auto sy = [&](float y) { return p1.y - (y - y_lo) / (y_hi - y_lo) * (p1.y - p0.y); };

  // horizontal grid lines with labels at 5 levels
  char buf[32];
  for (int k = 0; k <= 4; ++k) {
    const float y = y_lo + (y_hi - y_lo) * k / 4.0f;
    const float py = sy(y);
    dl->AddLine(ImVec2(p0.x, py), ImVec2(p1.x, py), IM_COL32(255, 255, 255, k == 0 || k == 4 ? 40 : 22));
    std::snprintf(buf, sizeof buf, axes.y_format, y);
    const ImVec2 ts = ImGui::CalcTextSize(buf);
    dl->AddText(ImVec2(p0.x - ts.x - 4.0f, py - 0.5f * ts.y), IM_COL32(200, 204, 210, 255), buf);
  }
  // zero line when in range
  if (y_lo < 0 && y_hi > 0) dl->AddLine(ImVec2(p0.x, sy(0)), ImVec2(p1.x, sy(0)), IM_COL32(255, 255, 255, 70));

  // curves, clipped to the frame
  dl->PushClipRect(p0, p1, true);
  for (const PlotSeries& s : series) {
    const ImU32 c = u32(s.color);
    bool have_prev = false;
    ImVec2 prev;
    for (int i = 0; i < s.count; ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) {
        have_prev = false;
        continue;
      }
      // keep far-off values near the frame so the segment direction survives clipping
      const float yv = std::clamp(s.y[i], y_lo - 10 * (y_hi - y_lo), y_hi + 10 * (y_hi - y_lo));
      const ImVec2 p(sx(s.x[i]), sy(yv));
      if (have_prev) dl->AddLine(prev, p, c, s.width);
      prev = p;
      have_prev = true;
    }
  }
  dl->PopClipRect();

  // axis labels
  if (!axes.x_label.empty()) {
    std::snprintf(buf, sizeof buf, "%.3g", x_lo);
    dl->AddText(ImVec2(p0.x, p1.y + 1), IM_COL32(160, 164, 170, 255), buf);
    std::snprintf(buf, sizeof buf, "%.3g", x_hi);
    const ImVec2 ts = ImGui::CalcTextSize(buf);
    dl->AddText(ImVec2(p1.x - ts.x, p1.y + 1), IM_COL32(160, 164, 170, 255), buf);
    const ImVec2 ls = ImGui::CalcTextSize(axes.x_label.c_str());
    dl->AddText(ImVec2(0.5f * (p0.x + p1.x - ls.x), p1.y + 1), IM_COL32(160, 164, 170, 255), axes.x_label.c_str());
  }
  if (!axes.y_label.empty())
    dl->AddText(ImVec2(p0.x + 6, p0.y + 2), IM_COL32(200, 204, 210, 200), axes.y_label.c_str());
  ImGui::PopID();
}

}  // namespace pba::app
