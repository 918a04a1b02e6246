#!/usr/bin/python3
"""Pareto plots of run time against error from bench/pareto_study's CSVs, and the README's table.

Usage: tools/plot_pareto.py OUT_PNG CSV [CSV ...]
Each CSV is bench/pareto_study's (one scene) or a limber.sweep table (python3 -m limber.sweep
bench/pareto_sweep/grid.json; one panel per scene in it), whose rows are named by the same series.
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


# A sweep row's series: its method and the options that are not a setting along the series.
SWEEP_SERIES = {
    ("weighted", "gauss-seidel", "pbd"): "verlet gauss-seidel", ("weighted", "jacobi", "pbd"): "verlet jacobi",
    ("weighted", "direct", "pbd"): "verlet direct", ("weighted", "gauss-seidel", "rattle"): "verlet rattle gauss-seidel",
    ("weighted", "direct", "rattle"): "verlet rattle direct", ("springs-explicit",): "springs explicit",
    ("springs-implicit",): "springs implicit", ("lagrange", "semi-implicit", "baumgarte"): "lagrange baumgarte",
    ("lagrange", "semi-implicit", "projection"): "lagrange projection", ("lagrange", "rk4", "projection"): "lagrange rk4 projection",
    ("featherstone", "rk4"): "featherstone rk4", ("featherstone", "semi-implicit"): "featherstone semi-implicit",
}
SWEEP_SETTINGS = ("iterations", "newton_iterations", "substeps", "stiffness")


def from_sweep(row):
    """A limber.sweep row in pareto_study's shape. Stable: the step never diverged, and the run
    stayed within kernel/study/run_metrics.hpp's StabilityBounds (gain ≤ 0.5, gap ≤ 0.5)."""
    present = lambda key: row.get(key, "nan") not in ("nan", "")
    key = (row["method"], *(row[k] for k in ("solver", "integrator", "projection", "stabilization") if present(k)))
    key = {"weighted": key[:3], "lagrange": key[:3], "featherstone": key[:2]}.get(row["method"], key[:1])
    rate = float(row["steps_per_second"]) * float(row["dt"])
    stable = (row["status"] == "ok" and float(row["energy_gain"]) <= 0.5
              and max(float(row["max_joint_gap"]), float(row["max_link_stretch"])) <= 0.5)
    return {"scene": row["scene"], "series": SWEEP_SERIES.get(key, " ".join(key)), "time_step": row["dt"],
            "setting": " ".join(f"{k} {float(row[k]):g}" for k in SWEEP_SETTINGS if present(k)),
            "wall_per_simulated_second": str(1 / rate if rate > 0 else math.inf), "trajectory_error": row["trajectory_error"],
            "max_joint_gap": row["max_joint_gap"], "max_link_stretch": row["max_link_stretch"],
            "relative_energy_drift": row["energy_drift"], "stability": "stable" if stable else "diverged"}


def read_scenes(paths):
    """One list of pareto_study-shaped rows per scene, in the files' order."""
    scenes = {}
    for path in paths:
        with open(path, newline="") as handle:
            rows = list(csv.DictReader(handle))
        for row in rows:
            row = from_sweep(row) if "steps_per_second" in row else row
            scenes.setdefault((path, row["scene"]), []).append(row)
    return list(scenes.values())


def main():
    out_png, paths = sys.argv[1], sys.argv[2:]
    scenes = read_scenes(paths)
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
