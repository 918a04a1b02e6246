#include "tools/cli/output_file.hpp"

#include <system_error>

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

}  // namespace

std::filesystem::path checked_output_path(const std::filesystem::path& path, const std::string& flag,
                                          const std::vector<std::filesystem::path>& inputs) {
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
  const std::filesystem::path partial = target.string() + ".part";
  if (const std::string what = not_replaceable(partial); !what.empty()) {
    throw InputError(named + ": its partial file '" + partial.string() + "' " + what + "; refusing to replace it");
  }
  return target;
}

OutputFile::OutputFile(const std::filesystem::path& path, std::string flag, const std::vector<std::filesystem::path>& inputs)
    : path_(checked_output_path(path, flag, inputs)), partial_(path_.string() + ".part"), flag_(std::move(flag)) {
  stream_.open(partial_, std::ios::binary | std::ios::trunc);
  if (!stream_) throw InputError(flag_ + ": '" + path.string() + "': cannot write " + partial_.string());
}

OutputFile::~OutputFile() {
  if (committed_) return;
  stream_.close();
  std::error_code ignored;
  std::filesystem::remove(partial_, ignored);
}

void OutputFile::require_space(double bytes) const {
  std::error_code error;
  const std::filesystem::path folder = std::filesystem::absolute(partial_, error).parent_path();
  const std::filesystem::space_info space = std::filesystem::space(folder, error);
  if (error || bytes <= double(space.available)) return;  // unknown space: the write itself reports a full disk
  const auto gigabytes = [](double b) { return format("%.3g GB", b / 1e9); };
  throw InputError(flag_ + ": '" + path_.string() + "' would take about " + gigabytes(bytes) + ", more than the " +
                   gigabytes(double(space.available)) + " free in " + folder.string() + " (fewer --steps, or no " + flag_ + ")");
}

void OutputFile::commit() {
  stream_.close();
  std::error_code error;
  if (!stream_) {
    std::filesystem::remove(partial_, error);
    committed_ = true;
    throw InputError(flag_ + ": writing '" + path_.string() + "' failed (disk full?); nothing was written under that name");
  }
  std::filesystem::rename(partial_, path_, error);
  if (error) {
    const std::string why = error.message();
    std::filesystem::remove(partial_, error);
    committed_ = true;
    throw InputError(flag_ + ": cannot rename " + partial_.string() + " to '" + path_.string() + "': " + why);
  }
  committed_ = true;
}

}  // namespace limber::cli
