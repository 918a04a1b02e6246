// The libFuzzer entry point (clang -fsanitize=fuzzer; tools/fuzz.sh builds and runs it). Each
// input is stepped under one configuration, picked by a hash of its bytes, so an input stays
// well inside the 1 s limit under the sanitizers; the replay (replay.cpp) steps all of them.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string_view>

#include "tools/fuzz/scene_fuzzing.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  limber::fuzz::load_and_step(bytes, std::hash<std::string_view>{}(bytes) % limber::fuzz::kConfigurations);
  return 0;
}
