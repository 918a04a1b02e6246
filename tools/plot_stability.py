#!/usr/bin/python3
"""Plots the stability stress figures of the README from bench/stability_stress's CSV output.

Usage: tools/plot_stability.py GRID_CSV SPRINGS_CSV OUT_DIR
  GRID_CSV     stability_stress grid --csv GRID_CSV
  SPRINGS_CSV  stability_stress springs --csv SPRINGS_CSV
Writes OUT_DIR/stability_region.png (one panel per method: end-link mass ratio against time
step, each run's outcome) and OUT_DIR/stability_springs.png (the explicit springs' predicted
eq. 3.15 boundary against the measured runs, stiffness against time step).
Needs Debian's python3-matplotlib.
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

# One colour and marker per outcome (study::name(Stability)).
OUTCOMES = {
    "stable": ("tab:green", "s", "stable"),
    "non-finite": ("tab:red", "X", "non-finite (NaN or > 1000 m/s)"),
    "energy growth": ("tab:orange", "^", "energy growth > 0.5 m g ΣL"),
    "joint gap": ("tab:purple", "D", "joint gap > 0.5 link"),
}


def rows(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def region_figure(grid, path):
    methods = []
    for r in grid:
        key = (r["method"], r["setting"])
        if key not in methods:
            methods.append(key)
    columns = 3
    lines = math.ceil(len(methods) / columns)
    figure, axes = plt.subplots(lines, columns, figsize=(4.0 * columns, 3.3 * lines), sharex=True, sharey=True, squeeze=False)
    for index, (method, setting) in enumerate(methods):
        axis = axes[index // columns][index % columns]
        cells = [r for r in grid if r["method"] == method and r["setting"] == setting]
        for outcome, (colour, marker, _) in OUTCOMES.items():
            points = [(float(r["mass_ratio"]), float(r["dt"])) for r in cells if r["stability"] == outcome]
            if points:
                axis.scatter(*zip(*points), color=colour, marker=marker, s=60, edgecolors="black", linewidths=0.4)
        predicted = sorted({(float(r["mass_ratio"]), float(r["predicted_stable_dt"])) for r in cells
                            if r["predicted_stable_dt"] not in ("", "nan")})
        if predicted:
            axis.plot(*zip(*predicted), color="grey", linestyle="--")
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_ylim(5e-4, 0.12)
        axis.set_title(f"{method}" + (f" ({setting})" if setting else ""), fontsize=9)
        axis.grid(True, which="major", alpha=0.3)
        if index % columns == 0:
            axis.set_ylabel("time step (s)")
        if index // columns == lines - 1:
            axis.set_xlabel("end-link mass / link mass")
    for index in range(len(methods), lines * columns):
        axes[index // columns][index % columns].axis("off")
    handles = [plt.Line2D([], [], color=c, marker=m, linestyle="none", markeredgecolor="black", label=label)
               for c, m, label in OUTCOMES.values()]
    handles.append(plt.Line2D([], [], color="grey", linestyle="--", label="explicit springs: predicted largest stable step"))
    figure.legend(handles=handles, loc="lower center", ncol=5, fontsize=8)
    figure.suptitle("Stability: 10-link chain (0.1 m, 1 kg links), released horizontally, 10 s per run", fontsize=11)
    figure.tight_layout(rect=(0, 0.04, 1, 0.97))
    figure.savefig(path, dpi=110)


def springs_figure(springs, path):
    integrators = []
    for r in springs:
        if r["integrator"] not in integrators:
            integrators.append(r["integrator"])
    figure, axes = plt.subplots(1, len(integrators), figsize=(5.4 * len(integrators), 4.2), sharey=True, squeeze=False)
    for axis, integrator in zip(axes[0], integrators):
        cells = [r for r in springs if r["integrator"] == integrator]
        stable = [(float(r["stiffness"]), float(r["dt"])) for r in cells if r["diverged"] == "0"]
        unstable = [(float(r["stiffness"]), float(r["dt"])) for r in cells if r["diverged"] == "1"]
        if stable:
            axis.scatter(*zip(*stable), color="tab:green", marker="s", s=40, edgecolors="black", linewidths=0.4, label="stable")
        if unstable:
            axis.scatter(*zip(*unstable), color="tab:red", marker="x", s=40, label="diverged (non-finite or energy)")
        predicted = sorted({(float(r["stiffness"]), float(r["predicted_stable_dt"])) for r in cells})
        axis.plot(*zip(*predicted), color="black", linestyle="--", label="predicted largest stable step")
        axis.set_xscale("log")
        axis.set_yscale("log")
        axis.set_ylim(5e-4, 0.09)
        axis.set_xlabel("joint stiffness k (N/m)")
        axis.set_title(f"explicit springs, {integrator}", fontsize=10)
        axis.grid(True, which="major", alpha=0.3)
    axes[0][0].set_ylabel("time step (s)")
    figure.legend(*axes[0][0].get_legend_handles_labels(), loc="lower center", ncol=3, fontsize=8)
    figure.suptitle("eq. 3.15 check: equal-mass 10-link chain, c = 20 N s/m, 10 s per run", fontsize=11)
    figure.tight_layout(rect=(0, 0.06, 1, 0.95))
    figure.savefig(path, dpi=110)


def main():
    if len(sys.argv) != 4:
        sys.exit("usage: tools/plot_stability.py GRID_CSV SPRINGS_CSV OUT_DIR")
    grid_csv, springs_csv, out_dir = sys.argv[1:4]
    region_figure(rows(grid_csv), f"{out_dir}/stability_region.png")
    springs_figure(rows(springs_csv), f"{out_dir}/stability_springs.png")


if __name__ == "__main__":
    main()
