#!/usr/bin/python3
"""Plots the figures of the README's thesis experiments.

Usage:
  tools/plot_thesis.py speed BENCHMARK_OUTPUT OUT_DIR
      BENCHMARK_OUTPUT: bench/thesis_speed's --benchmark_out, JSON or CSV (with repetitions, the
      medians are drawn). Writes OUT_DIR/thesis_speed.png: steps/s against links, log-log
      (thesis figures 4.7 and 4.8).
  tools/plot_thesis.py verlet-rk2 SERIES_CSV OUT_DIR
      SERIES_CSV: `bench/thesis_experiments verlet-rk2-csv`. Writes OUT_DIR/thesis_verlet_rk2.png:
      one particle on a spring, velocity and errors of RK2 and Verlet (thesis figure 3.12).
Needs Debian's python3-matplotlib.
"""
import csv
import json
import math
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

# The thesis's own figure for scale: ~600 frames/s at 5 links, both methods (Athlon XP 1800+, rendered).
THESIS_FRAME_RATE = 600.0


def benchmark_rows(path):
    """Rows of Google Benchmark output as dicts with name, aggregate, steps_per_second, links."""
    with open(path) as handle:
        text = handle.read()
    rows = []
    if text.lstrip().startswith("{"):
        for entry in json.loads(text)["benchmarks"]:
            rows.append({"name": entry.get("run_name", entry["name"]), "aggregate": entry.get("aggregate_name", ""),
                         "steps_per_second": float(entry["steps/s"]), "links": float(entry["links"])})
    else:
        # The CSV has a context header before its table; the table starts at the "name," line.
        lines = text.splitlines()
        start = next(i for i, line in enumerate(lines) if line.startswith("name,"))
        for entry in csv.DictReader(lines[start:]):
            name = entry["name"]
            aggregate = ""
            match = re.match(r"(.*)_(mean|median|stddev|cv)$", name)
            if match:
                name, aggregate = match.group(1), match.group(2)
            rows.append({"name": name, "aggregate": aggregate, "steps_per_second": float(entry["steps/s"]),
                         "links": float(entry["links"])})
    # Medians when the run was repeated, else the single measurements.
    if any(r["aggregate"] == "median" for r in rows):
        rows = [r for r in rows if r["aggregate"] == "median"]
    else:
        rows = [r for r in rows if r["aggregate"] == ""]
    return rows


def series(rows, pattern):
    points = sorted((r["links"], r["steps_per_second"]) for r in rows if re.fullmatch(pattern, r["name"]))
    return points


def plot_speed(path, out_dir):
    rows = benchmark_rows(path)
    figure, axes = plt.subplots(figsize=(6.4, 4.6))
    curves = [
        ("stiff springs, explicit (the thesis's step)", r"BM_SpringsExplicit/links:\d+", "o"),
        ("stiff springs, implicit (backward Euler)", r"BM_SpringsImplicit/links:\d+", "s"),
        ("weighted Verlet, 5 sweeps", r"BM_WeightedVerlet/links:\d+/sweeps:5/thesis_loop:0", "^"),
        ("weighted Verlet, 100 sweeps", r"BM_WeightedVerlet/links:\d+/sweeps:100/thesis_loop:0", "v"),
    ]
    colours = {}
    for label, pattern, marker in curves:
        points = series(rows, pattern)
        if points:
            line, = axes.loglog(*zip(*points), marker=marker, label=label)
            colours[pattern] = (line.get_color(), points)
    # What a fixed cost per rendered frame does to the same steps: 1 / (1/600 s + step time).
    for pattern in (curves[0][1], curves[2][1]):
        if pattern in colours:
            colour, points = colours[pattern]
            framed = [(n, 1.0 / (1.0 / THESIS_FRAME_RATE + 1.0 / rate)) for n, rate in points]
            axes.loglog(*zip(*framed), linestyle="--", color=colour, alpha=0.7)
    axes.axhline(THESIS_FRAME_RATE, color="grey", linestyle=":", label="thesis: ~600 frames/s at 5 links (rendered)")
    axes.plot([], [], color="grey", linestyle="--", label="ours + a 1/600 s frame cost")
    axes.set_xlabel("links in the chain")
    axes.set_ylabel("steps per second (CPU time)")
    axes.set_title("Heavy-end chain, one step, no rendering (thesis figures 4.7, 4.8)", fontsize=10)
    axes.legend(fontsize=7, loc="lower left")
    axes.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(f"{out_dir}/thesis_speed.png", dpi=110)


def plot_verlet_rk2(path, out_dir):
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    column = lambda name: [float(r[name]) for r in rows]
    time = column("time")
    exact_velocity, exact_position = column("exact_velocity"), column("exact_position")
    figure, (velocity_axes, error_axes) = plt.subplots(2, 1, figsize=(6.4, 6.4), sharex=True)
    velocity_axes.plot(time, exact_velocity, color="black", linewidth=1, label="exact")
    velocity_axes.plot(time, column("rk2_velocity"), marker="o", markersize=3, linestyle="none", label="RK2 (midpoint)")
    velocity_axes.plot(time, column("verlet_velocity"), marker="^", markersize=3, linestyle="none",
                       label="Verlet, (x − x*)/Δt (the kernel's)")
    velocity_axes.set_ylabel("velocity (m/s)")
    velocity_axes.set_title("One particle on a spring, period 1 s, Δt = 1/30 s (thesis figure 3.12)", fontsize=10)
    velocity_axes.legend(fontsize=7)
    velocity_axes.grid(True, alpha=0.3)

    def error(estimate, exact):
        return [abs(e - x) if not math.isnan(e) else float("nan") for e, x in zip(estimate, exact)]

    error_axes.semilogy(time, error(column("rk2_velocity"), exact_velocity), label="RK2 velocity")
    error_axes.semilogy(time, error(column("verlet_velocity"), exact_velocity), label="Verlet velocity (x − x*)/Δt")
    error_axes.semilogy(time, error(column("verlet_central_velocity"), exact_velocity), label="Verlet velocity, central difference")
    error_axes.semilogy(time, error(column("rk2_position"), exact_position), linestyle="--", label="RK2 position")
    error_axes.semilogy(time, error(column("verlet_position"), exact_position), linestyle="--", label="Verlet position, consistent start")
    error_axes.semilogy(time, error(column("verlet_position_kernel_start"), exact_position), linestyle=":",
                        label="Verlet position, compile()'s start")
    error_axes.set_xlabel("time (s)")
    error_axes.set_ylabel("|error| (m/s, m)")
    error_axes.legend(fontsize=7, ncol=2)
    error_axes.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(f"{out_dir}/thesis_verlet_rk2.png", dpi=110)


def main():
    if len(sys.argv) != 4 or sys.argv[1] not in ("speed", "verlet-rk2"):
        sys.exit(__doc__)
    what, path, out_dir = sys.argv[1:4]
    if what == "speed":
        plot_speed(path, out_dir)
    else:
        plot_verlet_rk2(path, out_dir)


if __name__ == "__main__":
    main()
