// What the fuzzers do with one input: the libFuzzer targets (scene_fuzzer.cpp for JSON scenes,
// model_fuzzer.cpp for MJCF and URDF model files, built with clang by tools/fuzz.sh) and the
// regression replay that ctest runs (replay.cpp, any compiler) share it, so a reproducer fails
// the same way in both.
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>

namespace limber::fuzz {

/// Most bodies a fuzzed scene may generate (SceneOptions::max_bodies): the loader's own guard is
/// 10⁷, which a fuzzer would meet as a timeout, not as a defect.
inline constexpr std::size_t kMaxBodies = 2000;
/// Most triangles of a fuzzed scene's colliders (SceneOptions::max_triangles; the loader's guard
/// is 10⁶, ~16 s to load and step once).
inline constexpr std::size_t kMaxTriangles = 20000;
/// Scenes up to this many bodies are also stepped. Contacts can grow as its square (fat limbs
/// all overlapping) and Featherstone's contact solve costs bodies × contacts per sweep: 25 fat
/// links took 1.1 s under the sanitizers and the coverage instrumentation (20 ms in Release).
inline constexpr std::size_t kMaxSteppedBodies = 16;
/// Steps each configuration takes, and the caps on the relaxation's sweeps and substeps a scene
/// may ask for (up to 10⁵ and 10⁴: minutes per step, the user's choice, but not a fuzzer's).
inline constexpr int kSteps = 4, kSweepCap = 30, kSubstepCap = 3;
/// The configurations stepped: particles (double, float, and the direct solver), springs,
/// Lagrange, Featherstone.
inline constexpr std::size_t kConfigurations = 6;

/// What an input is read as: a JSON scene (load_scene_text), an MJCF model (parse_mjcf and
/// model_from_mjcf) or a URDF robot (parse_urdf).
enum class Target { scene, mjcf, urdf };

/// The target a file name's extension stands for: ".xml" MJCF, ".urdf" URDF, anything else a scene.
Target target_of_file(std::string_view file_name);
/// The target called `name` ("scene", "mjcf", "urdf"), or nullopt.
std::optional<Target> target_named(std::string_view name);

/// Loads `bytes` as a scene file; if it loads and is small, compiles it under configuration
/// `only` (in [0, kConfigurations)) or, without it, under each, and steps it. Returns for every
/// input the kernel handles as documented: a ModelError from the loader, a ModelError or
/// std::invalid_argument from a method that cannot take it, any StepStatus. Aborts, with one
/// line on stderr, on a broken promise: a step reported ok over a non-finite pose, motion or
/// observation. Any other exception is left to escape (a fuzzer reports it as a crash).
void load_and_step(std::string_view bytes, std::optional<std::size_t> only = std::nullopt);

/// Loads `bytes` as model file `target` (the scene target: load_and_step above) with the loader's
/// own limits, and steps what loads (at most kMaxSteppedBodies bodies) under Featherstone, then
/// under configuration `only` too or, without it, under every one. The promises are the scene
/// target's. An MJCF input is named as a file in a fresh temporary directory (its includes
/// resolve there), which holds one file, "part.xml", for <include> to splice; an input with an
/// <include file> that is more than a plain name (absolute, or with a directory part: it could
/// reach any file of the machine) is not loaded at all, so a fuzzed include reads nothing else.
/// A URDF input floats its base or not by a hash of its bytes.
void load_and_step(Target target, std::string_view bytes, std::optional<std::size_t> only = std::nullopt);

}  // namespace limber::fuzz
