// Reads the PNG frames a headless run wrote and checks each shows a scene: not uniform,
// the background visible, enough colours, smooth like a rendering rather than noise.
// usage: png_check DIR [MIN_FILES]
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <stb_image.h>

#include "image_check.h"
#include "renderer.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 2) {
    std::fprintf(stderr, "usage: png_check DIR [MIN_FILES]\n");
    return 2;
  }
  const int min_files = argc > 2 ? std::atoi(argv[2]) : 1;
  int files = 0, failed = 0;
  // the default background gradient of the renderer
  const pba::app::SceneStyle style;
  for (const auto& e : fs::recursive_directory_iterator(argv[1])) {
    if (e.path().extension() != ".png") continue;
    int w = 0, h = 0, n = 0;
    unsigned char* data = stbi_load(e.path().c_str(), &w, &h, &n, 3);
    if (!data) {
      std::fprintf(stderr, "%s: cannot decode PNG\n", e.path().c_str());
      ++failed;
      continue;
    }
    std::vector<std::uint8_t> rgb(data, data + static_cast<std::size_t>(w) * h * 3);
    stbi_image_free(data);
    auto bg = [&](int y) {
      const float t = 1.0f - (static_cast<float>(y) + 0.5f) / static_cast<float>(h);
      const glm::vec3 c = glm::mix(style.sky_bottom, style.sky_top, t);
      return pba::Color{c.r, c.g, c.b, 1.0f};
    };
    pba::app::ImageRules rules;
    const auto st = pba::app::MeasureImage(rgb, w, h, bg, {}, rules.color_tolerance);
    const std::string err = pba::app::CheckImage(st, rules, {});
    ++files;
    if (!err.empty()) {
      std::fprintf(stderr, "%s: %s\n", e.path().c_str(), err.c_str());
      ++failed;
    }
  }
  std::printf("png_check: %d PNG files, %d failed\n", files, failed);
  if (files < min_files) {
    std::fprintf(stderr, "png_check: expected at least %d PNG files in %s\n", min_files, argv[1]);
    return 1;
  }
  return failed ? 1 : 0;
}
