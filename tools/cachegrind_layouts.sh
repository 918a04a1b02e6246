#!/usr/bin/env bash
# Cache behaviour of the particle layouts (soa, aos, aosoa) and orderings (depth-parity,
# breadth-first, reverse Cuthill-McKee, shuffled) under cachegrind: a 100000-link chain, 1 thread,
# 10 sweeps a step, double. Each case runs `limber run` for 21 steps and for 1 step and prints the
# difference, so the table covers exactly 20 steps, not loading and compiling the scene. Takes
# about 14 minutes (818 s on the shared 2-core VM, load average 3, given an AVX2 build).
#
#   tools/cachegrind_layouts.sh [BUILD_DIR]        (default: build-valgrind, built if missing)
#
# Valgrind 3.19 cannot run AVX-512 code, so the default build directory is an AVX2 build
# (-march=x86-64-v3) made here; its AoS path gathers instead of transposing records (that path
# is AVX-512 only). tools/setup.sh --bench installs valgrind.
# The simulated last-level cache is one core's 2 MiB L2 (valgrind would otherwise take the
# VM's 480 MiB L3, which holds the whole working set); CACHEGRIND_LL=size,assoc,line_size
# overrides it.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-valgrind}
if [ "$build" = build-valgrind ]; then
  echo "cachegrind_layouts: building $build (AVX2)" >&2
  [ -f "$build/build.ninja" ] ||
    cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DLIMBER_NATIVE=OFF -DCMAKE_CXX_FLAGS=-march=x86-64-v3 >/dev/null
  cmake --build "$build" -j2 --target limber_program >/dev/null
fi
limber=$build/tools/limber
links=100000

command -v valgrind >/dev/null || { echo "cachegrind_layouts: valgrind not found (tools/setup.sh --bench installs it)" >&2; exit 1; }
[ -x "$limber" ] || { echo "cachegrind_layouts: $limber not found; build the limber_program target" >&2; exit 1; }
orderings=(depth-parity breadth-first rcm shuffled)
if ! "$limber" run --help | grep -q -- --ordering; then
  orderings=(default)
  echo "Note: this limber has no --ordering option yet; measuring the layouts only."
fi
valgrind_opts=(--tool=cachegrind --cache-sim=yes --cachegrind-out-file=/dev/null -v)
valgrind_opts+=("--LL=${CACHEGRIND_LL:-2097152,16,64}")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# measure LAYOUT ORDERING STEPS: prints "D_refs D1_misses LLd_misses I_refs" of one run.
measure() {
  local log="$tmp/$1-$2-$3.log"
  # One substep of 10 sweeps a step, as the table states (the default is now 16 substeps: 16 times
  # the sweeps, and hours under cachegrind).
  local args=(run tools/scenes/chain.json --links "$links" --threads 1 --iterations 10 --substeps 1 --steps "$3"
              --layout "$1" --precision double)
  [ "$2" != default ] && args+=(--ordering "$2")
  if ! valgrind "${valgrind_opts[@]}" "$limber" "${args[@]}" >/dev/null 2>"$log"; then
    grep -q "Unrecognised instruction" "$log" &&
      echo "cachegrind_layouts: valgrind cannot run $limber (AVX-512?); see this script's header for an AVX2 build" >&2
    tail -n 20 "$log" >&2
    exit 1
  fi
  cp "$log" "$tmp/last.log"
  awk '/== I +refs:/ {i = $4} /== D +refs:/ {d = $4} /== D1 +misses:/ {d1 = $4} /== LLd +misses:/ {ll = $4}
       END {gsub(",", "", i); gsub(",", "", d); gsub(",", "", d1); gsub(",", "", ll); print d, d1, ll, i}' "$log"
}

start=$SECONDS
rows=()
for layout in soa aos aosoa; do
  for ordering in "${orderings[@]}"; do
    echo "cachegrind_layouts: $layout, $ordering" >&2
    long=$(measure "$layout" "$ordering" 21)
    short=$(measure "$layout" "$ordering" 1)
    read -r d21 m21 l21 i21 <<<"$long"
    read -r d1 m1 l1 i1 <<<"$short"
    rows+=("$(awk -v l="$layout" -v o="$ordering" -v d=$((d21 - d1)) -v m=$((m21 - m1)) -v ll=$((l21 - l1)) -v i=$((i21 - i1)) \
      'BEGIN {if (ll < 0) ll = 0; printf "| %s | %s | %.1f | %.2f | %.2f | %.3f | %.3f | %.1f |", l, o, d / 1e6, m / 1e6, 100 * m / d, ll / 1e6, 100 * ll / d, i / 1e6}')")
  done
done

echo "## Cachegrind: $links-link chain, 20 steps × 10 sweeps, 1 thread ($limber, run's default precision)"
echo
echo "| layout | ordering | D refs (M) | D1 misses (M) | D1 miss rate % | LLd misses (M) | LLd miss rate % | I refs (M) |"
echo "|---|---|---:|---:|---:|---:|---:|---:|"
printf '%s\n' "${rows[@]}"
echo
echo "Miss rates are misses per data reference (LLd: a difference below 0, noise, shows as 0)."
echo "Cache geometry valgrind simulated (CACHEGRIND_LL=size,assoc,line_size sets the LL):"
echo
grep -A3 "Cache configuration used" "$tmp/last.log" | tail -n 3 | sed 's/^==[0-9]*== */    /'
echo
echo "Took $((SECONDS - start)) s."
