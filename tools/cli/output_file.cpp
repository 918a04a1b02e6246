#include "tools/cli/output_file.hpp"

#include <array>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <random>
#include <streambuf>
#include <system_error>
#include <utility>

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include "tools/cli/cli.hpp"
#include "tools/cli/run_flags.hpp"

namespace limber::cli {

namespace {

// What is at `path` (not following a link), in words, when it is something an output must not
// replace; empty for nothing there or a regular file.
std::string not_replaceable(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::symlink_status(path, error);
  switch (status.type()) {
    case std::filesystem::file_type::not_found:
    case std::filesystem::file_type::regular: return {};
    case std::filesystem::file_type::directory: return "is a directory";
    case std::filesystem::file_type::character: return "is a character device";
    case std::filesystem::file_type::block: return "is a block device";
    case std::filesystem::file_type::fifo: return "is a named pipe";
    case std::filesystem::file_type::socket: return "is a socket";
    case std::filesystem::file_type::symlink: return "is a symbolic link";
    case std::filesystem::file_type::none: return "cannot be examined: " + error.message();
    default: return "is not a regular file";
  }
}

// --- The signal handler's list of temporary files (output_file.hpp) ---

// A slot is free, being filled by the thread that claimed it, or armed: its path is complete
// and the handler unlinks it. The handler reads only armed slots, with lock-free loads.
enum SlotState : int { kFree, kFilling, kArmed };
struct PartialSlot {
  std::atomic<int> state{kFree};
  char path[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler reads the slots' states");
PartialSlot partial_slots[16];

void remove_partials_and_reraise(int signal) {
  const int saved_errno = errno;
  for (PartialSlot& slot : partial_slots) {
    if (slot.state.load() == kArmed) ::unlink(slot.path);
  }
  errno = saved_errno;
  // SA_RESETHAND put the default action back on entry; the signal, blocked while this handler
  // runs, is delivered as it returns and ends the process as it would have without us.
  ::raise(signal);
}

// Installs remove_partials_and_reraise for SIGINT, SIGTERM and SIGHUP, once, where the action is
// the default (an ignored signal stays ignored; a program's own handler stays its own).
void install_signal_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_handler = remove_partials_and_reraise;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&action.sa_mask, signal);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction current {};
      if (::sigaction(signal, nullptr, &current) != 0) continue;
      if ((current.sa_flags & SA_SIGINFO) == 0 && current.sa_handler == SIG_DFL) ::sigaction(signal, &action, nullptr);
    }
  });
}

// Writes `path` down for the handler; returns its slot, or −1 when every slot is taken or the
// path is too long for one (the file is then written, just not removed by a signal).
int arm(const std::filesystem::path& path) {
  const std::string& text = path.native();
  for (int slot = 0; slot < static_cast<int>(std::size(partial_slots)) && text.size() < PATH_MAX; ++slot) {
    int expected = kFree;
    if (!partial_slots[slot].state.compare_exchange_strong(expected, kFilling)) continue;
    std::memcpy(partial_slots[slot].path, text.c_str(), text.size() + 1);
    partial_slots[slot].state.store(kArmed);
    return slot;
  }
  return -1;
}

void disarm(int slot) {
  if (slot >= 0) partial_slots[slot].state.store(kFree);
}

// 64 random bits in hex: the temporary file's own part of its name.
std::string random_hex() {
  std::random_device random;
  const unsigned long long bits = (static_cast<unsigned long long>(random()) << 32) ^ random();
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", bits);
  return text;
}

}  // namespace

// An output buffer over a file descriptor it owns. Writes go through write(2) to the file the
// descriptor was opened on, whatever its name comes to point at; the first failed write is
// kept (errno) and makes every later one fail, so the stream goes bad.
class OutputFile::Buffer : public std::streambuf {
 public:
  Buffer() { setp(space_.data(), space_.data() + space_.size()); }
  ~Buffer() override { close(); }
  void attach(int descriptor) { descriptor_ = descriptor; }

  /// Writes out what is buffered and closes the file; 0, or the errno of the first failure.
  int close() {
    if (descriptor_ < 0) return error_;
    drain();
    if (::close(std::exchange(descriptor_, -1)) != 0 && error_ == 0) error_ = errno;
    return error_;
  }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) *pptr() = traits_type::to_char_type(c), pbump(1);
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  // Writes the buffered bytes and empties the buffer; false once any write has failed.
  bool drain() {
    for (const char* at = pbase(); error_ == 0 && at < pptr();) {
      const ssize_t wrote = ::write(descriptor_, at, static_cast<std::size_t>(pptr() - at));
      if (wrote > 0) at += wrote;
      else if (wrote < 0 && errno != EINTR) error_ = errno;
      else if (wrote == 0) error_ = EIO;
    }
    setp(space_.data(), space_.data() + space_.size());
    return error_ == 0;
  }

  int descriptor_ = -1;
  int error_ = 0;
  std::array<char, 1 << 16> space_;
};

std::filesystem::path checked_output_path(const std::filesystem::path& path, const std::string& flag,
                                          const std::vector<std::filesystem::path>& inputs) {
  if (path.empty()) throw InputError(flag + ": needs a file name, got an empty one");
  const std::string named = flag + ": '" + path.string() + "'";
  std::error_code error;
  for (const std::filesystem::path& input : inputs) {
    if (!input.empty() && std::filesystem::equivalent(path, input, error)) {
      throw InputError(named + " is an input of this run (" + input.string() + "); refusing to write over it");
    }
  }
  std::filesystem::path target = path;
  if (std::filesystem::is_symlink(std::filesystem::symlink_status(path, error))) {
    target = std::filesystem::canonical(path, error);  // follows every link to the file named
    if (error) throw InputError(named + " is a symbolic link to nothing (" + error.message() + ")");
  }
  if (const std::string what = not_replaceable(target); !what.empty()) {
    throw InputError(named + (target == path ? "" : " (a link to '" + target.string() + "')") + " " + what +
                     ", not a regular file; refusing to replace it");
  }
  return target;
}

OutputFile::OutputFile(const std::filesystem::path& path, std::string flag, const std::vector<std::filesystem::path>& inputs)
    : path_(checked_output_path(path, flag, inputs)), flag_(std::move(flag)), buffer_(std::make_unique<Buffer>()) {
  std::error_code error;
  target_ = std::filesystem::absolute(path_, error);  // absolute: the handler and commit() do not depend on the working folder
  if (error) throw InputError(flag_ + ": '" + path.string() + "': " + error.message());
  install_signal_handlers();
  const std::string stem = target_.string() + "." + std::to_string(::getpid()) + ".";
  for (int attempt = 1;; ++attempt) {
    partial_ = stem + random_hex() + ".part";
    // Armed before the file exists, so a signal from here on finds it; a name already taken (64
    // random bits after this process's id: never in practice) is disarmed before another try.
    signal_slot_ = arm(partial_);
    const int descriptor = ::open(partial_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (descriptor >= 0) {
      buffer_->attach(descriptor);
      break;
    }
    const int why = errno;
    disarm(std::exchange(signal_slot_, -1));
    if (why != EEXIST || attempt == 8) {
      throw InputError(flag_ + ": '" + path.string() + "': cannot create " + partial_.string() + ": " + std::strerror(why));
    }
  }
  stream_.rdbuf(buffer_.get());
}

OutputFile::~OutputFile() {
  if (!committed_) discard();
}

void OutputFile::discard() {
  buffer_->close();
  ::unlink(partial_.c_str());
  disarm(std::exchange(signal_slot_, -1));
  committed_ = true;
}

void OutputFile::require_space(double bytes) const {
  std::error_code error;
  const std::filesystem::path folder = partial_.parent_path();
  const std::filesystem::space_info space = std::filesystem::space(folder, error);
  if (error || bytes <= double(space.available)) return;  // unknown space: the write itself reports a full disk
  const auto gigabytes = [](double b) { return format("%.3g GB", b / 1e9); };
  throw InputError(flag_ + ": '" + path_.string() + "' would take about " + gigabytes(bytes) + ", more than the " +
                   gigabytes(double(space.available)) + " free in " + folder.string() + " (fewer --steps, or no " + flag_ + ")");
}

void OutputFile::commit() {
  stream_.flush();
  if (const int error = buffer_->close(); error != 0 || !stream_) {
    discard();
    throw InputError(flag_ + ": writing '" + path_.string() + "' failed (" + std::strerror(error != 0 ? error : EIO) +
                     "); nothing was written under that name");
  }
  if (::rename(partial_.c_str(), target_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    discard();
    throw InputError(flag_ + ": cannot rename " + partial_.string() + " to '" + path_.string() + "': " + why);
  }
  disarm(std::exchange(signal_slot_, -1));
  committed_ = true;
}

}  // namespace limber::cli
