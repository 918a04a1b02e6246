#!/usr/bin/env bash
# tools/progress.sh: a build's progress as a few lines on stderr, its output in the log only, and
# on failure what failed. Runs a stand-in for Ninja.
#   progress_test.sh SOURCE_DIR
set -euo pipefail
cd "$1"
. tools/progress.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "progress_test: $*" >&2; exit 1; }

cat >"$work/fake_build" <<'FAKE'
#!/usr/bin/env bash
for k in $(seq 1 20); do echo "[$k/20] Building CXX object file$k.o"; done
if [ "${1:-}" = fail ]; then echo "FAILED: file21.o"; echo "file21.cpp:3:1: error: boom"; exit 1; fi
FAKE
chmod +x "$work/fake_build"

# A build whose first line must be shown while it still runs: it waits (up to 5 s) for its
# progress line to reach the screen before it goes on.
cat >"$work/slow_build" <<'SLOW'
#!/usr/bin/env bash
echo "[1/2] Building CXX object first.o"
for _ in $(seq 50); do grep -q '1/2 files built' "$1" && break; sleep 0.1; done
grep -q '1/2 files built' "$1" || { echo "the progress line did not come while the build ran"; exit 1; }
echo "[2/2] Linking CXX executable first"
SLOW
chmod +x "$work/slow_build"
quiet_build "$work/slow.log" "$work/slow_build" "$work/slow.err" 2>"$work/slow.err" || fail "progress came late: $(cat "$work/slow.log")"

quiet_build "$work/ok.log" "$work/fake_build" >"$work/ok.out" 2>"$work/ok.err" || fail "a build that passed returned non-zero"
[ ! -s "$work/ok.out" ] || fail "stdout was not empty: $(cat "$work/ok.out")"
[ "$(wc -l <"$work/ok.err")" -eq 10 ] || fail "expected a line at each tenth (10), got: $(cat "$work/ok.err")"
grep -qx '  20/20 files built' "$work/ok.err" || fail "no last line: $(cat "$work/ok.err")"
! grep -q 'Building CXX' "$work/ok.err" || fail "the build's own lines reached the screen"
[ "$(grep -c 'Building CXX' "$work/ok.log")" -eq 20 ] || fail "the log lost lines"

# As the setup scripts call it: under set -e and pipefail.
if bash -euo pipefail -c '. tools/progress.sh; quiet_build "$1" "$2" fail' _ "$work/bad.log" "$work/fake_build" >"$work/bad.out" 2>"$work/bad.err"; then
  fail "a failed build returned zero"
fi
grep -q 'error: boom' "$work/bad.err" || fail "the error was not shown: $(cat "$work/bad.err")"
grep -q "the build failed (exit 1); its whole output is in $work/bad.log" "$work/bad.err" || fail "no closing line: $(cat "$work/bad.err")"
echo "progress_test: ok"
