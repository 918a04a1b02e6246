// An output file that loses nothing: written beside its name (`NAME.part`) and renamed over it
// only when complete, so a failed or interrupted run never leaves half a file under the name
// (a crash leaves the `.part`), never written over one of the run's inputs, and never put in
// place of anything but a regular file: a device (/dev/null, /dev/full), a pipe, a socket or a
// directory at the path is refused before the run, as is one at `NAME.part`. A symbolic link is
// followed: the file it names is replaced and the link stays.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace limber::cli {

/// Where an output for `flag` (e.g. "--out") at `path` will be written: `path`, or the file a
/// symbolic link at `path` names. Throws InputError, creating nothing, when that is one of
/// `inputs` (the same file, however named), a directory, anything else that exists and is not
/// a regular file, a dangling link, or when `NAME.part` exists and is not a regular file.
std::filesystem::path checked_output_path(const std::filesystem::path& path, const std::string& flag,
                                          const std::vector<std::filesystem::path>& inputs);

class OutputFile {
 public:
  /// Opens `NAME.part` for writing, NAME the checked_output_path. `flag` names the flag in
  /// errors ("--out"). Throws InputError as checked_output_path does, or when it cannot be written.
  OutputFile(const std::filesystem::path& path, std::string flag, const std::vector<std::filesystem::path>& inputs);
  /// Removes the `.part` unless commit() ran.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream() { return stream_; }
  /// Throws InputError, before anything more is written, when `bytes` more would not fit in the
  /// space free where the file is written (a run of 10⁹ steps asking for terabytes).
  void require_space(double bytes) const;
  /// Closes the file and renames it over NAME (replacing a regular file there). Throws
  /// InputError when a write failed (a full disk) or the rename did; the `.part` is then removed.
  void commit();

 private:
  std::filesystem::path path_, partial_;
  std::string flag_;
  std::ofstream stream_;
  bool committed_ = false;
};

}  // namespace limber::cli
