#!/usr/bin/env python3
"""Writes the rope of Jolt Physics' soft-body comparison (bench/chains.md, "The rope against Jolt").

    bench/rope_scene.py N > rope.json

N particles 0.1 m apart along +x at rest, 1 kg each and the last 2 kg, the first pinned at the
origin; distance constraints between neighbours (no joints to relax separately, no collisions):
the rope of bench/chains.md ("The heavy-end chain"), as Jolt's XPBD soft body sees it. In limber's scene
format: N - 1 massless capsules whose point masses (0.5 kg at each end, 2 kg at the last tail)
lump into shared particles (settings.verlet: shared-particle joints, lumped limb masses).
"""
import argparse
import json

LINK = 0.1  # m


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("particles", type=int, help="number of particles, >= 2")
    args = parser.parse_args()
    if args.particles < 2:
        parser.error("need particles >= 2")
    links = args.particles - 1
    bodies, joints = [], []
    for k in range(links):
        tail = 2.0 if k == links - 1 else 0.5
        bodies.append({"name": f"l{k}", "shape": {"type": "capsule", "length": LINK, "radius": 0.001},
                       "point_masses": [{"position": [0, 0, LINK / 2], "mass": 0.5},
                                        {"position": [0, 0, -LINK / 2], "mass": tail}],
                       "position": [LINK * k + LINK / 2, 0, 0], "axis": [-1, 0, 0],
                       "collision": {"group": 2, "mask": 0}})
        inboard = {"inboard": "world", "inboard_anchor": [0, 0, 0]} if k == 0 else {"inboard": f"l{k - 1}", "inboard_anchor": "tail"}
        joints.append({"name": f"j{k}", "type": "spherical", **inboard, "outboard": f"l{k}", "outboard_anchor": "head"})
    scene = {"limber_scene": 1, "name": f"rope of {args.particles} particles",
             "description": "Jolt's soft-body rope: 0.1 m apart, 1 kg (the last 2 kg), the first pinned, along +x, at rest",
             "settings": {"gravity": [0, 0, -9.81], "time_step": 1 / 60, "duration": 2,
                          "verlet": {"joints": "shared_particle", "limb_masses": "lumps"}},
             "bodies": bodies, "joints": joints}
    print(json.dumps(scene, separators=(",", ":")))


if __name__ == "__main__":
    main()
