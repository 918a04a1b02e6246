#!/usr/bin/env bash
# Load + run time and peak memory of the sizes behind "any number" (bench/speed.md, "Linear
# costs"): a long chain, many humanoid copies and many balls, for two limber programs side by
# side (e.g. main's before a change and this build after it), each case given at most LIMIT s.
#
#   bench/linear_costs.sh BEFORE_LIMBER AFTER_LIMBER [LIMIT_S]     (default limit 120 s)
#
# Prints one line a case: the command's arguments, then "seconds peak_MB" for each program
# ("> LIMIT" when it did not finish). /usr/bin/time (Debian's time package) measures both.
set -euo pipefail
cd "$(dirname "$0")/.."
before=$1 after=$2 limit=${3:-120}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for n in 1000 10000; do bench/ball_scene.py "$n" --links 50 > "$tmp/balls_$n.json"; done

measure() {  # LIMBER ARGS...: "seconds peak_MB", or "> LIMIT s"
  local limber=$1; shift
  if timeout "$limit" /usr/bin/time -f "%e %M" -o "$tmp/time" "$limber" "$@" > /dev/null 2> "$tmp/err"; then
    awk '{printf "%.2f s %.0f MB", $1, $2 / 1024}' "$tmp/time"
  else
    echo "> $limit s"
  fi
}
case_row() {  # NAME ARGS...
  local name=$1; shift
  printf '%-44s | %-20s | %s\n' "$name" "$(measure "$before" "$@")" "$(measure "$after" "$@")"
}

printf '%-44s | %-20s | %s\n' case before after
for links in 200000 1000000; do
  case_row "chain.json --links $links --steps 1" run tools/scenes/chain.json --links "$links" --steps 1
done
for copies in 20000 100000; do
  case_row "humanoid --copies $copies --steps 1" run --copies "$copies" --steps 1
done
for method in weighted springs-implicit lagrange featherstone; do
  for n in 1000 10000; do
    case_row "$n balls, 50 links, $method, 10 steps" run "$tmp/balls_$n.json" --method "$method" --steps 10
  done
done
