// Replays saved fuzzer inputs through the fuzzers' own body (scene_fuzzing.hpp), with any
// compiler: `limber_fuzz_replay [--target scene|mjcf|urdf] FILE_OR_DIRECTORY...`. Without
// --target each file is read as its name says (".xml" MJCF, ".urdf" URDF, else a JSON scene).
// ctest runs it over tools/fuzz/regressions/ (every input that once broke a promise), the seed
// scenes and the model-file seeds (tools/fuzz/seeds/). Exits 0 when each returned; a broken
// promise aborts, as it does under the fuzzer.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tools/fuzz/scene_fuzzing.hpp"

namespace {

std::vector<std::filesystem::path> inputs_of(const std::filesystem::path& argument) {
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_directory(argument)) {
    for (const auto& entry : std::filesystem::directory_iterator(argument)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
  } else {
    files.push_back(argument);
  }
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  int first = 1;
  std::optional<limber::fuzz::Target> target;
  if (argc > 2 && std::string_view(argv[1]) == "--target") {
    target = limber::fuzz::target_named(argv[2]);
    if (!target) {
      std::fprintf(stderr, "limber_fuzz_replay: --target: expected scene, mjcf or urdf, got '%s'\n", argv[2]);
      return 2;
    }
    first = 3;
  }
  if (argc <= first) {
    std::fprintf(stderr, "usage: limber_fuzz_replay [--target scene|mjcf|urdf] FILE_OR_DIRECTORY...\n");
    return 2;
  }
  int replayed = 0;
  for (int k = first; k < argc; ++k) {
    if (!std::filesystem::exists(argv[k])) {
      std::fprintf(stderr, "limber_fuzz_replay: %s: no such file or directory\n", argv[k]);
      return 2;
    }
    for (const std::filesystem::path& file : inputs_of(argv[k])) {
      std::ifstream in(file, std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      std::printf("%s\n", file.c_str());
      std::fflush(stdout);  // the last name printed is the input that aborted
      limber::fuzz::load_and_step(target.value_or(limber::fuzz::target_of_file(file.string())), bytes);
      ++replayed;
    }
  }
  std::printf("replayed %d inputs\n", replayed);
  return replayed > 0 ? 0 : 1;
}
