#!/usr/bin/env bash
# Sets up if needed (tools/setup.sh --tests), builds, and runs the whole test suite with ctest. Exits non-zero on any
# failure. Extra arguments go to ctest (e.g. `tools/test.sh -L stress`, `tools/test.sh -LE stress`).
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${LIMBER_BUILD_DIR:-build}
tools/setup.sh --tests
ctest --test-dir "$build_dir" --output-on-failure -j2 "$@"
