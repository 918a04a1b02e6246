#!/usr/bin/python3
"""Plots the equal-error race of the README from bench/direct_race's CSV.

Usage: tools/plot_race.py RACE_CSV OUT_PNG
One panel per chain length: time per step (µs) against the largest joint error over the run
(relative to the link length), log-log, one marker per method; runs whose error exceeded a link
length are drawn hollow. Needs Debian's python3-matplotlib.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

FAMILIES = [("bullet", "tab:red", "s"), ("rattle", "tab:cyan", "h"), ("direct", "tab:blue", "o"), ("long-range", "tab:green", "^"),
            ("jacobi", "tab:purple", "v"), ("gauss-seidel", "tab:orange", "D")]


def style(method):
    for prefix, colour, marker in FAMILIES:
        if prefix in method:
            return colour, marker
    return "black", "x"


def main():
    race_csv, out_png = sys.argv[1:3]
    with open(race_csv, newline="") as handle:
        rows = list(csv.DictReader(handle))
    lengths = list(dict.fromkeys(int(row["links"]) for row in rows))
    figure, axes = plt.subplots(1, len(lengths), figsize=(4.2 * len(lengths), 4.6), squeeze=False)
    for panel, links in zip(axes[0], lengths):
        for row in (r for r in rows if int(r["links"]) == links):
            colour, marker = style(row["method"])
            error = max(float(row["max_error"]), 1e-16)  # rounding-level errors floored for the log axis
            hollow = error > 1 or row["finite"] != "1"
            panel.loglog(float(row["seconds_per_step"]) * 1e6, error, marker=marker, linestyle="none", markersize=7,
                         markeredgecolor=colour, markerfacecolor="none" if hollow else colour)
            panel.annotate(row["method"].replace(" (at most 50)", ""), (float(row["seconds_per_step"]) * 1e6, error),
                           fontsize=6, xytext=(4, 2), textcoords="offset points")
        panel.axhline(1e-4, color="grey", linewidth=0.6, linestyle="--")
        panel.set_title(f"{links} links", fontsize=10)
        panel.set_xlabel("time per step (µs), 1 thread")
    axes[0][0].set_ylabel("largest joint error over 2 s / link length")
    figure.suptitle("Heavy-end chain released horizontally, dt = 1/60 s (hollow: error above a link length)", fontsize=10)
    figure.tight_layout()
    figure.savefig(out_png, dpi=110)


if __name__ == "__main__":
    main()
