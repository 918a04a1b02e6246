// `limber view`: the viewer's window (GLFW), its OpenGL renderer and its Dear ImGui panels
// around a ViewState; headless (ViewRequest::frames ≥ 0) it renders offscreen into a hidden
// window and writes the last frame as PNG.
#pragma once

#include <iosfwd>

#include "tools/cli/cli.hpp"

namespace limber::viewer {

/// Shows or renders `request` (cli::Viewer). Exit codes as `limber run`'s: 0, 1 when the world
/// diverged (headless), 2 on bad input or no display, each with one line on `err`.
int run_viewer(const cli::ViewRequest& request, std::ostream& out, std::ostream& err);

}  // namespace limber::viewer
