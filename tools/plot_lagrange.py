#!/usr/bin/python3
"""Plots the Lagrange method's drift figure of the README from bench/lagrange_study's CSV.

Usage: tools/plot_lagrange.py DRIFT_CSV OUT_PNG
Two panels against time: the largest joint gap (m, log scale) and the energy change (J), one
series per integrator and stabilization. Needs Debian's python3-matplotlib.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main():
    drift_csv, out_png = sys.argv[1:3]
    with open(drift_csv, newline="") as handle:
        rows = list(csv.DictReader(handle))
    names = list(dict.fromkeys(row["configuration"] for row in rows))
    figure, (gap_axes, energy_axes) = plt.subplots(2, 1, figsize=(7, 6.4), sharex=True)
    for name in names:
        series = [row for row in rows if row["configuration"] == name]
        time = [float(row["time"]) for row in series]
        # Gaps at rounding level (1e-16) would dominate a log axis; floor them for display.
        gap_axes.semilogy(time, [max(float(row["largest_gap"]), 1e-16) for row in series], label=name, linewidth=0.8)
        energy_axes.plot(time, [float(row["energy_change"]) for row in series], label=name, linewidth=0.8)
    gap_axes.set_ylabel("largest joint gap over 0.05 s (m)")
    gap_axes.set_title("Lagrange: 5-link heavy-end chain released horizontally, dt = 1/240 s", fontsize=10)
    gap_axes.legend(fontsize=8)
    energy_axes.set_ylabel("energy change since release (J)")
    energy_axes.set_xlabel("simulated time (s)")
    figure.tight_layout()
    figure.savefig(out_png, dpi=110)


if __name__ == "__main__":
    main()
