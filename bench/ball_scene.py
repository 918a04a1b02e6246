#!/usr/bin/env python3
"""Writes a scene of many balls for the scaling measurements (bench/speed.md, "Linear costs").

    bench/ball_scene.py N [--links L] > balls.json

N balls (radius 0.05 m, 1 kg, restitution 0.5) on a square lattice 0.25 m apart, 1 m above the
ground, thrown down at 1 m/s with a small sideways part that differs from ball to ball (so their
paths are not all parallel), over a chain of L links (default 5, chain.json's generator; 0: no
chain) lying across the lattice at 0.5 m. Balls meet each other, the ground and the chain's
links. The same text on every run: no randomness.
"""
import argparse
import json
import math


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("balls", type=int, help="number of balls, >= 1")
    parser.add_argument("--links", type=int, default=5, help="links of the chain under them (0: none)")
    args = parser.parse_args()
    if args.balls < 1 or args.links < 0:
        parser.error("need balls >= 1 and links >= 0")
    spacing = 0.25
    side = math.ceil(math.sqrt(args.balls))
    balls = []
    for k in range(args.balls):
        i, j = k % side, k // side
        # A sideways part between -0.2 and 0.2 of the downward speed, from the ball's index.
        dx = ((k * 7919) % 41 - 20) / 100
        dy = ((k * 104729) % 37 - 18) / 90
        balls.append({"radius": 0.05, "mass": 1.0, "restitution": 0.5,
                      "position": [i * spacing, j * spacing, 1.0],
                      "speed": 1.0, "direction": [dx, dy, -1.0]})
    scene = {
        "limber_scene": 1,
        "name": f"balls_{args.balls}",
        "description": f"{args.balls} balls on a {side}x{side} lattice falling onto the ground and a "
                       f"{args.links}-link chain (bench/ball_scene.py)",
        "settings": {"gravity": [0, 0, -9.81], "time_step": 1 / 240, "duration": 1},
        "ground": {"height": 0, "restitution": 0.1, "friction": 0.5},
        "balls": balls,
    }
    if args.links > 0:
        length = side * spacing / args.links
        scene["chain"] = {"links": args.links, "shape": "capsule", "link_length": length, "link_radius": 0.02,
                          "link_mass": 1.0, "end_mass": 1.0, "anchor": [0, 0.5 * side * spacing, 0.5], "direction": [1, 0, 0],
                          "pinned": True}
    json.dump(scene, fp=__import__("sys").stdout, indent=None)
    print()


if __name__ == "__main__":
    main()
