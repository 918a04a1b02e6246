#!/usr/bin/python3
# Plots relaxation_bench's JSON (and relaxation_study's CSV) as PNGs.
#
#   tools/plot_relaxation.py --json FILE [--study CSV] [--out DIR]
#
#   FILE: build/bench/relaxation_bench --benchmark_out=FILE --benchmark_out_format=json
#   CSV:  build/bench/relaxation_study --csv CSV          (convergence.png only with --study)
#   DIR:  where the PNGs go (default: build/plots)
# Needs Debian's python3-matplotlib (apt-get install python3-matplotlib).
import argparse
import csv
import os
import sys

sys.dont_write_bytecode = True  # no __pycache__ in tools/
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from relaxation_report import REPO, best_2t, load, workloads  # noqa: E402

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit("plot_relaxation: matplotlib is missing; install Debian's python3-matplotlib "
             "(apt-get install python3-matplotlib) and run this with /usr/bin/python3")


def series(results, kind, family, t, path):
    """[(links, entry)] for one family (chain | tree), sorted by size; path '2t' = best two-thread."""
    points = []
    for w in workloads(results):
        if not w.startswith(family + "_"):
            continue
        e = best_2t(results, kind, w, t)[0] if path == "2t" else results.get((kind, w, t, path))
        if e:
            points.append((int(w.split("_")[1]), e))
    return sorted(points, key=lambda p: p[0])


LINES = [("scalar", "float", "scalar, float", "-", "o"), ("simd", "float", "SIMD, float", "-", "s"),
         ("2t", "float", "SIMD 2 threads (best), float", "-", "^"), ("simd", "double", "SIMD, double", "--", "s")]


def steps_per_second(results, out):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, family in zip(axes, ("chain", "tree")):
        for path, t, label, style, marker in LINES:
            pts = series(results, "Step", family, t, path)
            if pts:
                ax.plot([n for n, _ in pts], [e.get("steps/s", 1e6 / e["us"]) for _, e in pts],
                        style, marker=marker, label=label)
        ax.set(xscale="log", yscale="log", xlabel="links", title=f"{family}s: full steps per second (10 sweeps a step)")
        ax.grid(True, which="both", alpha=0.3)
        if ax.lines:
            ax.legend()
    axes[0].set_ylabel("steps / s")
    return save(fig, out, "steps_per_second.png")


def sweep_time_per_constraint(results, out):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for path, t, label, style, marker in LINES[:3]:
        pts = series(results, "Sweep", "chain", t, path)
        if pts:
            ax.plot([n for n, _ in pts], [e["us"] * 1e3 / e["constraints"] for _, e in pts],
                    style, marker=marker, label=label)
    ax.set(xscale="log", yscale="log", xlabel="links", ylabel="ns per constraint per sweep",
           title="chains: sweep time per constraint (flat = linear)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return save(fig, out, "sweep_time_per_constraint.png")


def convergence(study, out):
    data = {}
    with open(study) as f:
        for row in csv.DictReader(f):
            stretch = float(row["largest_stretch"])
            if stretch >= 0:  # -1: diverged
                data.setdefault(row["variant"], []).append((int(row["sweeps"]), stretch))
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for k, (variant, pts) in enumerate(data.items()):  # varied styles: some series coincide
        pts.sort()
        ax.plot([s for s, _ in pts], [x for _, x in pts], ("-", "--", ":")[k % 3], marker="osv^D<>"[k % 7],
                label=variant, fillstyle="none")
    ax.set(xscale="log", yscale="log", xlabel="sweeps per step", ylabel="largest link stretch (relative)",
           title="convergence: 100-link chain, heavy end, 1 s at 240 Hz")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    return save(fig, out, "convergence.png")


def save(fig, out, name):
    path = os.path.join(out, name)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main():
    parser = argparse.ArgumentParser(description="PNG plots of relaxation_bench / relaxation_study output.")
    parser.add_argument("--json", required=True, help="relaxation_bench JSON output")
    parser.add_argument("--study", help="relaxation_study CSV (for convergence.png)")
    parser.add_argument("--out", default=os.path.join(REPO, "build", "plots"), help="output directory")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    results, _ = load(args.json)
    written = [steps_per_second(results, args.out), sweep_time_per_constraint(results, args.out)]
    if args.study:
        written.append(convergence(args.study, args.out))
    print("\n".join(written))


if __name__ == "__main__":
    main()
