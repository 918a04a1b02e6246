// Reading the files a scene is made of: JSON scenes, MJCF and URDF model files, MJCF includes and
// the model file a JSON scene wraps. One function reads them all, so each is refused the same way
// when it is not something to read whole. Internal to kernel/scene.
//
// Only a regular file is read. A FIFO would block the open (or the read) until some other
// process writes, a device such as /dev/zero never ends, a directory has no text: each is
// refused by what it is. The file's type is checked before it is opened (so a FIFO is never
// opened), then again on the open descriptor (so a file swapped for a FIFO between the two is
// caught), which is opened non-blocking (so even that open returns at once). The size is checked
// against the caller's cap from the file's length and again while reading (a file that grows
// as it is read is stopped at the cap plus one byte).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber::scene_input {

/// What a file is read as, for its cap (scene_file.hpp): a JSON scene (kMaxSceneFileBytes), or an
/// MJCF or URDF model file, an MJCF file's includes counted with it (kMaxModelFileBytes).
enum class FileKind { scene, model };

/// The bytes of the regular file `path`. `already_read`: the bytes of the model's files read
/// before this one (an MJCF include's: the main file's and the other includes'), taken from the
/// cap. Throws ModelError, one line "<path>: <problem>":
/// - "cannot read file: <the system's reason>" (absent, no permission; a directory: "Is a
///   directory");
/// - "cannot read file: not a regular file but a FIFO (...)" (or a character device, a block
///   device, a socket);
/// - "larger than the 64 MiB a scene file may be" (or what is left of a model file's cap).
std::string read_file(const std::filesystem::path& path, FileKind kind, std::size_t already_read = 0);

}  // namespace limber::scene_input
