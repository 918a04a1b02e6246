// The libFuzzer entry point of the model-file targets (clang -fsanitize=fuzzer; tools/fuzz.sh
// --target mjcf|urdf builds and runs them): compiled once per target, LIMBER_FUZZ_TARGET naming
// it (mjcf or urdf). Each input that loads is stepped under Featherstone and under one more
// configuration picked by a hash of its bytes; the replay (replay.cpp) steps all of them.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string_view>

#include "tools/fuzz/scene_fuzzing.hpp"

#ifndef LIMBER_FUZZ_TARGET
#error "LIMBER_FUZZ_TARGET must name the target: mjcf or urdf"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  limber::fuzz::load_and_step(limber::fuzz::Target::LIMBER_FUZZ_TARGET, bytes,
                              std::hash<std::string_view>{}(bytes) % limber::fuzz::kConfigurations);
  return 0;
}
