#!/usr/bin/python3
# Runs bench/relaxation_bench (or reads its JSON) and prints the README's markdown tables.
#
#   tools/relaxation_report.py [--build DIR] [--filter REGEX]   run the benchmark (about a minute)
#   tools/relaxation_report.py --json FILE                      report on an existing JSON output
#
# --build DIR: the build tree holding bench/relaxation_bench (default: build, next to tools/).
# --filter REGEX is passed on as --benchmark_filter; cells whose benchmark did not run print "–".
import argparse
import json
import os
import subprocess
import sys
import tempfile

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SIZES = [10, 100, 1000, 10000, 100000, 1000000]
WORKLOADS = ([f"chain_{n}" for n in SIZES] + [f"tree_{n}" for n in SIZES]
             + ["grid_100x100", "humanoids_160", "heavy_end_chain_1000"])
TWO_THREADS = ("simd_2t_workers", "simd_2t_parallel_for")
TO_US = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}


def load(path):
    """{(kind, workload, type, path): benchmark entry with 'us' = real time in µs}, triad entry."""
    with open(path) as f:
        entries = json.load(f)["benchmarks"]
    results, triad = {}, None
    for e in entries:
        if e.get("run_type", "iteration") != "iteration" or e.get("error_occurred"):
            continue
        e["us"] = e["real_time"] * TO_US[e.get("time_unit", "ns")]
        parts = [p for p in e["name"].split("/") if not p.startswith("min_time:")]
        if parts[0] == "BM_StreamTriad":
            triad = e
        elif len(parts) == 4 or (len(parts) == 2 and parts[0] == "Colour"):
            results[tuple(parts)] = e
    return results, triad


def workloads(results):
    seen = {k[1] for k in results}
    return [w for w in WORKLOADS if w in seen] + sorted(seen - set(WORKLOADS))


def best_2t(results, kind, w, t):
    """(entry, 'workers' | 'parallel_for') of the faster two-thread path, or (None, None)."""
    runs = [(results[(kind, w, t, p)], p[8:]) for p in TWO_THREADS if (kind, w, t, p) in results]
    return min(runs, key=lambda r: r[0]["us"]) if runs else (None, None)


def fmt(x, unit=""):
    """3 significant digits; k/M/G suffixes when unit is given (rates); '–' when missing."""
    if x is None:
        return "–"
    if unit:
        for factor, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
            if abs(x) >= factor:
                return f"{x / factor:.3g} {prefix}{unit}"
        return f"{x:.3g} {unit}"
    return f"{float(f'{x:.3g}'):,.0f}" if abs(x) >= 1000 else f"{x:.3g}"


def ratio(a, b):
    return fmt(a / b) + "×" if a is not None and b else "–"


def us(entry):
    return entry["us"] if entry else None


def table(title, header, rows, note=None, intro=None):
    print(f"### {title}\n")
    if intro:
        print(f"{intro}\n")
    rows = [r for r in rows if any(c != "–" for c in r[1:])]  # drop rows with nothing measured
    if not rows:
        print("_no matching benchmarks_\n")
        return
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join("---" if i == 0 else "---:" for i in range(len(header))) + "|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
    print(f"\n{note}\n" if note else "")


def speed_table(results, t):
    rows = []
    for w in workloads(results):
        g = lambda p: results.get(("Sweep", w, t, p))
        scalar, simd = g("scalar"), g("simd")
        two, which = best_2t(results, "Sweep", w, t)
        any_run = next((e for e in (simd, scalar, two) if e), None)
        fastest = min((e for e in (scalar, simd, two) if e), key=us, default=None)
        rows.append([w, fmt(any_run and any_run.get("constraints")), fmt(any_run and any_run.get("colours")),
                     fmt(us(scalar)), fmt(us(simd)), ratio(us(scalar), us(simd)),
                     f"{fmt(us(two))} ({which})" if two else "–", ratio(us(simd), us(two)),
                     fmt(fastest and fastest.get("projections/s"), "/s")])
    table(f"Time per sweep (µs) and speed-ups, {t}",
          ["workload", "constraints", "colours", "scalar SoA µs", "SIMD µs (auto layout)", "SIMD / scalar",
           "SIMD 2 threads µs (best)", "2 threads / 1", "projections/s (fastest)"], rows)


def crossover(results, family):
    """Smallest constraint count from which the best 2-thread sweep beats SIMD on 1 thread."""
    points = []
    for w in workloads(results):
        simd, (two, _) = results.get(("Sweep", w, "float", "simd")), best_2t(results, "Sweep", w, "float")
        if w.startswith(family + "_") and simd and two:
            points.append((simd["constraints"], two["us"] < simd["us"]))
    if not points:
        return f"{family}s: not measured"
    points.sort()
    faster_from = None
    for n, faster in reversed(points):
        if not faster:
            break
        faster_from = n
    if faster_from is None:
        return f"{family}s: 2 threads never faster than 1 in the measured range (up to {fmt(points[-1][0])} constraints)"
    below = [n for n, _ in points if n < faster_from]
    since = f" (slower at {fmt(below[-1])})" if below else " (at every measured size)"
    return f"{family}s: 2 threads faster than 1 from {fmt(faster_from)} constraints on{since}"


def threads_table(results):
    rows = []
    for w in workloads(results):
        g = lambda p: us(results.get(("Sweep", w, "float", p)))
        rows.append([w, fmt(g("simd")), ratio(g("simd"), g("simd_2t_workers")),
                     ratio(g("simd"), g("simd_2t_parallel_for"))])
    note = "Crossover (best 2-thread path vs SIMD on 1 thread, float): " + \
        "; ".join(crossover(results, f) for f in ("chain", "tree")) + "."
    table("Threads: workers vs parallel_for (float, speed-up over SIMD on 1 thread)",
          ["workload", "SIMD 1 thread µs", "workers", "parallel_for"], rows, note)


def bandwidth_table(results, triad):
    bw = triad and triad["bytes/s"]
    rows = []
    for w in workloads(results):
        for t in ("float", "double"):
            simd = results.get(("Sweep", w, t, "simd"))
            two, which = best_2t(results, "Sweep", w, t)
            if not w.startswith(("chain_", "tree_")) or not (simd or two) \
                    or (simd or two)["constraints"] < 1e5:
                continue
            row = [f"{w} {t}"]
            for e in (simd, two):
                b = e and e["bytes/s"]
                row += [fmt(b and b / 1e9), fmt(b / bw) if b and bw else "–", ratio(bw, b)]
            rows.append(row + [which or "–"])
    table("Memory bandwidth (sweeps with ≥ 10^5 constraints)",
          ["workload", "SIMD GB/s", "of triad", "× bound", "2 threads GB/s", "of triad", "× bound", "2-thread path"],
          rows, "“of triad”: sweep bytes/s ÷ triad bytes/s; “× bound”: how many times slower the sweep is "
          "than streaming its data at the triad's bandwidth. The triad runs on one thread.",
          f"Stream triad (1 thread, 3 × 64 MiB): {fmt(bw and bw / 1e9)} GB/s.")


def layout_table(results):
    rows = []
    for w in workloads(results):
        g = lambda p: us(results.get(("Sweep", w, "float", p)))
        base = g("simd_soa")
        rows.append([w, fmt(base)] + [ratio(g(p), base) for p in ("simd_aos", "simd_aosoa", "simd", "scalar", "scalar_aos")])
    table("Layouts (float; times relative to SIMD on SoA)",
          ["workload", "SIMD SoA µs", "SIMD AoS", "SIMD AoSoA", "SIMD auto", "scalar SoA", "scalar AoS"], rows)


def colouring_table(results):
    rows = []
    for w in workloads(results):
        e = results.get(("Colour", w))
        if e:
            rows.append([w, fmt(e.get("constraints")), fmt(e.get("colours")), fmt(e["us"] / 1e3)])
    table("Colouring (greedy, one thread)", ["workload", "constraints", "colours", "ms"], rows)


def step_table(results):
    rows = []
    for w in workloads(results):
        row = [w]
        for t in ("float", "double"):
            two, which = best_2t(results, "Step", w, t)
            for e in (results.get(("Step", w, t, "scalar")), results.get(("Step", w, t, "simd")), two):
                row.append(fmt(e and e.get("steps/s", 1e6 / e["us"])))
        rows.append(row)
    table("Full step (steps/s: Verlet integration + 10 sweeps)",
          ["workload", "float scalar", "float SIMD", "float 2 threads", "double scalar", "double SIMD",
           "double 2 threads"], rows)


def jacobi_table(results):
    rows = []
    for w in workloads(results):
        g = lambda p: us(results.get(("Sweep", w, "float", p)))
        rows.append([w, fmt(g("simd")), fmt(g("jacobi_simd")), ratio(g("jacobi_simd"), g("simd")),
                     fmt(g("simd_2t_workers")), fmt(g("jacobi_simd_2t_workers")),
                     ratio(g("jacobi_simd_2t_workers"), g("simd_2t_workers"))])
    table("Jacobi vs Gauss-Seidel cost per sweep (float)",
          ["workload", "GS SIMD µs", "Jacobi SIMD µs", "Jacobi / GS", "GS 2t workers µs",
           "Jacobi 2t workers µs", "Jacobi / GS (2t)"], rows)


def run_bench(build, bench_filter, out):
    bench = os.path.join(build, "bench", "relaxation_bench")
    if not os.access(bench, os.X_OK):
        sys.exit(f"relaxation_report: {bench} not found; build it (cmake --build {build} --target relaxation_bench)")
    cmd = [bench, "--benchmark_format=json", f"--benchmark_out={out}", "--benchmark_out_format=json"]
    if bench_filter:
        cmd.append(f"--benchmark_filter={bench_filter}")
    print(f"relaxation_report: running {' '.join(cmd)}", file=sys.stderr)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def main():
    parser = argparse.ArgumentParser(description="Markdown tables from relaxation_bench.")
    parser.add_argument("--build", default=os.path.join(REPO, "build"), help="build tree (default: build)")
    parser.add_argument("--filter", help="passed on as --benchmark_filter")
    parser.add_argument("--json", help="read this benchmark JSON instead of running the benchmark")
    args = parser.parse_args()
    if args.json:
        results, triad = load(args.json)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "relaxation_bench.json")
            run_bench(args.build, args.filter, out)
            results, triad = load(out)
    speed_table(results, "float")
    speed_table(results, "double")
    threads_table(results)
    bandwidth_table(results, triad)
    layout_table(results)
    step_table(results)
    jacobi_table(results)
    colouring_table(results)


if __name__ == "__main__":
    main()
