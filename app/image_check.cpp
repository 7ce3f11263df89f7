// Image statistics for the self-test: uniformity, background, colours, smoothness.
#include "image_check.h"

#include "pba/core.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unordered_set>

namespace pba::app {

ImageStats MeasureImage(const std::vector<std::uint8_t>& rgb, int width, int height,
                        const std::function<Color(int row)>& background, const std::vector<Color>& expected,
                        double color_tolerance, const std::vector<std::uint8_t>* counted) {
  ImageStats s;
  s.color_hits.assign(expected.size(), 0);
  const double n = static_cast<double>(width) * height;
  if (n <= 0 || rgb.size() < static_cast<std::size_t>(n) * 3) return s;
  double sum = 0, sum2 = 0;
  long long bg = 0, smooth = 0;
  std::unordered_set<int> colors;
  const double tol2 = color_tolerance * color_tolerance;
  // a mask of another size is the caller's bug (a frame and a mask of different windows):
  // counting every pixel instead would pass a colour seen only on a panel
  if (counted && counted->size() != static_cast<std::size_t>(n))
    throw Error("MeasureImage: the counted-pixel mask has " + std::to_string(counted->size()) + " entries, the image " +
                std::to_string(width) + " x " + std::to_string(height) + " = " +
                std::to_string(static_cast<long long>(n)) + " pixels");
  for (int y = 0; y < height; ++y) {
    const Color b = background(y);
    for (int x = 0; x < width; ++x) {
      const std::uint8_t* p = &rgb[(static_cast<std::size_t>(y) * width + x) * 3];
      // brightness spread
      const double l = 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
      sum += l, sum2 += l * l;
      // background match within 6 levels per channel
      if (std::abs(p[0] - 255.0 * b.r) <= 6.5 && std::abs(p[1] - 255.0 * b.g) <= 6.5 && std::abs(p[2] - 255.0 * b.b) <= 6.5)
        ++bg;
      // smoothness against the right neighbour
      if (x + 1 < width) {
        const std::uint8_t* q = p + 3;
        if (std::abs(p[0] - q[0]) <= 3 && std::abs(p[1] - q[1]) <= 3 && std::abs(p[2] - q[2]) <= 3) ++smooth;
      }
      colors.insert((p[0] >> 3) << 10 | (p[1] >> 3) << 5 | (p[2] >> 3));
      // expected colours (where they count)
      if (counted && !(*counted)[static_cast<std::size_t>(y) * width + x]) continue;
      for (std::size_t k = 0; k < expected.size(); ++k) {
        const double dr = p[0] - 255.0 * expected[k].r, dg = p[1] - 255.0 * expected[k].g,
                     db = p[2] - 255.0 * expected[k].b;
        if (dr * dr + dg * dg + db * db <= tol2) ++s.color_hits[k];
      }
    }
  }
  const double mean = sum / n;
  s.luma_stddev = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
  s.background_fraction = bg / n;
  s.distinct_colors = static_cast<int>(colors.size());
  s.smooth_fraction = smooth / (static_cast<double>(width - 1) * height);
  return s;
}

std::string CheckImage(const ImageStats& s, const ImageRules& r, const std::vector<Color>& expected) {
  std::string err;
  char buf[256];
  if (s.luma_stddev < r.min_luma_stddev) {
    std::snprintf(buf, sizeof buf, "image is (nearly) uniform: brightness stddev %.2f < %.2f; ", s.luma_stddev,
                  r.min_luma_stddev);
    err += buf;
  }
  if (s.background_fraction < r.min_background_fraction) {
    std::snprintf(buf, sizeof buf, "background colour covers %.1f%% < %.1f%% of the image; ",
                  100 * s.background_fraction, 100 * r.min_background_fraction);
    err += buf;
  }
  if (s.distinct_colors < r.min_distinct_colors) {
    std::snprintf(buf, sizeof buf, "only %d distinct colours < %d; ", s.distinct_colors, r.min_distinct_colors);
    err += buf;
  }
  if (s.smooth_fraction < r.min_smooth_fraction) {
    std::snprintf(buf, sizeof buf, "image looks like noise: %.1f%% smooth pixels < %.1f%%; ",
                  100 * s.smooth_fraction, 100 * r.min_smooth_fraction);
    err += buf;
  }
  for (std::size_t k = 0; k < s.color_hits.size() && k < expected.size(); ++k)
    if (s.color_hits[k] < r.min_color_hits) {
      std::snprintf(buf, sizeof buf, "expected colour #%02x%02x%02x found in %d pixels < %d; ",
                    int(std::lround(255 * expected[k].r)), int(std::lround(255 * expected[k].g)),
                    int(std::lround(255 * expected[k].b)), s.color_hits[k], r.min_color_hits);
      err += buf;
    }
  if (err.size() >= 2) err.resize(err.size() - 2);
  return err;
}

double ImageDifference(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  if (a.size() != b.size() || a.empty()) return 1.0;
  long long diff = 0;
  for (std::size_t i = 0; i + 2 < a.size(); i += 3)
    if (std::abs(a[i] - b[i]) > 8 || std::abs(a[i + 1] - b[i + 1]) > 8 || std::abs(a[i + 2] - b[i + 2]) > 8) ++diff;
  return static_cast<double>(diff) / (a.size() / 3);
}

long long ChangedPixels(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b, int w, int x0,
                        int y0, int x1, int y1) {
  if (a.size() != b.size() || w <= 0) return 0;
  const int h = static_cast<int>(a.size() / 3 / static_cast<std::size_t>(w));
  x0 = std::max(0, x0), x1 = std::min(w, x1), y0 = std::max(0, y0), y1 = std::min(h, y1);
  long long diff = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * w + x) * 3;
      if (std::abs(a[i] - b[i]) > 8 || std::abs(a[i + 1] - b[i + 1]) > 8 || std::abs(a[i + 2] - b[i + 2]) > 8) ++diff;
    }
  return diff;
}

}  // namespace pba::app
