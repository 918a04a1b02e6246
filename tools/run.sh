#!/usr/bin/env bash
# The main job: sets up if needed, then runs `limber`. With no arguments (or only flags) it runs
# `limber run tools/scenes/ragdoll.json` with those flags: the thesis's humanoid with arms and
# human joint ranges, knocked over by the ball. Otherwise the arguments go to limber unchanged
# (`limber run` without a scene still runs the thesis's own humanoid, compiled into the program):
#   tools/run.sh
#   tools/run.sh --body thin --ball-speed 12 --method lagrange
#   tools/run.sh run                                   # the thesis's humanoid, as in the thesis
#   tools/run.sh run tools/scenes/chain.json --links 100
#   tools/run.sh view                                  # the viewer (installs GLFW, ImGui first)
#   tools/run.sh view tools/scenes/volley.json --method featherstone
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${LIMBER_BUILD_DIR:-build}
setup_flags=()
if [ "${1:-}" = view ]; then setup_flags=(--viewer); fi
tools/setup.sh "${setup_flags[@]}"  # a line for each stage and the build's progress; the tools' output only on failure
if [ $# -eq 0 ] || [[ "$1" == -* && "$1" != "--help" && "$1" != "--version" ]]; then
  set -- run tools/scenes/ragdoll.json "$@"
fi
exec "$build_dir/tools/limber" "$@"
