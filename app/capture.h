// Headless capture: numbered PNG frames and an MP4 piped through ffmpeg.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace pba::app {

/// Writes RGB frames as PNG files (frame_0000.png, ...) and, when ffmpeg is on the PATH,
/// streams every frame to `ffmpeg -f rawvideo` to make an H.264 MP4.
class Capture {
 public:
  Capture() = default;
  ~Capture();
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;

  /// Prepares `dir` (created if missing) for frames of `width` x `height` at `fps` frames/s.
  /// `video_name` is the MP4 file name inside `dir`; empty disables video.
  /// Returns false and sets `error` when the directory cannot be created.
  bool open(const std::string& dir, int width, int height, double fps, const std::string& video_name,
            std::string* error);
  /// Writes frame number `index` as PNG; returns false and sets `error` on failure.
  bool write_png(int index, const std::vector<std::uint8_t>& rgb, std::string* error);
  /// Appends a frame to the video (no-op without ffmpeg).
  void write_video(const std::vector<std::uint8_t>& rgb);
  /// Finishes the video; returns false when ffmpeg reported an error.
  bool close();

  /// Paths of PNG files written so far.
  const std::vector<std::string>& pngs() const { return pngs_; }
  /// Path of the MP4, empty when no video is being written.
  const std::string& video_path() const { return video_path_; }
  /// Why there is no video (ffmpeg missing, failed), empty otherwise.
  const std::string& video_note() const { return video_note_; }

 private:
  std::string dir_;
  int width_ = 0, height_ = 0;
  std::FILE* ffmpeg_ = nullptr;
  std::string video_path_;
  std::string video_note_;
  std::vector<std::string> pngs_;
};

/// True when an executable named `name` is found on the PATH.
bool on_path(const std::string& name);

/// Writes an RGB image as PNG. Returns false on I/O failure.
bool write_png_file(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb);

}  // namespace pba::app
