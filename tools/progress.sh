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
  # The build's output goes to the log and becomes the progress: its [done/total] lines, read
  # line by line as they come (mawk, Debian's awk, reads a pipe in 4 kB blocks: the progress
  # came in bursts minutes apart). The callers run under `set -e -o pipefail`: the list keeps a
  # failed build from ending the script before its error is shown.
  local status=0
  NINJA_STATUS='[%f/%t] ' "$@" 2>&1 | tee "$log" | {
    local line finished total shown=0
    while IFS= read -r line; do
      [[ $line =~ ^\[([0-9]+)/([0-9]+)\] ]] || continue
      finished=${BASH_REMATCH[1]} total=${BASH_REMATCH[2]}
      if [ "$tty" = 1 ]; then
        printf '\r  %d/%d files built' "$finished" "$total"
        shown=1
      elif [ $((10 * finished / total)) -gt "$shown" ]; then
        shown=$((10 * finished / total))
        printf '  %d/%d files built\n' "$finished" "$total"
      fi
    done
    if [ "$tty" = 1 ] && [ "$shown" -gt 0 ]; then printf '\n'; fi
  } >&2 || status=${PIPESTATUS[0]}
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
