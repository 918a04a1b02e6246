#!/usr/bin/python3
"""Pareto plots of run time against error from bench/pareto_study's CSVs, and the README's table.

Usage: tools/plot_pareto.py OUT_PNG SCENE_CSV [SCENE_CSV ...]
One panel per scene: wall time per simulated second against the error, log-log, one series per
method (a line through its settings, in CSV order). The error is the trajectory error against
the reference (m) where the CSV has one, else the largest joint gap or link stretch (relative).
Diverged runs (stability column not "stable") are left out. The Pareto front — the runs no other
run beats in both time and error — is circled, and printed to stdout as a markdown table per
scene. Needs Debian's python3-matplotlib.
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

STYLES = {
    "verlet gauss-seidel": ("tab:orange", "D"),
    "verlet gauss-seidel thesis masses": ("peru", "d"),
    "verlet jacobi": ("tab:purple", "v"),
    "verlet direct": ("tab:blue", "o"),
    "verlet rattle gauss-seidel": ("tab:cyan", "h"),
    "verlet rattle direct": ("navy", "p"),
    "springs explicit": ("tab:olive", "<"),
    "springs implicit": ("tab:green", ">"),
    "lagrange baumgarte": ("tab:brown", "s"),
    "lagrange projection": ("tab:pink", "s"),
    "lagrange rk4 projection": ("tab:red", "P"),
    "featherstone rk4": ("black", "*"),
    "featherstone semi-implicit": ("tab:gray", "X"),
}


def error_of(row):
    trajectory = float(row["trajectory_error"])
    if not math.isnan(trajectory):
        return trajectory
    return max(float(row["max_joint_gap"]), float(row["max_link_stretch"]))


def pareto_front(rows):
    """Rows not dominated in (time, error): sorted by time, each strictly more accurate than all faster ones."""
    front, best = [], math.inf
    for row in sorted(rows, key=lambda r: (float(r["wall_per_simulated_second"]), error_of(r))):
        if error_of(row) < best:
            front.append(row)
            best = error_of(row)
    return front


def main():
    out_png, paths = sys.argv[1], sys.argv[2:]
    scenes = []
    for path in paths:
        with open(path, newline="") as handle:
            scenes.append(list(csv.DictReader(handle)))
    figure, axes = plt.subplots(1, len(scenes), figsize=(5.2 * len(scenes), 5.6), squeeze=False)
    for panel, rows in zip(axes[0], scenes):
        scene = rows[0]["scene"]
        stable = [r for r in rows if r["stability"] == "stable"]
        trajectory = not math.isnan(float(rows[0]["trajectory_error"]))
        for series in dict.fromkeys(r["series"] for r in rows):
            points = [r for r in stable if r["series"] == series]
            if not points:
                continue
            colour, marker = STYLES.get(series, ("black", "x"))
            points.sort(key=lambda r: float(r["wall_per_simulated_second"]))
            panel.loglog([max(error_of(r), 1e-16) for r in points], [float(r["wall_per_simulated_second"]) for r in points],
                         marker=marker, color=colour, linestyle="none", markersize=6, label=series)
        front = pareto_front(stable)
        panel.loglog([max(error_of(r), 1e-16) for r in front], [float(r["wall_per_simulated_second"]) for r in front],
                     color="grey", linewidth=0.8, linestyle="--", marker="o", markersize=13, markerfacecolor="none")
        panel.set_title(scene, fontsize=10)
        panel.set_xlabel("trajectory error over 2 s (m)" if trajectory else "largest joint gap or stretch / link length")
        panel.set_ylabel("wall time per simulated second (s), 1 thread")
        print(f"\n{scene}: Pareto front ({len(stable)} of {len(rows)} runs stable)\n")
        print("| method | setting | Δt (s) | time per simulated s | error | energy change |")
        print("|---|---|---|---|---|---|")
        for row in front:
            print(f"| {row['series']} | {row['setting']} | 1/{1 / float(row['time_step']):.0f} | "
                  f"{float(row['wall_per_simulated_second']) * 1e3:.3g} ms | {error_of(row):.2g}"
                  f"{' m' if trajectory else ''} | {float(row['relative_energy_drift']):.1g} |")
    handles = {}
    for panel in axes[0]:
        for handle, label in zip(*panel.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    figure.legend(handles.values(), handles.keys(), fontsize=8, loc="lower center", ncol=6)
    figure.suptitle("Run time against error, every method (circled, dashed: the Pareto front; diverged runs left out)",
                    fontsize=10)
    figure.tight_layout(rect=(0, 0.1, 1, 1))
    figure.savefig(out_png, dpi=110)


if __name__ == "__main__":
    main()
