#!/usr/bin/env bash
# Fuzzes the scene loader, and the methods stepping what it loads, for SECONDS (default 60):
# libFuzzer with AddressSanitizer and UndefinedBehaviorSanitizer on the library and the target
# (tools/fuzz/). Builds it first if needed, in build-fuzz/ (clang 14 from Debian). Exits non-zero
# on a crash, a sanitizer report, an input taking over 1 s, or over 2 GB of memory; the input is
# then in build-fuzz/artifacts/ — keep it in tools/fuzz/regressions/ (ctest replays that folder)
# once it is fixed.
#
#   tools/fuzz.sh [SECONDS] [libFuzzer flags...]
#
# The corpus grows in build-fuzz/corpus/ from the seeds (tools/scenes/, tools/fuzz/regressions/),
# guided by the dictionary of the format's keys (tools/fuzz/scene.dict). Environment:
# LIMBER_FUZZ_DIR (default build-fuzz), LIMBER_SKIP_INSTALL=1 to skip apt-get.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
  echo "fuzz.sh: SECONDS must be a whole number >= 1, got '$seconds'" >&2
  exit 2
fi
build_dir=${LIMBER_FUZZ_DIR:-build-fuzz}
tools/install_packages.sh library clang

flags="-fsanitize=address,undefined,fuzzer-no-link -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14 \
  -DCMAKE_CXX_FLAGS="$flags" -DLIMBER_BUILD_FUZZER=ON -DLIMBER_BUILD_CLI=OFF -DLIMBER_BUILD_TESTS=OFF \
  -DLIMBER_BUILD_EXAMPLES=OFF -DLIMBER_INSTALL=OFF >/dev/null
cmake --build "$build_dir" -j2 --target limber_scene_fuzzer

mkdir -p "$build_dir/corpus" "$build_dir/artifacts"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
exec "$build_dir/tools/fuzz/limber_scene_fuzzer" "$build_dir/corpus" tools/scenes tools/fuzz/regressions \
  -dict=tools/fuzz/scene.dict -max_total_time="$seconds" -timeout=1 -rss_limit_mb=2048 -max_len=65536 \
  -artifact_prefix="$build_dir/artifacts/" -print_final_stats=1 "$@"
