#!/usr/bin/env bash
# Installs the Debian packages limber needs (only the missing ones), then configures and builds
# what was asked for: the library and the `limber` program by default, the viewer with --viewer,
# the test suite with --tests, the benchmarks and studies (and the other engines they compare
# with) with --bench, the Python module with --python (or --tests).
#
#   tools/setup.sh [--viewer] [--tests] [--bench] [--python] [--portable] [--debug]
#
#   --viewer     also GLFW, OpenGL (Mesa), Dear ImGui and stb: `limber view`; and Xvfb, which runs it
#                headless (xvfb-run -a limber view SCENE --frames N --screenshot out.png)
#   --tests      also GoogleTest, GoogleMock and MuJoCo (the Featherstone cross-check), and the
#                viewer's packages (its tests render under Xvfb), and --python's (its tests are
#                the suite's too); builds the tests
#   --bench      also Google Benchmark, Bullet, ODE, libccd, FCL and matplotlib; builds bench/ (LIMBER_BUILD_BENCHMARKS)
#   --python     also python3-dev, pybind11, NumPy, pytest, pandas and Dask; builds the module `limber`
#                (build/python/limber: PYTHONPATH=build/python; LIMBER_BUILD_PYTHON)
#   --portable   build for baseline x86-64 instead of -march=native
#   --debug      Debug build instead of Release
#
# What a build directory was once configured with (tests, benchmarks) it keeps, but a call
# without --tests or --bench builds only the library and the program: `tools/run.sh` after
# `tools/test.sh` neither drops nor rebuilds the tests. The build is a unity build
# (CMAKE_UNITY_BUILD, as the sanitizers' are: eight files of a target compiled as one, so the
# Eigen templates they share compile once a batch): the suite builds in 8.2 min from nothing on 2
# cores against 12.5 file by file (ninja's log, g++ 12, 2026-11-28), and a header edit rebuilds
# sooner; an edit of one .cpp recompiles its batch. LIMBER_UNITY_BUILD=OFF builds file by file.
# Environment: LIMBER_BUILD_DIR (default: build), LIMBER_SKIP_INSTALL=1 to skip apt-get.
set -euo pipefail
cd "$(dirname "$0")/.."

native=ON
build_type=Release
tests=OFF
bench=OFF
python=OFF
viewer=OFF
for arg in "$@"; do
  case "$arg" in
    --viewer) viewer=ON ;;
    --tests) tests=ON; viewer=ON; python=ON ;;
    --bench) bench=ON ;;
    --python) python=ON ;;
    --portable) native=OFF ;;
    --debug) build_type=Debug ;;
    *) echo "setup.sh: unknown option '$arg' (expected --viewer, --tests, --bench, --python, --portable or --debug)" >&2; exit 2 ;;
  esac
done
build_dir=${LIMBER_BUILD_DIR:-build}
build_all=OFF
if [ "$tests" = ON ] || [ "$bench" = ON ]; then build_all=ON; fi
if [ -f "$build_dir/CMakeCache.txt" ]; then
  grep -q '^LIMBER_BUILD_TESTS:BOOL=ON' "$build_dir/CMakeCache.txt" && tests=ON
  grep -q '^LIMBER_BUILD_BENCHMARKS:BOOL=ON' "$build_dir/CMakeCache.txt" && bench=ON
  grep -q '^LIMBER_BUILD_PYTHON:BOOL=ON' "$build_dir/CMakeCache.txt" && python=ON
fi

# Debian 12 packages: the library's, and the tests', the viewer's and the benchmarks' on request.
purposes=(library)
if [ "$tests" = ON ]; then purposes+=(tests); fi
if [ "$viewer" = ON ]; then purposes+=(viewer); fi
if [ "$bench" = ON ]; then purposes+=(bench); fi
if [ "$python" = ON ]; then purposes+=(python); fi
tools/install_packages.sh "${purposes[@]}"

# Configure once (or again when the options change), then build only what was asked for. The
# compiler's output goes to $build_dir/build.log, shown when the build fails.
. tools/progress.sh
mkdir -p "$build_dir"
if ! cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" -DLIMBER_NATIVE="$native" \
  -DLIMBER_BUILD_TESTS="$tests" -DLIMBER_BUILD_BENCHMARKS="$bench" -DLIMBER_BUILD_PYTHON="$python" \
  -DCMAKE_UNITY_BUILD="${LIMBER_UNITY_BUILD:-ON}" >"$build_dir/configure.log" 2>&1; then
  cat "$build_dir/configure.log" >&2
  stage "configuring $build_dir/ failed (above)"
  exit 1
fi
what="the library and the limber program"
if [ "$build_all" = ON ]; then
  [ "$tests" = ON ] && what="$what, the tests"
  [ "$bench" = ON ] && what="$what, the benchmarks"
  stage "building $what in $build_dir/ ($build_type; about 10 min from nothing on 2 cores, seconds when up to date)"
  quiet_build "$build_dir/build.log" cmake --build "$build_dir" -j2
else
  targets=(limber_program)
  if [ "$python" = ON ]; then targets+=(limber_python); what="$what, the Python module"; fi
  stage "building $what in $build_dir/ ($build_type; about 3 min from nothing on 2 cores, seconds when up to date)"
  quiet_build "$build_dir/build.log" cmake --build "$build_dir" -j2 --target "${targets[@]}"
fi
