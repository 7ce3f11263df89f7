// GLFW window, OpenGL context and Dear ImGui set-up.
#include "window.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>

namespace pba::app {

namespace {

std::string* g_glfw_error = nullptr;  // where the GLFW error callback writes during open()

void on_glfw_error(int code, const char* text) {
  if (g_glfw_error) *g_glfw_error += "GLFW error " + std::to_string(code) + ": " + text + "\n";
}

// a calm dark theme with a readable proportional font when DejaVu is installed
void style_imgui() {
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini litter in the working directory
  const char* font = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  if (std::filesystem::exists(font)) io.Fonts->AddFontFromFileTTF(font, 15.0f);
  ImGui::StyleColorsDark();
  ImGuiStyle& s = ImGui::GetStyle();
  s.WindowRounding = 4.0f;
  s.FrameRounding = 3.0f;
  s.GrabRounding = 3.0f;
  s.WindowBorderSize = 0.0f;
  s.Colors[ImGuiCol_WindowBg].w = 0.86f;
}

}  // namespace

Window::~Window() {
  if (imgui_ready_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  if (window_) glfwDestroyWindow(window_);
  glfwTerminate();
}

bool Window::open(const WindowConfig& config, std::string* error) {
  config_ = config;
  g_glfw_error = error;
  glfwSetErrorCallback(on_glfw_error);
  // an X server now and then refuses a connection that the next attempt gets (seen with
  // Xvfb in sandboxed VMs: about one connection in ten under load): a few tries, 0.1 s to
  // 1.6 s apart, before giving up; only the last attempt's messages are kept
  const std::size_t keep = error->size();
  bool ready = false;
  for (int attempt = 0; attempt < 5; ++attempt) {
    error->resize(keep);
    if ((ready = glfwInit())) break;
    const char* display = std::getenv("DISPLAY");
    if (display == nullptr || *display == '\0') break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100 << attempt));
  }
  if (!ready) {
    *error += "could not initialise GLFW (is DISPLAY set to a running X server?)";
    return false;
  }
  // core profile 3.3; the app renders into its own multisampled targets
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_VISIBLE, config.visible ? GLFW_TRUE : GLFW_FALSE);
  glfwWindowHint(GLFW_SAMPLES, 0);
  window_ = glfwCreateWindow(config.width, config.height, config.title.c_str(), nullptr, nullptr);
  if (!window_) {
    *error += "could not create an OpenGL 3.3 core window";
    g_glfw_error = nullptr;
    return false;
  }
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(config.visible && config.vsync ? 1 : 0);

  // our key callback first: the imgui backend chains to it
  glfwSetWindowUserPointer(window_, this);
  glfwSetKeyCallback(window_, &Window::on_key);
  glfwSetDropCallback(window_, &Window::on_drop);

  // dear imgui with its glfw and opengl3 backends (from libimgui.a)
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  style_imgui();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imgui_ready_ = true;
  g_glfw_error = nullptr;
  return true;
}

void Window::on_key(GLFWwindow* w, int key, int, int action, int mods) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  if (self && action == GLFW_PRESS) self->keys_.emplace_back(key, mods);
}

void Window::on_drop(GLFWwindow* w, int count, const char** paths) {
  auto* self = static_cast<Window*>(glfwGetWindowUserPointer(w));
  if (!self) return;
  for (int i = 0; i < count; ++i)
    if (paths[i]) self->dropped_.emplace_back(paths[i]);
}

std::vector<std::string> Window::take_dropped_files() {
  std::vector<std::string> d;
  d.swap(dropped_);
  return d;
}

std::vector<std::pair<int, int>> Window::take_key_presses() {
  std::vector<std::pair<int, int>> k;
  k.swap(keys_);
  return k;
}

bool Window::should_close() const { return glfwWindowShouldClose(window_); }

void Window::request_close() { glfwSetWindowShouldClose(window_, GLFW_TRUE); }

void Window::poll() { glfwPollEvents(); }

void Window::swap() { glfwSwapBuffers(window_); }

void Window::framebuffer_size(int* w, int* h) const {
  if (!config_.visible) {
    *w = config_.width;
    *h = config_.height;
    return;
  }
  glfwGetFramebufferSize(window_, w, h);
}

void Window::begin_ui_frame() {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  if (!config_.visible) {
    // a hidden window may report another size; ImGui lays out for the capture size
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(static_cast<float>(config_.width), static_cast<float>(config_.height));
    io.DisplayFramebufferScale = ImVec2(1, 1);
  }
  ImGui::NewFrame();
}

void Window::end_ui_frame() {
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

}  // namespace pba::app
