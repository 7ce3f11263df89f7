// A small multi-series line plot with shared axes, drawn with ImGui's draw list: linear or
// log10 axes (decade ticks), point markers, a legend and vertical guide lines.
#pragma once

#include <string>
#include <vector>

#include "pba/draw.h"

namespace pba::app {

/// One curve: parallel arrays of x and y values in one colour.
struct PlotSeries {
  const float* x = nullptr;  ///< abscissae, increasing
  const float* y = nullptr;  ///< ordinates; non-finite values break the curve
  int count = 0;             ///< number of points
  Color color;               ///< line colour
  float width = 1.5f;        ///< line width in pixels
  std::string label;         ///< legend entry; empty: not in the legend
  float marker = 0;          ///< radius (px) of a dot drawn at each point; 0: none
  std::string tag;           ///< text drawn at the curve's first point inside the frame
};

/// Where a plot draws its legend: in a corner of the frame, or in rows below the plot
/// (which then takes more than its `height`).
enum class PlotCorner { TopLeft, TopRight, BottomLeft, BottomRight, Below };

/// Axis ranges and labels of a plot. A range with lo >= hi is fitted to the data.
struct PlotAxes {
  float x_lo = 0, x_hi = 0;  ///< x range (fit when empty)
  float y_lo = 0, y_hi = 0;  ///< y range (fit when empty)
  float y_min_span = 1e-6f;  ///< smallest fitted y span (keeps flat curves readable)
  float y_clamp_lo = -1e30f, y_clamp_hi = 1e30f;  ///< limits on a fitted y range
  bool y_include_zero = false;  ///< fitted y range always contains 0
  std::string x_label;       ///< e.g. "t (s)"
  std::string y_label;       ///< e.g. "E / E0"
  const char* y_format = "%.3g";  ///< tick label format (linear y only)
  /// Log10 axes: values <= 0 break the curve; ranges (given or fitted) are in data units,
  /// fitted ranges snap to whole decades, and ticks sit at decades labelled 1e-3, 1, 10.
  bool x_log = false, y_log = false;
  std::vector<float> x_marks;  ///< vertical guide lines at these x (data units)
  PlotCorner legend = PlotCorner::BottomRight;  ///< legend place (when a series has a label)
};

/// Draws the series into a plot `height` pixels tall spanning the window's content width.
/// Linear plots label the y ticks and the x range ends; log axes label their decades.
void LinePlot(const char* id, const std::vector<PlotSeries>& series, const PlotAxes& axes, float height);

}  // namespace pba::app
