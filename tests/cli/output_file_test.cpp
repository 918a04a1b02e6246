// `--out` writes a temporary file of its own (tools/cli/output_file.hpp) and shares none: two
// runs writing one name at once each leave a whole trajectory, a file already at NAME.part is
// never written through, and SIGINT or SIGTERM leave no temporary file. Runs at once and signals
// need processes: these tests start the program itself (LIMBER_PROGRAM).
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/cli/run_cli.hpp"
#include "tests/support/test_directory.hpp"
#include "tools/cli/cli.hpp"

extern char** environ;

namespace limber::cli {
namespace {

using ::testing::IsEmpty;
using test::Result;
using test::run;
using test::scene;

std::string contents(const std::filesystem::path& path) {
  std::ostringstream text;
  text << std::ifstream(path, std::ios::binary).rdbuf();
  return text.str();
}

// Starts the limber program with `arguments`, its stdout and stderr into `log`, SIGINT and
// SIGTERM at their default actions and unblocked whatever this process has (a test started in
// the background may have SIGINT ignored). Returns its process id, or −1.
pid_t start_program(const std::vector<std::string>& arguments, const std::filesystem::path& log) {
  std::vector<std::string> words{LIMBER_PROGRAM};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t to_default, none;
  sigemptyset(&to_default), sigemptyset(&none);
  sigaddset(&to_default, SIGINT), sigaddset(&to_default, SIGTERM);
  posix_spawnattr_setsigdefault(&attributes, &to_default);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  pid_t pid = -1;
  const int error = posix_spawn(&pid, LIMBER_PROGRAM, &actions, &attributes, argv.data(), environ);
  posix_spawnattr_destroy(&attributes);
  posix_spawn_file_actions_destroy(&actions);
  return error == 0 ? pid : -1;
}

// The process's wait status once it has ended.
int wait_for(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

// Two runs writing one --out at once, of different trajectories (other time steps, other step
// counts): each exits 0, and the file is one run's trajectory, byte for byte, never a mix.
TEST(OutputFile, TwoRunsWritingOneNameAtOnceLeaveOneWholeTrajectory) {
  const std::filesystem::path folder = limber::testing::test_directory();
  const std::string out = (folder / "trajectory.csv").string();
  const std::vector<std::vector<std::string>> runs{
      {"run", scene("chain.json"), "--dt", "0.004", "--steps", "6000"},
      {"run", scene("chain.json"), "--dt", "0.005", "--steps", "5000"}};
  std::vector<pid_t> started;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    std::vector<std::string> arguments = runs[k];
    arguments.insert(arguments.end(), {"--out", out});
    started.push_back(start_program(arguments, folder / ("log" + std::to_string(k))));
    ASSERT_GT(started.back(), 0);
  }
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const int status = wait_for(started[k]);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == kSuccess) << "run " << k << ": " << contents(folder / ("log" + std::to_string(k)));
  }
  const std::string written = contents(out);
  std::vector<std::string> alone;  // each run's trajectory, written alone
  for (std::size_t k = 0; k < runs.size(); ++k) {
    std::vector<std::string> arguments = runs[k];
    const std::string path = (folder / ("alone" + std::to_string(k) + ".csv")).string();
    arguments.insert(arguments.end(), {"--out", path});
    const Result r = run(arguments);
    ASSERT_EQ(r.code, kSuccess) << r.err;
    alone.push_back(contents(path));
  }
  ASSERT_NE(alone[0], alone[1]);
  EXPECT_TRUE(written == alone[0] || written == alone[1])
      << "the file is neither run's trajectory: " << written.size() << " bytes, against " << alone[0].size() << " and " << alone[1].size();
  EXPECT_THAT(test::partial_files(folder), IsEmpty());
  std::filesystem::remove_all(folder);
}

// A file already at NAME.part, here a hard link to another file, is no run's: the run writes a
// temporary file of its own, and the other file keeps its content.
TEST(OutputFile, AFileAlreadyAtNamePartIsNeverWrittenThrough) {
  const std::filesystem::path folder = limber::testing::test_directory();
  const std::filesystem::path out = folder / "trajectory.csv", other = folder / "other.csv";
  std::ofstream(other) << "another file's content\n";
  std::filesystem::create_hard_link(other, out.string() + ".part");
  const Result r = run({"run", scene("chain.json"), "--steps", "5", "--out", out.string()});
  ASSERT_EQ(r.code, kSuccess) << r.err;
  EXPECT_EQ(contents(other), "another file's content\n");
  EXPECT_EQ(std::filesystem::hard_link_count(other), 2u);
  EXPECT_EQ(contents(out).rfind("time,", 0), 0u);
  std::filesystem::remove_all(folder);
}

// An --out that cannot be created is one line naming it, before the run: an empty name, a
// folder that does not exist.
TEST(OutputFile, AnOutThatCannotBeCreatedIsRefusedBeforeTheRun) {
  const std::filesystem::path folder = limber::testing::test_directory();
  for (const std::string& out : {std::string(), (folder / "nowhere" / "trajectory.csv").string()}) {
    const Result r = run({"run", scene("chain.json"), "--steps", "2", "--out", out});
    EXPECT_EQ(r.code, kBadInput) << out;
    EXPECT_EQ(r.out, "") << out;
    EXPECT_EQ(r.err.rfind("limber: --out: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_THAT(test::partial_files(folder), IsEmpty());
  EXPECT_THAT(test::partial_files(std::filesystem::current_path()), IsEmpty());
  std::filesystem::remove_all(folder);
}

// SIGINT or SIGTERM in the middle of a run: the process ends by that signal, its temporary file
// is gone, and the older file under the name is as it was.
void expect_a_signal_leaves_no_temporary_file(int signal) {
  const std::filesystem::path folder = limber::testing::test_directory();
  const std::filesystem::path out = folder / "trajectory.csv", log = folder / "log";
  std::ofstream(out) << "an older result\n";
  const pid_t pid = start_program({"run", scene("stick_in_box.json"), "--steps", "10000000", "--out", out.string()}, log);
  ASSERT_GT(pid, 0);
  // The run is writing once its temporary file is there: wait for it (polling; 2 minutes at most).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  int status = 0;
  bool ended = false;
  while (test::partial_files(folder).empty() && !ended && std::chrono::steady_clock::now() < deadline) {
    ended = waitpid(pid, &status, WNOHANG) == pid;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (ended || test::partial_files(folder).empty()) {
    if (!ended) kill(pid, SIGKILL), wait_for(pid);
    FAIL() << "the run wrote no temporary file" << (ended ? " and ended: " : ": ") << contents(log);
  }
  ASSERT_EQ(kill(pid, signal), 0);
  status = wait_for(pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal) << "wait status " << status << ": " << contents(log);
  EXPECT_THAT(test::partial_files(folder), IsEmpty());
  EXPECT_EQ(contents(out), "an older result\n");
  std::filesystem::remove_all(folder);
}

TEST(OutputFile, SigintLeavesNoTemporaryFile) { expect_a_signal_leaves_no_temporary_file(SIGINT); }
TEST(OutputFile, SigtermLeavesNoTemporaryFile) { expect_a_signal_leaves_no_temporary_file(SIGTERM); }

}  // namespace
}  // namespace limber::cli
