// A small multi-series line plot with shared axes, drawn with ImGui's draw list.
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
};

/// Axis ranges and labels of a plot. A range with lo >= hi is fitted to the data.
struct PlotAxes {
  float x_lo = 0, x_hi = 0;  ///< x range (fit when empty)
  float y_lo = 0, y_hi = 0;  ///< y range (fit when empty)
  float y_min_span = 1e-6f;  ///< smallest fitted y span (keeps flat curves readable)
  float y_clamp_lo = -1e30f, y_clamp_hi = 1e30f;  ///< limits on a fitted y range
  bool y_include_zero = false;  ///< fitted y range always contains 0
  std::string x_label;       ///< e.g. "t (s)"
  std::string y_label;       ///< e.g. "E / E0"
  const char* y_format = "%.3g";  ///< tick label format
};

/// Draws the series into a plot `height` pixels tall spanning the window's content width.
void LinePlot(const char* id, const std::vector<PlotSeries>& series, const PlotAxes& axes, float height);

}  // namespace pba::app
