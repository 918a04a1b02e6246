#!/usr/bin/python3
"""Plots the README's "Other engines on the same chain" from bench/peer_chains's CSV.

Usage: tools/plot_peers.py PEERS_CSV [OUT_PNG]   (default bench/figures/peer_chains.png)
Left: time per step (µs, one thread) against the number of links, log-log, one line per engine
and method. Right: the largest joint error over the run (relative to the link length) against
the number of links. limber's methods are solid lines and circles, the other engines dashed
(Bullet squares, ODE triangles, MuJoCo diamonds); runs that diverged (or that MuJoCo reset) are
hollow markers; skipped runs are left out. Needs Debian's
python3-matplotlib.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

ERROR_FLOOR = 1e-16  # rounding-level and zero errors are drawn here on the log axis

# One marker per engine; one colour per engine and method.
MARKERS = {"limber": "o", "Bullet": "s", "ODE": "^", "MuJoCo": "D"}


def marker_of(engine):
    for prefix, marker in MARKERS.items():
        if engine.startswith(prefix):
            return marker
    return "x"


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: tools/plot_peers.py PEERS_CSV [OUT_PNG]")
    peers_csv = sys.argv[1]
    out_png = sys.argv[2] if len(sys.argv) == 3 else "bench/figures/peer_chains.png"
    with open(peers_csv, newline="") as handle:
        rows = [row for row in csv.DictReader(handle) if row["seconds_per_step"]]  # skipped runs have no time
    series = list(dict.fromkeys((row["engine"], row["method"]) for row in rows))
    palette = plt.get_cmap("tab20").colors

    figure, (time_panel, error_panel) = plt.subplots(1, 2, figsize=(13, 6.2))
    for index, (engine, method) in enumerate(series):
        points = sorted((int(r["links"]), r) for r in rows if r["engine"] == engine and r["method"] == method)
        colour = palette[(2 * index) % 20 if index < 10 else (2 * index + 1) % 20]
        marker = marker_of(engine)
        linestyle = "-" if engine == "limber" else "--"
        links = [n for n, _ in points]
        times = [float(r["seconds_per_step"]) * 1e6 for _, r in points]
        errors = [max(float(r["max_error"]), ERROR_FLOOR) for _, r in points]
        for panel, values in ((time_panel, times), (error_panel, errors)):
            panel.loglog(links, values, color=colour, linestyle=linestyle, linewidth=1.2, marker=marker, markersize=6,
                         label=f"{engine}: {method}")
            diverged = [(n, value) for n, value, (_, row) in zip(links, values, points) if row["finite"] != "1"]
            if diverged:
                panel.loglog(*zip(*diverged), marker=marker, linestyle="none", markersize=6, markeredgecolor=colour,
                             markerfacecolor="white")

    time_panel.set_xlabel("links")
    time_panel.set_ylabel("time per step (µs), 1 thread")
    time_panel.set_title("Time per step", fontsize=10)
    error_panel.set_xlabel("links")
    error_panel.set_ylabel("largest joint error over 2 s / link length")
    error_panel.set_title(f"Joint error (zero and rounding drawn at {ERROR_FLOOR:g})", fontsize=10)
    error_panel.axhline(1, color="grey", linewidth=0.6, linestyle=":")
    handles, labels = time_panel.get_legend_handles_labels()
    figure.legend(handles, labels, loc="lower center", ncol=3, fontsize=7.5, frameon=False)
    figure.suptitle("Heavy-end chain released horizontally, dt = 1/60 s, 2 s, no contacts "
                    "(solid: limber; dashed: other engines; hollow: diverged or reset)", fontsize=10)
    figure.tight_layout(rect=(0, 0.17, 1, 0.95))
    figure.savefig(out_png, dpi=110)


if __name__ == "__main__":
    main()
