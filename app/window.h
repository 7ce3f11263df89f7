// The app's window: GLFW window with an OpenGL 3.3 core context and Dear ImGui.
#pragma once

#include <string>
#include <utility>
#include <vector>

struct GLFWwindow;

namespace pba::app {

/// How to open the window.
struct WindowConfig {
  int width = 1280;            ///< client width in pixels
  int height = 720;            ///< client height in pixels
  bool visible = true;         ///< false for headless capture (hidden window, off-screen target)
  bool vsync = true;           ///< wait for the display refresh in swap (visible windows only)
  std::string title = "pba samples";
};

/// Owns the GLFW window, its GL context and the ImGui context with its GLFW/OpenGL3 backends.
class Window {
 public:
  Window() = default;
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  /// Opens the window and sets up ImGui. Returns false and sets `error` on failure.
  bool open(const WindowConfig& config, std::string* error);
  /// True once the user asked to close (close button or glfwSetWindowShouldClose).
  bool should_close() const;
  /// Asks the main loop to end.
  void request_close();
  /// Processes pending window-system events.
  void poll();
  /// Presents the back buffer.
  void swap();
  /// Framebuffer size in pixels (the capture size when headless).
  void framebuffer_size(int* w, int* h) const;
  /// Starts an ImGui frame; headless windows report the configured size to ImGui.
  void begin_ui_frame();
  /// Renders the ImGui frame into the bound framebuffer.
  void end_ui_frame();
  /// Key presses (GLFW key, modifier bits) since the last call, in order. Queued from the
  /// event callback, so a tap shorter than a frame is not lost.
  std::vector<std::pair<int, int>> take_key_presses();
  /// Paths of files dropped on the window since the last call, in order.
  std::vector<std::string> take_dropped_files();
  /// The GLFW handle, for input queries.
  GLFWwindow* handle() const { return window_; }
  /// Whether the window is shown on screen.
  bool visible() const { return config_.visible; }

 private:
  GLFWwindow* window_ = nullptr;
  WindowConfig config_;
  bool imgui_ready_ = false;
  std::vector<std::pair<int, int>> keys_;
  std::vector<std::string> dropped_;

  static void on_key(GLFWwindow* w, int key, int scancode, int action, int mods);
  static void on_drop(GLFWwindow* w, int count, const char** paths);
};

}  // namespace pba::app
