// An output file that loses nothing and shares nothing: written to a temporary file of its own
// beside its name (`NAME.<pid>.<random>.part`, created with O_EXCL, so two runs writing one NAME
// never share it and a file already there, a hard link included, is never written through) and
// renamed over NAME only when complete (rename(2): atomic), so a failed or interrupted run never
// leaves half a file under the name and two runs at once each leave a whole trajectory, the last
// to finish its own. The temporary file is removed on every error path and on SIGINT, SIGTERM
// and SIGHUP (below); a crash or SIGKILL leaves it, and NAME as it was. Never written over one
// of the run's inputs, and never put in place of anything but a regular file: a device
// (/dev/null, /dev/full), a pipe, a socket or a directory at the path is refused before the run.
// A symbolic link is followed: the file it names is replaced and the link stays.
//
// Signals: while an OutputFile is open, a handler for SIGINT, SIGTERM and SIGHUP (installed
// once, only where the signal's action is the default: an ignored signal or a program's own
// handler is left alone) unlinks every open OutputFile's temporary file, by paths written down
// when each was created (absolute, in fixed buffers: the handler allocates nothing and calls
// only unlink and raise), then re-raises the signal with its default action, so the process
// ends as the signal says. Up to 16 files at once have this (more are written, just not removed
// by a signal).
#pragma once

#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace limber::cli {

/// Where an output for `flag` (e.g. "--out") at `path` will be written: `path`, or the file a
/// symbolic link at `path` names. Throws InputError, creating nothing, when `path` is empty, or
/// that is one of `inputs` (the same file, however named), a directory, anything else that
/// exists and is not a regular file, or a dangling link.
std::filesystem::path checked_output_path(const std::filesystem::path& path, const std::string& flag,
                                          const std::vector<std::filesystem::path>& inputs);

class OutputFile {
 public:
  /// Creates the temporary file beside NAME, the checked_output_path, for writing. `flag` names
  /// the flag in errors ("--out"). Throws InputError as checked_output_path does, or when the
  /// file cannot be created (a read-only folder, a folder that does not exist).
  OutputFile(const std::filesystem::path& path, std::string flag, const std::vector<std::filesystem::path>& inputs);
  /// Removes the temporary file unless commit() ran.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream() { return stream_; }
  /// The temporary file being written (absolute).
  const std::filesystem::path& partial_path() const { return partial_; }
  /// Throws InputError, before anything more is written, when `bytes` more would not fit in the
  /// space free where the file is written (a run of 10⁹ steps asking for terabytes).
  void require_space(double bytes) const;
  /// Closes the file and renames it over NAME (replacing a regular file there). Throws
  /// InputError when a write failed (a full disk) or the rename did; the temporary file is
  /// then removed.
  void commit();

 private:
  class Buffer;  // the stream's buffer: write(2) on the descriptor O_EXCL opened (output_file.cpp)
  void discard();

  std::filesystem::path path_;     ///< NAME as checked (errors name it)
  std::filesystem::path target_;   ///< NAME, absolute: what commit() renames onto
  std::filesystem::path partial_;  ///< the temporary file, absolute
  std::string flag_;
  std::unique_ptr<Buffer> buffer_;
  std::ostream stream_{nullptr};
  int signal_slot_ = -1;           ///< where the signal handler finds partial_; −1: none
  bool committed_ = false;
};

}  // namespace limber::cli
