# Progress for the setup, test and sanitizer scripts (sourced, not run): a line for each stage,
# and a build's progress on one line that updates in a terminal (a line at each tenth of the way
# elsewhere, as in a CI log). What the tools print — apt-get, the compiler — goes to a log, shown
# only when the step fails.
#
#   . tools/progress.sh
#   stage "building the library"          # "limber: building the library" on stderr
#   quiet_build LOG cmake --build build   # runs the build, its output in LOG

stage() { printf 'limber: %s\n' "$*" >&2; }

# Runs a Ninja build ("$@"), its whole output in LOG, showing [done/total] as it goes. On failure
# prints what failed (from the first FAILED: line, at most 80 lines) and the log's name, and
# returns the build's status.
quiet_build() {
  local log=$1
  shift
  local tty=0
  if [ -t 2 ]; then tty=1; fi
  # The build's output goes to the log and, through awk, becomes the progress: its
  # [done/total] lines. The callers run under `set -e -o pipefail`: the list keeps a failed
  # build from ending the script before its error is shown.
  local status=0
  NINJA_STATUS='[%f/%t] ' "$@" 2>&1 | tee "$log" | awk -v tty="$tty" '
    match($0, /^\[[0-9]+\/[0-9]+\]/) {
      split(substr($0, 2, RLENGTH - 2), n, "/")
      if (tty == 1) { printf "\r  %d/%d files built", n[1], n[2]; fflush() }
      else if (int(10 * n[1] / n[2]) > shown) { shown = int(10 * n[1] / n[2]); printf "  %d/%d files built\n", n[1], n[2]; fflush() }
    }
    END { if (tty == 1 && NR > 0) printf "\n" }' >&2 || status=${PIPESTATUS[0]}
  if [ "$status" -ne 0 ]; then
    if grep -q '^FAILED:' "$log"; then
      sed -n '/^FAILED:/,$p' "$log" | head -n 80 >&2
    else
      tail -n 40 "$log" >&2
    fi
    printf 'limber: the build failed (exit %d); its whole output is in %s\n' "$status" "$log" >&2
  fi
  return "$status"
}
