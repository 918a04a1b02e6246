// The viewer's Dear ImGui panels: simulation controls, method and solver settings, the scene
// (body type, friction, another file), the ball launcher, picking, overlays, and live plots of
// energy, joint gap and time per step. They act on a ViewState through its public calls only.
#pragma once

#include <string>

#include "tools/viewer/view_state.hpp"

namespace limber::viewer {

/// Pixels the control panel takes with every section open.
inline constexpr int kFullPanelHeight = 760;

/// What the panels edit before it is applied (the method settings apply with a reset).
struct PanelState {
  std::string shown_method;  ///< the ViewState's method the fields below were read from
  int method = 0;            ///< index into the method names
  int iterations = 100, substeps = 1, projection = 0;
  int body = 0;              ///< 0: the scene's own, then thin, medium, wide
  float friction = 0.6f;
  char scene_path[512] = {};
  /// Whether to plot the time per step: wall-clock, so off in the headless mode, whose pictures
  /// must be the same every run.
  bool wall_clock = true;
  /// Out: whether every panel's content fitted its window in the last frame drawn (nothing cut
  /// off at the panel's side or bottom, nothing to scroll).
  bool fits = true;
};

/// Draws the panels for a width × height frame and applies what the user changed. Frames shorter
/// than kFullPanelHeight start with the Ball and Picking sections closed, so the headers fit.
void draw_panels(ViewState& view, PanelState& panel, int width, int height);

}  // namespace limber::viewer
