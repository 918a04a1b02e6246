#!/usr/bin/python3
"""A Python step against a C++ step, raced in one run (bench/README.md, "Python").

    PYTHONPATH=build/python bench/python_overhead.py [--rounds 5]

For each scene, each round runs the same loop twice, one after the other: in C++
(build/bench/world_readout: World::step, then World::poses into one buffer) and in Python
(World.step(), then World.poses(), which returns new N x 3 and N x 4 arrays). Both start from
the scene's initial state and step the particle method with the scene's settings on one thread.
The ratios are Python's wall time over C++'s: the median of the rounds' ratios, and the ratio of
each side's fastest round (the least disturbed on a shared machine).
"""
import argparse
import pathlib
import statistics
import subprocess
import time

import numpy as np

import limber

ROOT = pathlib.Path(__file__).resolve().parents[1]
PROGRAM = ROOT / "build" / "bench" / "world_readout"
SCENES = [  # (label, scene file, links, steps)
    ("humanoid (tools/scenes/humanoid.json)", ROOT / "tools" / "scenes" / "humanoid.json", None, 4000),
    ("chain of 10^4 links (chain.json, links 10000)", ROOT / "tools" / "scenes" / "chain.json", 10000, 200),
]


def cpp_seconds(scene, links, steps):
    command = [str(PROGRAM), str(scene), str(steps)] + ([str(links)] if links else [])
    return float(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def python_seconds(scene, links, steps):
    world = limber.World(limber.load_scene(str(scene), links=links), method="weighted", threads=1)
    count = len(world.body_names)
    out = (np.empty((count, 3)), np.empty((count, 4)))
    start = time.perf_counter()
    for _ in range(steps):
        world.step(poses=out)
    return time.perf_counter() - start


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    rounds = parser.parse_args().rounds
    print("| scene | steps | C++ ms/step (median, fastest) | Python ms/step (median, fastest) | Python / C++ (median, fastest) |")
    print("|---|---:|---:|---:|---:|")
    for label, scene, links, steps in SCENES:
        cpp, python = [], []
        for _ in range(rounds):
            cpp.append(cpp_seconds(scene, links, steps))
            python.append(python_seconds(scene, links, steps))
        ratio = statistics.median(p / c for p, c in zip(python, cpp))
        print(f"| {label} | {steps} | {1e3 * statistics.median(cpp) / steps:.4f}, {1e3 * min(cpp) / steps:.4f} | "
              f"{1e3 * statistics.median(python) / steps:.4f}, {1e3 * min(python) / steps:.4f} | {ratio:.3f}, {min(python) / min(cpp):.3f} |")


if __name__ == "__main__":
    main()
