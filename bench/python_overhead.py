#!/usr/bin/python3
"""A Python step against a C++ step, raced in one run (bench/README.md, "Python").

    PYTHONPATH=build/python bench/python_overhead.py [--rounds 5]

For each scene, each round runs the same loop twice, one after the other: in C++
(build/bench/world_readout: World::step, then World::poses into one buffer) and in Python
(World.step(), then World.poses(), which returns new N x 3 and N x 4 arrays). Both start from
the scene's initial state and step the particle method with the scene's settings on one thread.
The ratios are Python's wall time over C++'s: the median of the rounds' ratios, and the ratio of
each side's fastest round (the least disturbed on a shared machine).

A second table splits the humanoid's Python cost inside one process, once the body sleeps (the
fastest of the rounds, µs a call): World.run(1000) (the same steps in a C++ loop inside the
module), World.step() alone, World.step(poses=out), and World.poses(out=out) alone.
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


def per_call_microseconds(rounds, calls=20000):
    """The humanoid asleep: (World.run per step, step(), step(poses=), poses(out=)), µs, fastest round."""
    scene = limber.load_scene(str(SCENES[0][1]))
    world = limber.World(scene, method="weighted", threads=1)
    world.run(4000, observe=False)  # the body has come to rest and sleeps
    count = len(world.body_names)
    out = (np.empty((count, 3)), np.empty((count, 4)))
    calls_of = {"World.run, a step": lambda: world.run(calls, observe=False), "step()": world.step,
                "step(poses=out)": lambda: world.step(poses=out), "poses(out=out)": lambda: world.poses(out=out)}
    best = {}
    for _ in range(rounds):
        for name, call in calls_of.items():
            repeats = 1 if name.startswith("World.run") else calls
            start = time.perf_counter()
            for _ in range(repeats):
                call()
            best[name] = min(best.get(name, float("inf")), (time.perf_counter() - start) / calls * 1e6)
    return best


def print_per_call(rounds):
    best = per_call_microseconds(rounds)
    print("\n| humanoid asleep, µs a call (fastest round) | " + " | ".join(best) + " |")
    print("|---|" + "---:|" * len(best))
    print("| | " + " | ".join(f"{value:.3f}" for value in best.values()) + " |")


if __name__ == "__main__":
    main()
    print_per_call(5)
