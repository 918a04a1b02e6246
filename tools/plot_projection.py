#!/usr/bin/python3
"""Plots the projection rules' figures from bench/projection_study's CSVs.

Usage: tools/plot_projection.py ORDER_CSV FRAMES_CSV OUT_PNG
Left panels (one per workload): the largest point error over 2 s against the (sub)step, log-log,
for the pbd and rattle rules relaxed to convergence, with slopes 1 and 2 for reference. Right
panel: frames of 1/60 s on the heavy-end chain, error over 2 s against the wall time per frame,
one line per sweep count through 1 … 128 substeps. Needs Debian's python3-matplotlib.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

RULES = {"pbd": ("tab:orange", "D"), "rattle": ("tab:blue", "o")}


def read(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def order_panel(axis, rows, workload):
    for rule, (colour, marker) in RULES.items():
        points = [(float(r["time_step"]), float(r["max_point_error"])) for r in rows if r["workload"] == workload and r["projection"] == rule]
        axis.loglog([p[0] for p in points], [p[1] for p in points], marker=marker, color=colour, label=rule, markersize=4)
    # Guides through each rule's finest point: slope 2 for rattle, slope 1 for pbd.
    for rule, slope, style in (("rattle", 2, ":"), ("pbd", 1, "--")):
        finest = min((float(r["time_step"]), float(r["max_point_error"])) for r in rows
                     if r["workload"] == workload and r["projection"] == rule)
        largest = max(float(r["time_step"]) for r in rows if r["workload"] == workload)
        axis.loglog([finest[0], largest], [finest[1], finest[1] * (largest / finest[0]) ** slope], color="grey",
                    linestyle=style, linewidth=0.8, label=f"slope {slope}")
    axis.set_title(workload, fontsize=10)
    axis.set_xlabel("(sub)step (s)")


def frames_panel(axis, rows):
    for rule, (colour, marker) in RULES.items():
        for sweeps in sorted({int(r["sweeps"]) for r in rows if r["projection"] == rule}):
            points = sorted((float(r["microseconds_per_frame"]), float(r["max_point_error_2s"]), int(r["substeps"]))
                            for r in rows if r["projection"] == rule and int(r["sweeps"]) == sweeps)
            axis.loglog([p[0] for p in points], [p[1] for p in points], marker=marker, color=colour, markersize=3,
                        alpha=0.35 + 0.13 * min(sweeps, 5), label=f"{rule}, {sweeps} sweep{'s' if sweeps > 1 else ''}")
    axis.axhline(1e-3, color="grey", linewidth=0.6, linestyle="--")
    axis.set_title("heavy-end chain, frames of 1/60 s", fontsize=10)
    axis.set_xlabel("wall time per frame (µs), 1 thread")
    axis.set_ylabel("largest point error over 2 s (m)")
    axis.legend(fontsize=6, ncol=2)


def main():
    order_csv, frames_csv, out_png = sys.argv[1:4]
    order_rows, frame_rows = read(order_csv), read(frames_csv)
    workloads = list(dict.fromkeys(r["workload"] for r in order_rows))
    figure, axes = plt.subplots(1, len(workloads) + 1, figsize=(4.0 * (len(workloads) + 1), 4.2))
    for axis, workload in zip(axes, workloads):
        order_panel(axis, order_rows, workload)
    axes[0].set_ylabel("largest point error over 2 s (m), converged")
    axes[0].legend(fontsize=7)
    frames_panel(axes[-1], frame_rows)
    figure.suptitle("Projection rules: pbd (end-of-step gradient) and rattle (start-of-step gradient + velocity stage)", fontsize=10)
    figure.tight_layout()
    figure.savefig(out_png, dpi=110)


if __name__ == "__main__":
    main()
