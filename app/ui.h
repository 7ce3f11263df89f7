// The app's ImGui panels: menu bar with the sample picker, simulation settings,
// profiler, the sample's own panel and the divergence message.
#pragma once

#include <array>
#include <string>

#include "physics_loop.h"
#include "renderer.h"
#include "sample.h"

namespace pba::app {

/// A fixed-length history of one measurement for the profiler plots.
struct History {
  static constexpr int kSize = 240;  ///< frames kept
  std::array<float, kSize> values{}; ///< ring buffer
  int next = 0;                      ///< index of the oldest value
  int count = 0;                     ///< values stored, up to kSize
  /// Appends a value, dropping the oldest when full.
  void push(float v);
  /// The values oldest first, into `out` (kSize long); returns count.
  int ordered(float* out) const;
  /// Mean of the stored values, 0 when empty.
  float mean() const;
  /// Largest stored value, 0 when empty.
  float max() const;
};

/// UI state that lives across frames.
struct UiState {
  char search[64] = "";       ///< sample picker filter
  History frame_ms;           ///< frame time (ms)
  History physics_ms;         ///< wall time of the frame's ticks (ms)
  History ticks;              ///< ticks per frame
  History dropped_ms;         ///< time dropped per frame (ms)
  float left_width = 290;     ///< width of the left panel (px)
  float right_width = 370;    ///< width of the sample panel (px)
  float menu_height = 21;     ///< height of the main menu bar (px), measured when drawn
  std::string status;         ///< a short note in the menu bar (e.g. where a screenshot went)
  double status_until = 0;    ///< ImGui time (s) until which the note shows
};

/// What the user asked for through the UI this frame.
struct UiActions {
  int select = -1;       ///< index into Samples() to switch to, -1 for none
  bool restart = false;  ///< recreate the current sample
  bool quit = false;     ///< leave the app
  bool screenshot = false;  ///< save the finished frame as a PNG
};

/// Everything the panels show about the frame.
struct UiFrame {
  int sample_index = 0;           ///< current sample
  Sample* sample = nullptr;       ///< current sample, for DrawUI
  const PhysicsReadout* physics = nullptr;
  const DrawStats* draw = nullptr;
  double frame_dt = 0;            ///< last frame time (s)
  const std::string* diverged = nullptr;  ///< non-empty: the divergence message
  bool headless = false;          ///< hide the interactive-only hints
};

/// Draws the menu bar and the panels for one frame.
UiActions DrawUi(UiState& ui, SampleContext& ctx, const UiFrame& frame);

/// Draws the divergence message in the middle of `view`, the region the panels leave free
/// (also when panels are hidden), wrapped to fit inside it.
UiActions DrawDiverged(const std::string& message, bool headless, const ScreenRect& view);

/// Width of the left and right panels for a window `width` pixels wide (0 when hidden).
void PanelWidths(const UiState& ui, const Settings& s, float width, float* left, float* right);

/// The part of a `width` x `height` pixel window that the panels and the menu bar leave for
/// the 3D view (the whole window when the panels are hidden).
ScreenRect ViewRegion(const UiState& ui, const Settings& s, float width, float height);

}  // namespace pba::app
