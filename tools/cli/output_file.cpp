#include "tools/cli/output_file.hpp"

#include <system_error>

#include "tools/cli/cli.hpp"
#include "tools/cli/run_flags.hpp"

namespace limber::cli {

OutputFile::OutputFile(const std::filesystem::path& path, std::string flag, const std::vector<std::filesystem::path>& inputs)
    : path_(path), partial_(path.string() + ".part"), flag_(std::move(flag)) {
  const std::string named = flag_ + ": '" + path_.string() + "'";
  std::error_code error;
  for (const std::filesystem::path& input : inputs) {
    if (!input.empty() && std::filesystem::equivalent(path_, input, error)) {
      throw InputError(named + " is an input of this run (" + input.string() + "); refusing to write over it");
    }
  }
  if (std::filesystem::is_directory(path_, error)) throw InputError(named + " is a directory");
  stream_.open(partial_, std::ios::binary | std::ios::trunc);
  if (!stream_) throw InputError(named + ": cannot write " + partial_.string());
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
