// Line plot with a frame, grid lines, tick labels (linear or decades), clipped curves,
// markers, tags and a legend.
#include "plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <imgui.h>

namespace pba::app {

namespace {
ImU32 u32(Color c) { return ImGui::ColorConvertFloat4ToU32(ImVec4(c.r, c.g, c.b, c.a)); }

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// a decade's label: 1e-3, 0.1, 1, 10, 100, 1e3
void decade_label(int e, char* buf, std::size_t n) {
  if (e >= -1 && e <= 2) std::snprintf(buf, n, "%g", std::pow(10.0, e));
  else std::snprintf(buf, n, "1e%d", e);
}

// the smallest label stride (in decades) that keeps labels `need_px` apart
int decade_stride(float px_per_decade, float need_px) {
  int stride = 1;
  while (stride * px_per_decade < need_px && stride < 64) ++stride;
  return stride;
}

// a fitted log range: whole decades around the data, at least one decade wide
void snap_decades(float* lo, float* hi) {
  *lo = std::floor(*lo + 0.02f);
  *hi = std::ceil(*hi - 0.02f);
  if (*hi <= *lo) *hi = *lo + 1;
}

}  // namespace

void LinePlot(const char* id, const std::vector<PlotSeries>& series, const PlotAxes& axes, float height) {
  ImGui::PushID(id);
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  const float width = std::max(ImGui::GetContentRegionAvail().x, 50.0f);
  const float line_h = ImGui::GetTextLineHeight();

  // a legend below the plot flows in rows: where each entry goes
  const float sample_w = 14, pad = 4, gap = 12;
  std::vector<ImVec2> below;  // entry offsets from the legend's top-left, per labelled series
  float below_h = 0;
  if (axes.legend == PlotCorner::Below) {
    float x = 0, y = 0;
    for (const PlotSeries& s : series) {
      if (s.label.empty()) continue;
      const float w = sample_w + pad + ImGui::CalcTextSize(s.label.c_str()).x;
      if (x > 0 && x + w > width - 52.0f) x = 0, y += line_h;
      below.emplace_back(x, y);
      x += w + gap;
    }
    if (!below.empty()) below_h = y + line_h + 2;
  }
  ImGui::InvisibleButton("plot", ImVec2(width, height + below_h));
  ImDrawList* dl = ImGui::GetWindowDrawList();

  // data to plot space: log10 on log axes, where values <= 0 have no place
  auto tx = [&](float x) { return axes.x_log ? (x > 0 ? std::log10(x) : kNaN) : x; };
  auto ty = [&](float y) { return axes.y_log ? (y > 0 ? std::log10(y) : kNaN) : y; };

  // fit the ranges that were left open
  float x_lo = tx(axes.x_lo), x_hi = tx(axes.x_hi), y_lo = ty(axes.y_lo), y_hi = ty(axes.y_hi);
  const bool fit_x = !(x_hi > x_lo), fit_y = !(y_hi > y_lo);
  if (fit_x) x_lo = 1e30f, x_hi = -1e30f;
  if (fit_y) y_lo = 1e30f, y_hi = -1e30f;
  for (const PlotSeries& s : series)
    for (int i = 0; i < s.count; ++i) {
      const float x = tx(s.x[i]), y = ty(s.y[i]);
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      if (fit_x) x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x);
      if (fit_y) y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
    }
  if (fit_x && axes.x_log) {
    if (x_lo > x_hi) x_lo = 0, x_hi = 1;
    snap_decades(&x_lo, &x_hi);
  } else if (fit_x && !(x_hi > x_lo)) {
    x_lo = 0, x_hi = 1;
  }
  if (fit_y && axes.y_log) {
    // whole decades, within the clamps (given in data units)
    if (y_lo > y_hi) y_lo = -6, y_hi = 0;
    snap_decades(&y_lo, &y_hi);
    if (axes.y_clamp_lo > 0) y_lo = std::max(y_lo, std::floor(std::log10(axes.y_clamp_lo)));
    if (axes.y_clamp_hi > 0) y_hi = std::min(y_hi, std::ceil(std::log10(axes.y_clamp_hi)));
    if (y_hi <= y_lo) y_hi = y_lo + 1;
  } else if (fit_y) {
    if (y_lo > y_hi) y_lo = 0, y_hi = 1;
    if (axes.y_include_zero) y_lo = std::min(y_lo, 0.0f), y_hi = std::max(y_hi, 0.0f);
    y_lo = std::max(y_lo, axes.y_clamp_lo);
    y_hi = std::min(y_hi, axes.y_clamp_hi);
    if (y_hi - y_lo < axes.y_min_span) {
      const float c = 0.5f * (y_lo + y_hi);
      y_lo = c - 0.5f * axes.y_min_span, y_hi = c + 0.5f * axes.y_min_span;
    }
    // padded, but not past the clamps: a count's axis clamped at 0 padded below read as less
    // than none (-80 bodies under the rain's 1000)
    const float pad = 0.08f * (y_hi - y_lo);
    y_lo = std::max(y_lo - pad, axes.y_clamp_lo), y_hi = std::min(y_hi + pad, axes.y_clamp_hi);
  }

  // frame: room on the left for the widest tick label, below for the x label (and log x's
  // decades)
  char buf[32];
  float left = 36.0f;
  if (!axes.y_log)
    for (int k = 0; k <= 4; ++k) {
      std::snprintf(buf, sizeof buf, axes.y_format, y_lo + (y_hi - y_lo) * k / 4.0f);
      left = std::max(left, ImGui::CalcTextSize(buf).x + 8.0f);
    }
  else
    left = std::max(left, ImGui::CalcTextSize("1e-10").x + 8.0f);
  float bottom = axes.x_label.empty() ? 4.0f : 16.0f;
  if (axes.x_log) bottom = axes.x_label.empty() ? 16.0f : 16.0f + line_h;
  const ImVec2 p0(origin.x + left, origin.y + 4.0f);
  const ImVec2 p1(origin.x + width - 4.0f, origin.y + height - bottom);
  dl->AddRectFilled(p0, p1, IM_COL32(24, 26, 30, 230), 3.0f);
  auto sx = [&](float x) { return p0.x + (x - x_lo) / (x_hi - x_lo) * (p1.x - p0.x); };
  auto sy = [&](float y) { return p1.y - (y - y_lo) / (y_hi - y_lo) * (p1.y - p0.y); };
  const ImU32 tick_col = IM_COL32(200, 204, 210, 255), axis_col = IM_COL32(160, 164, 170, 255);

  if (axes.y_log) {
    // decades: a grid line each, labels as often as they fit, minor lines when roomy
    const float ppd = (p1.y - p0.y) / (y_hi - y_lo);
    const int stride = decade_stride(ppd, 1.15f * line_h);
    for (int e = static_cast<int>(std::ceil(y_lo - 1e-4f)); e <= static_cast<int>(std::floor(y_hi + 1e-4f)); ++e) {
      const float py = sy(static_cast<float>(e));
      dl->AddLine(ImVec2(p0.x, py), ImVec2(p1.x, py), IM_COL32(255, 255, 255, 26));
      if (e % stride != 0) continue;
      decade_label(e, buf, sizeof buf);
      const ImVec2 ts = ImGui::CalcTextSize(buf);
      dl->AddText(ImVec2(p0.x - ts.x - 4.0f, py - 0.5f * ts.y), tick_col, buf);
    }
    if (ppd > 36)
      for (int e = static_cast<int>(std::floor(y_lo)); e < static_cast<int>(std::ceil(y_hi)); ++e)
        for (int k = 2; k <= 9; ++k) {
          const float y = static_cast<float>(e) + std::log10(static_cast<float>(k));
          if (y > y_lo && y < y_hi) dl->AddLine(ImVec2(p0.x, sy(y)), ImVec2(p0.x + 4, sy(y)), IM_COL32(255, 255, 255, 60));
        }
  } else {
    // horizontal grid lines with labels at 5 levels
    for (int k = 0; k <= 4; ++k) {
      const float y = y_lo + (y_hi - y_lo) * k / 4.0f;
      const float py = sy(y);
      dl->AddLine(ImVec2(p0.x, py), ImVec2(p1.x, py), IM_COL32(255, 255, 255, k == 0 || k == 4 ? 40 : 22));
      std::snprintf(buf, sizeof buf, axes.y_format, y);
      const ImVec2 ts = ImGui::CalcTextSize(buf);
      dl->AddText(ImVec2(p0.x - ts.x - 4.0f, py - 0.5f * ts.y), tick_col, buf);
    }
    // zero line when in range
    if (y_lo < 0 && y_hi > 0) dl->AddLine(ImVec2(p0.x, sy(0)), ImVec2(p1.x, sy(0)), IM_COL32(255, 255, 255, 70));
  }
  if (axes.x_log) {
    // vertical decade lines, labelled under the frame
    const float ppd = (p1.x - p0.x) / (x_hi - x_lo);
    const int stride = decade_stride(ppd, ImGui::CalcTextSize("1e-10").x + 6);
    for (int e = static_cast<int>(std::ceil(x_lo - 1e-4f)); e <= static_cast<int>(std::floor(x_hi + 1e-4f)); ++e) {
      const float px = sx(static_cast<float>(e));
      dl->AddLine(ImVec2(px, p0.y), ImVec2(px, p1.y), IM_COL32(255, 255, 255, 26));
      if (e % stride != 0) continue;
      decade_label(e, buf, sizeof buf);
      const ImVec2 ts = ImGui::CalcTextSize(buf);
      const float lx = std::clamp(px - 0.5f * ts.x, p0.x - 8.0f, p1.x - ts.x + 4.0f);
      dl->AddText(ImVec2(lx, p1.y + 1), tick_col, buf);
    }
    if (ppd > 36)
      for (int e = static_cast<int>(std::floor(x_lo)); e < static_cast<int>(std::ceil(x_hi)); ++e)
        for (int k = 2; k <= 9; ++k) {
          const float x = static_cast<float>(e) + std::log10(static_cast<float>(k));
          if (x > x_lo && x < x_hi) dl->AddLine(ImVec2(sx(x), p1.y), ImVec2(sx(x), p1.y - 4), IM_COL32(255, 255, 255, 60));
        }
  }

  // curves, markers and tags, clipped to the frame
  dl->PushClipRect(p0, p1, true);
  for (float m : axes.x_marks) {
    const float x = tx(m);
    if (std::isfinite(x) && x >= x_lo && x <= x_hi)
      dl->AddLine(ImVec2(sx(x), p0.y), ImVec2(sx(x), p1.y), IM_COL32(255, 255, 255, 90), 1.0f);
  }
  for (const PlotSeries& s : series) {
    const ImU32 c = u32(s.color);
    bool have_prev = false, tagged = s.tag.empty();
    ImVec2 prev;
    for (int i = 0; i < s.count; ++i) {
      const float x = tx(s.x[i]), y = ty(s.y[i]);
      if (!std::isfinite(x) || !std::isfinite(y)) {
        have_prev = false;
        continue;
      }
      // keep far-off values near the frame so the segment direction survives clipping
      const float yv = std::clamp(y, y_lo - 10 * (y_hi - y_lo), y_hi + 10 * (y_hi - y_lo));
      const ImVec2 p(sx(x), sy(yv));
      if (have_prev) dl->AddLine(prev, p, c, s.width);
      if (s.marker > 0) dl->AddCircleFilled(p, s.marker, c, 10);
      if (!tagged && p.x >= p0.x && p.x <= p1.x && p.y >= p0.y && p.y <= p1.y) {
        // above-right of the point, or below it near the top; inside the frame
        const ImVec2 ts = ImGui::CalcTextSize(s.tag.c_str());
        const float lx = std::max(p0.x + 2.0f, std::min(p.x + 3.0f, p1.x - ts.x - 2.0f));
        const float ly = p.y - ts.y >= p0.y ? p.y - ts.y : std::min(p.y + 3.0f, p1.y - ts.y);
        dl->AddText(ImVec2(lx, ly), c, s.tag.c_str());
        tagged = true;
      }
      prev = p;
      have_prev = true;
    }
  }
  dl->PopClipRect();

  // axis labels
  if (axes.x_log) {
    if (!axes.x_label.empty()) {
      const ImVec2 ls = ImGui::CalcTextSize(axes.x_label.c_str());
      dl->AddText(ImVec2(0.5f * (p0.x + p1.x - ls.x), p1.y + 1 + line_h), axis_col, axes.x_label.c_str());
    }
  } else if (!axes.x_label.empty()) {
    std::snprintf(buf, sizeof buf, "%.3g", x_lo);
    dl->AddText(ImVec2(p0.x, p1.y + 1), axis_col, buf);
    std::snprintf(buf, sizeof buf, "%.3g", x_hi);
    const ImVec2 ts = ImGui::CalcTextSize(buf);
    dl->AddText(ImVec2(p1.x - ts.x, p1.y + 1), axis_col, buf);
    const ImVec2 ls = ImGui::CalcTextSize(axes.x_label.c_str());
    dl->AddText(ImVec2(0.5f * (p0.x + p1.x - ls.x), p1.y + 1), axis_col, axes.x_label.c_str());
  }
  if (!axes.y_label.empty())
    dl->AddText(ImVec2(p0.x + 6, p0.y + 2), IM_COL32(200, 204, 210, 200), axes.y_label.c_str());

  // legend: a short line in each labelled series' colour, then its label
  if (axes.legend == PlotCorner::Below) {
    std::size_t k = 0;
    const ImVec2 b0(p0.x, origin.y + height + 1);
    for (const PlotSeries& s : series) {
      if (s.label.empty()) continue;
      const ImVec2 e(b0.x + below[k].x, b0.y + below[k].y);
      const float my = e.y + 0.5f * line_h;
      dl->AddLine(ImVec2(e.x, my), ImVec2(e.x + sample_w, my), u32(s.color), std::max(s.width, 2.0f));
      dl->AddText(ImVec2(e.x + sample_w + pad, e.y), tick_col, s.label.c_str());
      ++k;
    }
  } else {
    float legend_w = 0;
    int rows = 0;
    for (const PlotSeries& s : series)
      if (!s.label.empty()) legend_w = std::max(legend_w, ImGui::CalcTextSize(s.label.c_str()).x), ++rows;
    if (rows > 0) {
      const ImVec2 size(sample_w + 3 * pad + legend_w, rows * line_h + 2 * pad);
      const bool right = axes.legend == PlotCorner::TopRight || axes.legend == PlotCorner::BottomRight;
      const bool top = axes.legend == PlotCorner::TopLeft || axes.legend == PlotCorner::TopRight;
      // below the y label when it shares the top-left corner
      const float top_y = p0.y + 4 + (axes.legend == PlotCorner::TopLeft && !axes.y_label.empty() ? line_h + 2 : 0);
      const ImVec2 b0(right ? p1.x - 4 - size.x : p0.x + 4, top ? top_y : p1.y - 4 - size.y);
      dl->AddRectFilled(b0, ImVec2(b0.x + size.x, b0.y + size.y), IM_COL32(18, 20, 24, 215), 3.0f);
      dl->AddRect(b0, ImVec2(b0.x + size.x, b0.y + size.y), IM_COL32(255, 255, 255, 40), 3.0f);
      float y = b0.y + pad;
      for (const PlotSeries& s : series) {
        if (s.label.empty()) continue;
        const float my = y + 0.5f * line_h;
        dl->AddLine(ImVec2(b0.x + pad, my), ImVec2(b0.x + pad + sample_w, my), u32(s.color), std::max(s.width, 2.0f));
        dl->AddText(ImVec2(b0.x + 2 * pad + sample_w, y), tick_col, s.label.c_str());
        y += line_h;
      }
    }
  }
  ImGui::PopID();
}

}  // namespace pba::app
