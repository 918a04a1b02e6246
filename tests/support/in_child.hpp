// A call run in a forked child process, for the tests of inputs that once hung or crashed the
// loader (a FIFO as a file, text nested 10⁵ deep): a call that hangs or overflows its stack then
// fails its own test instead of stopping the whole suite. The child's alarm ends a call that runs
// past the limit; the parent waits for the child's output and its end, never for a time.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <exception>
#include <functional>
#include <string>

namespace limber::testing {

/// How a call in a child ended.
struct ChildOutcome {
  std::string output;  ///< what the call returned, or "error: <what()>" when it threw
  int signal = 0;      ///< the signal that ended the child (SIGALRM: it ran past the limit); 0: it finished

  /// For a failed expectation: the signal's name, and whether it was the time limit.
  std::string ending() const {
    if (signal == 0) return "finished";
    return std::string("killed by ") + strsignal(signal) + (signal == SIGALRM ? " (it ran past the time limit: it hung)" : "");
  }
};

/// Runs `call` in a forked child that its alarm ends after `seconds` (generous: a loaded 2-core
/// machine may be slow, but a call that needs more is taken as hung). Returns what it returned
/// or threw, or the signal that ended it.
inline ChildOutcome in_child(const std::function<std::string()>& call, unsigned seconds = 60) {
  int pipe_ends[2];
  if (::pipe(pipe_ends) != 0) return {std::string("pipe: ") + std::strerror(errno), -1};
  const pid_t child = ::fork();
  if (child < 0) return {std::string("fork: ") + std::strerror(errno), -1};
  if (child == 0) {
    ::close(pipe_ends[0]);
    ::alarm(seconds);  // SIGALRM's default action ends the process
    std::string output;
    try {
      output = call();
    } catch (const std::exception& error) {
      output = std::string("error: ") + error.what();
    }
    for (std::size_t written = 0; written < output.size();) {
      const ssize_t count = ::write(pipe_ends[1], output.data() + written, output.size() - written);
      if (count <= 0) break;
      written += static_cast<std::size_t>(count);
    }
    ::_exit(0);  // not exit(): the parent's atexit handlers and buffers are not the child's to run
  }
  ::close(pipe_ends[1]);
  ChildOutcome outcome;
  char buffer[4096];
  for (;;) {
    const ssize_t count = ::read(pipe_ends[0], buffer, sizeof buffer);
    if (count < 0 && errno == EINTR) continue;
    if (count <= 0) break;
    outcome.output.append(buffer, static_cast<std::size_t>(count));
  }
  ::close(pipe_ends[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status)) outcome.signal = WTERMSIG(status);
  return outcome;
}

}  // namespace limber::testing
