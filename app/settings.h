// Settings shared by the app and every sample: pause, stepping, strategy, integrator, views.
#pragma once

#include "pba/integrate.h"
#include "pba/time.h"

namespace pba::app {

/// What the user (or the command line) chose; the UI edits it, samples read it.
struct Settings {
  /// Time-stepping strategy and its parameters (workbook 3.1). fixed_dt is 1 / step rate.
  pba::StepperSettings stepper{};
  /// Integration substeps per tick: each tick of dt runs Step() this many times with dt / substeps.
  int substeps = 1;
  /// Integrator for samples that integrate with one method (workbook 3.2).
  pba::Method method = pba::Method::SemiImplicitEuler;

  bool paused = false;       ///< physics stops; the view stays live
  bool single_step = false;  ///< run one tick on the next frame, then stay paused
  bool restart = false;      ///< recreate the sample on the next frame

  /// Upper limit on rendered frames per second; 0 means no limit (vsync when shown).
  double frame_limit_hz = 0;
  /// Artificial extra render time per frame in milliseconds (the workbook's doWork()).
  double render_delay_ms = 0;

  bool show_ui = true;        ///< draw the ImGui panels (F1 toggles)
  bool show_labels = true;    ///< draw 3D text labels
  bool show_grid = true;      ///< draw the ground and its grid
  bool show_profiler = true;  ///< open the profiler panel
};

}  // namespace pba::app
