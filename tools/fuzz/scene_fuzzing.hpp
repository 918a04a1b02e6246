// What the scene fuzzer does with one input: the libFuzzer target (scene_fuzzer.cpp, built with
// clang by tools/fuzz.sh) and the regression replay that ctest runs (replay.cpp, any compiler)
// share it, so a reproducer fails the same way in both.
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

/// Loads `bytes` as a scene file; if it loads and is small, compiles it under configuration
/// `only` (in [0, kConfigurations)) or, without it, under each, and steps it. Returns for every
/// input the kernel handles as documented: a ModelError from the loader, a ModelError or
/// std::invalid_argument from a method that cannot take it, any StepStatus. Aborts, with one
/// line on stderr, on a broken promise: a step reported ok over a non-finite pose, motion or
/// observation. Any other exception is left to escape (a fuzzer reports it as a crash).
void load_and_step(std::string_view bytes, std::optional<std::size_t> only = std::nullopt);

}  // namespace limber::fuzz
