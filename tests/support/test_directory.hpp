// A fresh directory for the files of the running test, of its own: ctest runs tests in parallel
// (and CI may run beside another checkout), so a fixed name under /tmp is a race in which one
// test reads the half-written file of another. The process's folder goes when it exits.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

namespace limber::testing {

/// <temp>/limber_tests/<pid>/<Suite.Name>, a parameterized test's '/' as '.': emptied at the
/// test's first call (a reused pid may find an old run's files), kept for its later calls.
inline std::filesystem::path test_directory() {
  // Removed at exit by the process that made it, not by a forked child exiting.
  struct ProcessFolder {
    pid_t owner = ::getpid();
    std::filesystem::path path = std::filesystem::temp_directory_path() / "limber_tests" / std::to_string(owner);
    std::set<std::filesystem::path> made;
    ~ProcessFolder() {
      std::error_code ignored;
      if (::getpid() == owner) std::filesystem::remove_all(path, ignored);
    }
  };
  static ProcessFolder folder;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name();
  std::replace(name.begin(), name.end(), '/', '.');
  const auto dir = folder.path / name;
  if (folder.made.insert(dir).second) std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace limber::testing
