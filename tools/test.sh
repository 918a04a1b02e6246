#!/usr/bin/env bash
# Sets up if needed (tools/setup.sh --tests), builds, and runs the whole test suite with ctest. Exits non-zero on any
# failure. Extra arguments go to ctest (e.g. `tools/test.sh -LE stress`, `tools/test.sh -L stress`).
#
#   tools/test.sh [--sanitize] [ctest arguments...]
#
# --sanitize (what CI runs, .ci/run): after the suite, the sanitizer runs in their shortened form,
# tools/sanitize.sh address -LE stress (ASan + UBSan + LeakSanitizer over every test but the long
# stress runs, which the suite has just run uninstrumented) and tools/sanitize.sh thread (the
# threaded tests under ThreadSanitizer); each builds with clang 14 in a folder of its own.
set -euo pipefail
cd "$(dirname "$0")/.."
sanitize=0
if [ "${1:-}" = --sanitize ]; then sanitize=1; shift; fi
build_dir=${LIMBER_BUILD_DIR:-build}
tools/setup.sh --tests
. tools/progress.sh
stage "running the tests (ctest -j2, about 2 min; -LE stress skips the long runs)"
ctest --test-dir "$build_dir" --output-on-failure -j2 "$@"
if [ $sanitize = 1 ]; then
  tools/sanitize.sh address -LE stress
  tools/sanitize.sh thread
fi
