// The CLI tests' way to run `limber`: in-process, through run_main, with what it printed.
#pragma once

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tools/cli/cli.hpp"

namespace limber::cli::test {

struct Result {
  int code;
  std::string out, err;
};

/// `limber <arguments…>`, in this process.
inline Result run(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), "limber");
  std::vector<const char*> argv;
  for (const std::string& a : arguments) argv.push_back(a.c_str());
  std::ostringstream out, err;
  const int code = run_main(static_cast<int>(argv.size()), argv.data(), out, err);
  return {code, out.str(), err.str()};
}

/// A scene file of tools/scenes/.
inline std::string scene(const std::string& file) { return std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/" + file; }

/// The files in `folder` whose names end in ".part": an output's temporary files (output_file.hpp).
inline std::vector<std::filesystem::path> partial_files(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> found;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.path().filename().string().ends_with(".part")) found.push_back(entry.path());
  }
  return found;
}

}  // namespace limber::cli::test
