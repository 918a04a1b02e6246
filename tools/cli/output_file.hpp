// An output file that loses nothing: written beside its name (`NAME.part`) and renamed over it
// only when complete, so a failed or interrupted run never leaves half a file under the name
// (a crash leaves the `.part`), and never written over one of the run's inputs.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace limber::cli {

class OutputFile {
 public:
  /// Opens `path`.part for writing. `flag` names the flag in errors ("--out"). Throws
  /// InputError when `path` is one of `inputs` (the same file, however named), a directory, or
  /// cannot be written.
  OutputFile(const std::filesystem::path& path, std::string flag, const std::vector<std::filesystem::path>& inputs);
  /// Removes the `.part` unless commit() ran.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream() { return stream_; }
  /// Throws InputError, before anything more is written, when `bytes` more would not fit in the
  /// space free where the file is written (a run of 10⁹ steps asking for terabytes).
  void require_space(double bytes) const;
  /// Closes the file and renames it over `path`. Throws InputError when a write failed (a full
  /// disk) or the rename did; the `.part` is then removed.
  void commit();

 private:
  std::filesystem::path path_, partial_;
  std::string flag_;
  std::ofstream stream_;
  bool committed_ = false;
};

}  // namespace limber::cli
