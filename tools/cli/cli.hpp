// The `limber` command-line program, as a function so tests can run it in-process.
#pragma once

#include <iosfwd>

namespace limber::cli {

/// Exit codes of `limber`.
enum ExitCode : int {
  kSuccess = 0,
  kDiverged = 1,   ///< the simulation reported divergence (NaN or runaway speed)
  kBadInput = 2,   ///< bad flags, values or scene file; one line on `err` says which
};

/// Runs `limber` with the given arguments (argv[0] is the program name), writing the summary to
/// `out` and errors to `err`. Never throws.
int run_main(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace limber::cli
