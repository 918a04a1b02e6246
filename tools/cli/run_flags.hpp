// `limber run`'s flags, shared by `limber run` and `limber view` (tools/cli/ only, not
// installed): what they are, how each is checked, and how they become a loaded scene and a
// method's options. Every bad value is an InputError whose what() is the one line printed after
// "limber: ".
#pragma once

#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/model/model.hpp"
#include "tools/cli/cli.hpp"

namespace limber::cli {

inline std::string format(const char* pattern, auto... values) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, pattern, values...);
  return buffer;
}

// The flags of `limber run`, with the option handles that tell whether each was given.
struct RunFlags {
  std::string scene;
  std::string method = "weighted";
  std::string precision = "double";
  std::string body;
  double ball_speed = 0, ball_radius = 0, ball_mass = 0, ball_restitution = 0, friction = 0;
  std::vector<double> ball_direction;
  long links = 0, copies = 0, steps = 0;
  int iterations = 0, substeps = 0;
  std::string projection;
  double dt = 0, tolerance = 0, budget_us = 0, over_relaxation = 1;
  std::string out_path;
  std::string solver = "gauss-seidel", sweep = "coloured", pinned = "first", layout = "auto", threading = "workers";
  std::string joint_solve;  ///< --joint-solve: rows or tree (empty: the scene's settings.verlet.joint_solve)
  std::string ordering = "depth-parity";
  int threads = 0;
  bool scalar = false;
  int newton_iterations = 2;
  double compliance = 0;
  bool warm_start = false, long_range_attachments = false;
  bool floating_base = false;  ///< --floating-base: a URDF robot's root link floats (SceneOptions::floating_base)
  bool profile = false;  ///< --profile: time each stage of the step (StepReport::profile) and print where the time went
  double stiffness = 0, damping = 0;
  std::string integrator, linear_solver = "ldlt";
  std::string stabilization = "baumgarte", constraint_solver = "auto";

  CLI::Option *body_option, *ball_speed_option, *ball_direction_option, *ball_radius_option, *ball_mass_option,
      *ball_restitution_option, *friction_option, *links_option, *copies_option, *steps_option, *dt_option, *iterations_option,
      *tolerance_option, *budget_option, *over_relaxation_option, *out_option, *stiffness_option, *damping_option,
      *integrator_option, *linear_solver_option, *stabilization_option, *constraint_solver_option, *newton_iterations_option,
      *compliance_option, *warm_start_option, *projection_option, *substeps_option;
  std::vector<CLI::Option*> verlet_only_options;  ///< flags that only the Verlet methods take
  std::vector<CLI::Option*> thread_options;       ///< --threads, --threading: the Verlet methods and featherstone

  bool springs() const { return method == "springs-explicit" || method == "springs-implicit"; }
  bool lagrange() const { return method == "lagrange"; }
  bool featherstone() const { return method == "featherstone"; }
  bool rigid() const { return springs() || lagrange() || featherstone(); }  ///< the methods on rigid bodies
};

inline bool given(const CLI::Option* option) { return option->count() > 0; }

/// Declares the run flags on `run` (the `run` or `view` subcommand, or an app of its own).
void add_run_flags(CLI::App& run, RunFlags& flags);
/// The method and its options the flags ask for, over the scene's method settings (each reader
/// refuses the other methods' flags).
WorldOptions method_options(const RunFlags& flags, const MethodSettings& scene);
/// The scene and method that parsed run flags ask for. Throws ModelError, InputError or
/// std::invalid_argument (options that do not go together), each one line; OutOfMemoryError
/// when the scene would generate more bodies than the memory available holds
/// (require_memory_for), before generating them.
LoadedRun load(const RunFlags& flags);

/// The memory the system has available now, bytes (Linux: MemAvailable in /proc/meminfo);
/// nullopt where it cannot tell.
std::optional<double> available_memory();
/// Bytes one body of a long chain or of many copies needs under the flags' method, from loading
/// to stepping in `limber run` (peak resident memory per body at 10⁶ links, bench/speed.md,
/// "Linear costs").
double bytes_per_body(const RunFlags& flags);
/// Throws OutOfMemoryError, one line naming `source`, `path` and both figures, when `bodies`
/// bodies need more than `available` bytes under the flags' method (bytes_per_body).
void require_memory_for(double bodies, const std::string& source, const std::string& path, const RunFlags& flags,
                        double available);

}  // namespace limber::cli
