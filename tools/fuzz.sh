#!/usr/bin/env bash
# Fuzzes a loader, and the methods stepping what it loads, for SECONDS (default 60): libFuzzer
# with AddressSanitizer and UndefinedBehaviorSanitizer on the library and the target
# (tools/fuzz/). Builds it first if needed, in build-fuzz/ (clang 14 from Debian). Exits non-zero
# on a crash, a sanitizer report, an input taking over 1 s, or over 2 GB of memory; the input is
# then in build-fuzz/artifacts/ — keep it in tools/fuzz/regressions/ (ctest replays that folder;
# name an MJCF input *.xml and a URDF one *.urdf, so the replay reads it as such) once it is fixed.
#
#   tools/fuzz.sh [--target scene|mjcf|urdf] [SECONDS] [libFuzzer flags...]
#
# Targets: scene (the default: JSON scene files, load_scene_text), mjcf (MuJoCo model files:
# parse_mjcf and model_from_mjcf), urdf (URDF robots: parse_urdf). Each corpus grows in
# build-fuzz/corpus/ (scene) or build-fuzz/corpus-TARGET/ from the seeds (scene: tools/scenes/;
# mjcf and urdf: tools/fuzz/seeds/TARGET/, and for mjcf MuJoCo's humanoid.xml when
# libmujoco-samples is installed; all: tools/fuzz/regressions/), guided by the target's
# dictionary (tools/fuzz/TARGET.dict). Environment: LIMBER_FUZZ_DIR (default build-fuzz),
# LIMBER_FUZZ_JOBS (build jobs, default 2), LIMBER_SKIP_INSTALL=1 to skip apt-get.
set -euo pipefail
cd "$(dirname "$0")/.."
target=scene
if [ "${1:-}" = "--target" ]; then
  target=${2:-}
  shift 2 || shift $#
fi
case "$target" in
  scene | mjcf | urdf) ;;
  *) echo "fuzz.sh: --target must be scene, mjcf or urdf, got '$target'" >&2; exit 2 ;;
esac
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
cmake --build "$build_dir" -j"${LIMBER_FUZZ_JOBS:-2}" --target "limber_${target}_fuzzer"

if [ "$target" = scene ]; then
  corpus="$build_dir/corpus"
  seeds=(tools/scenes)
else
  corpus="$build_dir/corpus-$target"
  seeds=("tools/fuzz/seeds/$target")
fi
mkdir -p "$corpus" "$build_dir/artifacts"
humanoid=/usr/share/mujoco/model/humanoid/humanoid.xml
if [ "$target" = mjcf ] && [ -f "$humanoid" ]; then cp "$humanoid" "$corpus/humanoid.xml"; fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
exec "$build_dir/tools/fuzz/limber_${target}_fuzzer" "$corpus" "${seeds[@]}" tools/fuzz/regressions \
  -dict="tools/fuzz/$target.dict" -max_total_time="$seconds" -timeout=1 -rss_limit_mb=2048 -max_len=65536 \
  -artifact_prefix="$build_dir/artifacts/" -print_final_stats=1 "$@"
