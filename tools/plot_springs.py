#!/usr/bin/python3
"""Plots the stiff-spring figures of the README from bench/spring_study's CSV output.

Usage: tools/plot_springs.py GAP_CSV STABLE_DT_CSV OUT_DIR
Writes OUT_DIR/spring_gap.png (top-joint gap of the 5-link heavy-end chain against stiffness)
and OUT_DIR/spring_stable_dt.png (largest stable time step against stiffness).
Needs Debian's python3-matplotlib.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def rows(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def main():
    gap_csv, stable_csv, out_dir = sys.argv[1:4]
    gap = rows(gap_csv)
    figure, axes = plt.subplots(figsize=(6.4, 4.2))
    for method in ["springs-explicit", "springs-implicit-linearized", "springs-implicit"]:
        points = [(float(r["stiffness"]), float(r["top_gap"]), r["stable"] == "1") for r in gap if r["method"] == method]
        stable = [(k, g) for k, g, ok in points if ok]
        unstable = [(k, g) for k, g, ok in points if not ok]
        line, = axes.loglog(*zip(*stable), marker="o", label=method) if stable else (None,)
        if unstable:
            axes.loglog(*zip(*unstable), linestyle="none", marker="x", color=line.get_color() if line else None)
    verlet = [r for r in gap if r["method"] == "weighted-verlet"]
    if verlet:
        axes.axhline(float(verlet[0]["top_gap"]), color="grey", linestyle="--", label="weighted Verlet, 100 sweeps")
    axes.set_xlabel("joint stiffness k (N/m)")
    axes.set_ylabel("largest top-joint gap / link length")
    axes.set_title("5-link heavy-end chain, released horizontally, dt = 1/240 s (x: unstable)")
    axes.legend(fontsize=8)
    axes.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(f"{out_dir}/spring_gap.png", dpi=110)

    stable = rows(stable_csv)
    figure, axes = plt.subplots(figsize=(6.4, 4.2))
    for integrator in ["euler", "semi-implicit", "rk4", "backward-euler-linearized", "backward-euler"]:
        points = [(float(r["stiffness"]), float(r["largest_stable_dt"])) for r in stable
                  if r["integrator"] == integrator and float(r["largest_stable_dt"]) > 0]
        if points:
            axes.loglog(*zip(*points), marker="o", label=integrator)
    bound = sorted({(float(r["stiffness"]), float(r["symplectic_bound"])) for r in stable})
    axes.loglog(*zip(*bound), color="grey", linestyle="--", label="2/ω, one link on one spring")
    axes.set_xlabel("joint stiffness k (N/m)")
    axes.set_ylabel("largest stable time step (s)")
    axes.set_title("5-link heavy-end chain, 2 s, damping 20 N s/m")
    axes.legend(fontsize=8)
    axes.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(f"{out_dir}/spring_stable_dt.png", dpi=110)


if __name__ == "__main__":
    main()
