// PNG frames through stb_image_write, video through a pipe to ffmpeg.
#include "capture.h"

#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <system_error>

#include <stb_image_write.h>
#include <unistd.h>

namespace pba::app {

namespace fs = std::filesystem;

bool on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (!path) return false;
  std::stringstream ss(path);
  std::string dir;
  while (std::getline(ss, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path p = fs::path(dir) / name;
    if (::access(p.c_str(), X_OK) == 0) return true;
  }
  return false;
}

bool write_png_file(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb) {
  return stbi_write_png(path.c_str(), width, height, 3, rgb.data(), width * 3) != 0;
}

Capture::~Capture() { close(); }

bool Capture::open(const std::string& dir, int width, int height, double fps, const std::string& video_name,
                   std::string* error) {
  dir_ = dir;
  width_ = width;
  height_ = height;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    *error = "--out " + dir + ": cannot create directory" + (ec ? " (" + ec.message() + ")" : "");
    return false;
  }
  // remove frames of an earlier run so the directory holds exactly this capture
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("frame_", 0) == 0 && e.path().extension() == ".png") fs::remove(e.path(), ec);
  }
  if (video_name.empty()) return true;
  if (!on_path("ffmpeg")) {
    video_note_ = "no video: ffmpeg not found (run scripts/install-deps)";
    return true;
  }
  // libx264 needs even dimensions: pad by one pixel when necessary
  video_path_ = (fs::path(dir) / video_name).string();
  std::ostringstream cmd;
  cmd << "ffmpeg -y -loglevel error -f rawvideo -pix_fmt rgb24 -s " << width << "x" << height << " -r " << fps
      << " -i - -vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -preset veryfast -crf 20 -pix_fmt yuv420p"
      << " -movflags +faststart '" << video_path_ << "'";
  ffmpeg_ = ::popen(cmd.str().c_str(), "w");
  if (!ffmpeg_) {
    video_note_ = "no video: could not start ffmpeg";
    video_path_.clear();
  }
  return true;
}

bool Capture::write_png(int index, const std::vector<std::uint8_t>& rgb, std::string* error) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04d.png", index);
  const std::string path = (fs::path(dir_) / name).string();
  if (!write_png_file(path, width_, height_, rgb)) {
    *error = "could not write " + path;
    return false;
  }
  pngs_.push_back(path);
  return true;
}

void Capture::write_video(const std::vector<std::uint8_t>& rgb) {
  if (!ffmpeg_) return;
  if (std::fwrite(rgb.data(), 1, rgb.size(), ffmpeg_) != rgb.size()) {
    ::pclose(ffmpeg_);
    ffmpeg_ = nullptr;
    video_note_ = "no video: ffmpeg stopped reading frames";
    video_path_.clear();
  }
}

bool Capture::close() {
  if (!ffmpeg_) return video_note_.empty();
  const int status = ::pclose(ffmpeg_);
  ffmpeg_ = nullptr;
  if (status != 0) {
    video_note_ = "ffmpeg failed (exit status " + std::to_string(status) + ")";
    video_path_.clear();
    return false;
  }
  return true;
}

}  // namespace pba::app
