// The `limber` command-line program, as a function so tests can run it in-process.
#pragma once

#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace limber::cli {

/// Exit codes of `limber`.
enum ExitCode : int {
  kSuccess = 0,
  kDiverged = 1,   ///< the simulation diverged: a non-finite number, runaway speed or energy, a joint come apart
  kBadInput = 2,   ///< bad flags, values or scene file; one line on `err` says which
  kOutOfMemory = 3,  ///< not enough memory: refused before loading (the estimate against what is available), or an allocation failed
};

/// A bad flag, value or output path; what() is the one line printed after "limber: ".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Not enough memory for what was asked; what() is the one line printed after "limber: ".
class OutOfMemoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What `limber run`'s flags ask for: the scene with the flags' changes (ball, friction, Δt,
/// body variant, links, copies) and the method with its options.
struct LoadedRun {
  Scene scene;
  WorldOptions options;
  std::string source;    ///< the scene file, or "embedded tools/scenes/humanoid.json"
  std::string scene_path;  ///< the scene file; empty for the embedded humanoid
  std::string out_path;  ///< --out: where to write the trajectory (trajectory.hpp); empty: nowhere
};

/// Parses `limber run`'s flags (the arguments after "run", scene file first if any) and loads
/// what they ask for. Throws std::exception whose what() is the one line `limber run` prints
/// (a bad flag, value or scene file).
LoadedRun load_run(const std::vector<std::string>& run_arguments);

/// The options `limber run --method <method>` gives the scene's method settings, with no other
/// flag ("weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange",
/// "featherstone"). Throws std::exception naming the method when it is none of these.
WorldOptions options_for_method(const std::string& method, const MethodSettings& scene);

/// The options `limber run`'s flags ask for on a scene already loaded (the arguments after
/// "run", without a scene file), with the changes they make to its model (--dt, --friction,
/// --ball-*) made on `scene`: the options of Python's World(scene, method, **options). The flags
/// that load a scene (--body, --links, --copies, --floating-base) or belong to a run (--steps,
/// --out) are refused by name. Throws std::exception whose what() is `limber run`'s one line.
WorldOptions options_for_scene(Scene& scene, const std::vector<std::string>& run_arguments);

/// What `limber view` was asked for.
struct ViewRequest {
  std::vector<std::string> run_arguments;  ///< the run flags given to `view` (load_run's input)
  long frames = -1;         ///< ≥ 0: headless: simulate and draw this many frames offscreen, then exit; −1: a window
  std::string screenshot;   ///< headless: write the last frame here (PNG); empty: none
  bool hide_ui = false;     ///< draw the scene without the control panels
  /// Overlays shown from the start: "bounding-spheres", "contacts", "joint-gaps", "centre-of-mass", "forces".
  std::vector<std::string> overlays;
  /// The camera: yaw and pitch (degrees), distance (m), then optionally the point it looks at
  /// (x, y, z, m); empty: framed to the bodies.
  std::vector<double> camera;
  int width = 1280, height = 720;  ///< pixels
};

/// The viewer (tools/viewer), which the program passes in when it was built with one: shows or
/// renders `request` and returns the exit code, its errors one line each on `err`.
using Viewer = int (*)(const ViewRequest& request, std::ostream& out, std::ostream& err);

/// Runs `limber` with the given arguments (argv[0] is the program name), writing the summary to
/// `out` and errors to `err`. `limber view` goes to `viewer`, or is refused with one line when
/// it is null. Never throws.
int run_main(int argc, const char* const* argv, std::ostream& out, std::ostream& err, Viewer viewer = nullptr);

}  // namespace limber::cli
