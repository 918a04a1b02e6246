// The one reader of scene, model and include files (input_file.hpp): POSIX open, fstat and read,
// so that the file's type is known before anything blocks on it.
#include "limber/kernel/scene/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

#include "limber/kernel/model/model.hpp"  // ModelError
#include "limber/kernel/scene/scene_file.hpp"  // the caps

namespace limber::scene_input {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& problem) { throw ModelError(path + ": " + problem); }

[[noreturn]] void fail_errno(const std::string& path, int error) {
  fail(path, std::string("cannot read file: ") + std::strerror(error));
}

// Refuses anything but a regular file, by what it is.
void require_regular(const std::string& path, const struct stat& status) {
  const mode_t mode = status.st_mode;
  if (S_ISREG(mode)) return;
  if (S_ISDIR(mode)) fail_errno(path, EISDIR);
  const char* kind = S_ISFIFO(mode)  ? "a FIFO (a named pipe: reading it would wait for a writer)"
                     : S_ISCHR(mode) ? "a character device (such as /dev/zero: it may never end)"
                     : S_ISBLK(mode) ? "a block device"
                     : S_ISSOCK(mode) ? "a socket"
                                      : "of an unknown kind";
  fail(path, std::string("cannot read file: not a regular file but ") + kind);
}

// Closes the descriptor however the read ends.
struct Descriptor {
  int fd = -1;
  ~Descriptor() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

std::string read_file(const std::filesystem::path& path, FileKind kind, std::size_t already_read) {
  const std::string name = path.string();
  const std::size_t cap = kind == FileKind::scene ? kMaxSceneFileBytes : kMaxModelFileBytes;
  const std::size_t max_bytes = cap - std::min(already_read, cap);
  const auto too_large = [&] {
    const std::string mib = std::to_string(cap >> 20) + " MiB";
    if (kind == FileKind::scene) fail(name, "larger than the " + mib + " a scene file may be");
    if (already_read == 0) fail(name, "larger than the " + mib + " a model file may be (with its includes)");
    fail(name, "larger than the " + std::to_string(max_bytes) + " bytes left of the " + mib + " a model file and its includes may have");
  };
  struct stat status {};
  if (::stat(name.c_str(), &status) != 0) fail_errno(name, errno);
  require_regular(name, status);
  if (static_cast<std::uintmax_t>(status.st_size) > max_bytes) too_large();
  Descriptor file;
  do {
    file.fd = ::open(name.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  } while (file.fd < 0 && errno == EINTR);
  if (file.fd < 0) fail_errno(name, errno);
  if (::fstat(file.fd, &status) != 0) fail_errno(name, errno);
  require_regular(name, status);  // the path may name another file than the one stat saw
  std::string text;
  text.reserve(std::min(static_cast<std::size_t>(status.st_size), max_bytes) + 1);
  char buffer[1 << 16];
  for (;;) {
    const std::size_t want = std::min(sizeof buffer, max_bytes + 1 - text.size());
    const ssize_t count = ::read(file.fd, buffer, want);
    if (count < 0 && errno == EINTR) continue;
    if (count < 0) fail_errno(name, errno);
    if (count == 0) break;
    text.append(buffer, static_cast<std::size_t>(count));
    if (text.size() > max_bytes) too_large();
  }
  return text;
}

}  // namespace limber::scene_input
