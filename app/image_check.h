// Checks that a rendered frame shows a scene, not a blank or garbage image.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pba/draw.h"

namespace pba::app {

/// Measurements of one RGB image.
struct ImageStats {
  double luma_stddev = 0;          ///< spread of brightness (0 for a uniform image)
  double background_fraction = 0;  ///< pixels matching the expected background colour
  int distinct_colors = 0;         ///< distinct colours at 5 bits per channel
  double smooth_fraction = 0;      ///< pixels equal (within 3) to their right neighbour
  std::vector<int> color_hits;     ///< pixels within tolerance of each expected colour
};

/// What a frame must satisfy.
struct ImageRules {
  double min_luma_stddev = 4.0;          ///< not uniform
  double min_background_fraction = 0.05; ///< the background shows somewhere
  int min_distinct_colors = 24;          ///< more than a clear colour and a few shapes
  double min_smooth_fraction = 0.3;      ///< natural images are mostly smooth; noise is not
  int min_color_hits = 6;                ///< pixels needed per expected colour
  double color_tolerance = 28.0;         ///< RGB distance (0..255 scale) for a colour match
};

/// Measures `rgb` (width x height, top row first). `background(y)` gives the background
/// colour expected at row y; `expected` colours are counted in color_hits, over the pixels
/// whose entry in `counted` (width x height, top row first) is nonzero, or over every pixel
/// when it is null (the self-test passes the 3D viewport's pixels: a sample's colour on a
/// panel's plot line is not its body in the scene). Throws pba::Error, naming both sizes,
/// when `counted` is not width x height.
ImageStats MeasureImage(const std::vector<std::uint8_t>& rgb, int width, int height,
                        const std::function<Color(int row)>& background, const std::vector<Color>& expected,
                        double color_tolerance, const std::vector<std::uint8_t>* counted = nullptr);

/// Empty when `stats` satisfies `rules`, else a message listing each failed rule;
/// `expected` names the colours for the message.
std::string CheckImage(const ImageStats& stats, const ImageRules& rules, const std::vector<Color>& expected);

/// Fraction of pixels whose colour differs by more than 8 in any channel between two images.
double ImageDifference(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b);

/// Pixels in columns [x0, x1) and rows [y0, y1) whose colour differs by more than 8 in any
/// channel between two RGB images of width `w` (rows top-down); 0 when the sizes differ.
long long ChangedPixels(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b, int w, int x0,
                        int y0, int x1, int y1);

}  // namespace pba::app
