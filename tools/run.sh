#!/usr/bin/env bash
# The main job: sets up if needed, then runs `limber`. With no arguments (or only flags) it runs
# `limber run` on the embedded humanoid scene; otherwise the arguments go to limber unchanged:
#   tools/run.sh
#   tools/run.sh --body thin --ball-speed 12
#   tools/run.sh run tools/scenes/chain.json --links 100
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${LIMBER_BUILD_DIR:-build}
if ! setup_log=$(tools/setup.sh 2>&1); then
  printf '%s\n' "$setup_log" >&2
  exit 1
fi
if [ $# -eq 0 ] || [[ "$1" == -* && "$1" != "--help" && "$1" != "--version" ]]; then
  set -- run "$@"
fi
exec "$build_dir/tools/limber" "$@"
