#!/usr/bin/env bash
# Installs the Debian 12 packages a purpose needs, only the missing ones (apt-get; sudo when not
# root). The one list of limber's packages: tools/setup.sh, tools/fuzz.sh and the sanitizer runs
# call it. LIMBER_SKIP_INSTALL=1 skips it.
#
#   tools/install_packages.sh PURPOSE...
#
#   library   the library and the `limber` program (compiler, CMake, Ninja and make — an installed
#             package's client may configure with either —, Eigen, oneTBB, xsimd,
#             nlohmann-json, pugixml (the MJCF reader), CLI11, libccd (general convex pairs))
#   tests     GoogleTest, GoogleMock, MuJoCo (the Featherstone and MJCF cross-checks) and its
#             sample models (/usr/share/mujoco/model: the MJCF reader's humanoid tests)
#   viewer    GLFW, OpenGL (Mesa), Dear ImGui, stb; Xvfb, which runs it headless
#   bench     Google Benchmark, the peer engines (MuJoCo, Bullet, ODE), libccd and FCL
#             (bench/convex_pairs), matplotlib (tools/plot_*.py), valgrind
#             (tools/cachegrind_layouts.sh)
#   clang     clang 14 and its runtimes (libFuzzer, the sanitizers) and llvm-symbolizer: the fuzzer
#             and the sanitizer runs build with it
#   python    Python 3's headers, pybind11, NumPy and pytest: the module `limber` and its tests;
#             pandas and Dask distributed: its sweeps (limber.sweep)
set -euo pipefail
packages=()
for purpose in "$@"; do
  case "$purpose" in
    library) packages+=(g++ cmake ninja-build make pkg-config libeigen3-dev libtbb-dev libxsimd-dev nlohmann-json3-dev libpugixml-dev libcli11-dev libccd-dev) ;;
    tests) packages+=(libgtest-dev libgmock-dev libmujoco-dev libmujoco-samples) ;;
    viewer) packages+=(libglfw3-dev libgl-dev libimgui-dev libstb-dev xvfb xauth libgl1-mesa-dri) ;;
    bench) packages+=(libbenchmark-dev libmujoco-dev libbullet-dev libode-dev libccd-dev libfcl-dev python3-matplotlib valgrind) ;;
    clang) packages+=(clang-14 libclang-rt-14-dev llvm-14) ;;
    python) packages+=(python3-dev pybind11-dev python3-numpy python3-pytest python3-pandas python3-distributed) ;;
    *) echo "install_packages.sh: unknown purpose '$purpose' (expected library, tests, viewer, bench, clang or python)" >&2; exit 2 ;;
  esac
done
if [ "${LIMBER_SKIP_INSTALL:-0}" = 1 ]; then exit 0; fi
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then exit 0; fi
# apt-get's own output goes to a log, shown only when it fails.
echo "limber: installing ${#missing[@]} Debian packages: ${missing[*]}" >&2
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
log=$(mktemp "${TMPDIR:-/tmp}/limber-apt.XXXXXX.log")
if ! { "${sudo_cmd[@]}" apt-get update -qq && DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
  tail -n 40 "$log" >&2
  echo "install_packages.sh: apt-get failed; its whole output is in $log" >&2
  exit 1
fi
rm -f "$log"
