// The self-test's image measures (app/image_check.cpp): an expected colour counts only over
// the pixels the caller marks (the 3D viewport), not on the panels around it.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "image_check.h"
#include "pba/core.h"

namespace {

// A 40 x 20 grey image with a 3 x 4 patch of pure red at columns 30-32 (a panel's plot line,
// say) and a 2 x 2 patch at columns 5-6 (a body in the scene): red counts 12 + 4 pixels over
// the whole image, 4 over columns 0-19, 12 over columns 20-39, none over an empty mark.
TEST(AppImageCheck, ExpectedColoursCountOnlyWhereMarked) {
  const int w = 40, h = 20;
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w) * h * 3, 128);
  auto paint = [&](int x0, int y0, int x1, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        std::uint8_t* p = &rgb[(static_cast<std::size_t>(y) * w + x) * 3];
        p[0] = 255, p[1] = 0, p[2] = 0;
      }
  };
  paint(30, 5, 33, 9);
  paint(5, 10, 7, 12);
  const std::vector<pba::Color> red{{1, 0, 0}};
  const auto grey = [](int) { return pba::Color{0.5f, 0.5f, 0.5f}; };
  auto hits = [&](const std::vector<std::uint8_t>* counted) {
    return pba::app::MeasureImage(rgb, w, h, grey, red, 28.0, counted).color_hits[0];
  };
  std::vector<std::uint8_t> left(static_cast<std::size_t>(w) * h, 0), right = left, none = left;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) (x < 20 ? left : right)[static_cast<std::size_t>(y) * w + x] = 1;
  EXPECT_EQ(hits(nullptr), 16);
  EXPECT_EQ(hits(&left), 4);
  EXPECT_EQ(hits(&right), 12);
  EXPECT_EQ(hits(&none), 0);
  // the other measures stay the whole image's
  const pba::app::ImageStats all = pba::app::MeasureImage(rgb, w, h, grey, red, 28.0, nullptr);
  const pba::app::ImageStats some = pba::app::MeasureImage(rgb, w, h, grey, red, 28.0, &left);
  EXPECT_EQ(all.background_fraction, some.background_fraction);
  EXPECT_EQ(all.distinct_colors, some.distinct_colors);
  // a mask of another size (a frame and a mask of different windows) is refused by its sizes,
  // not taken for "count everything"
  const std::vector<std::uint8_t> short_mask(static_cast<std::size_t>(w) * h - 1, 1);
  try {
    pba::app::MeasureImage(rgb, w, h, grey, red, 28.0, &short_mask);
    ADD_FAILURE() << "a 799-entry mask for a 40 x 20 image was taken";
  } catch (const pba::Error& e) {
    EXPECT_NE(std::string(e.what()).find("799 entries"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("40 x 20 = 800"), std::string::npos) << e.what();
  }
}

}  // namespace
