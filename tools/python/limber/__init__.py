"""limber from Python: scenes, and the World with its state as NumPy arrays.

    import limber
    scene = limber.load_scene("tools/scenes/ragdoll.json")
    world = limber.World(scene, method="featherstone")
    for _ in range(240):
        assert world.step() == "ok"
    positions, orientations = world.poses()   # N×3 m, N×4 (w, x, y, z)

Units are SI. Errors are limber.ModelError (a bad scene: the message names the file and the
field) and limber.WorldError (a bad call), both ValueErrors. World.step releases the GIL.
The C++ reference is kernel/world/world.hpp.
"""
from ._limber import ModelError, Scene, World, WorldError, load_scene, methods

__all__ = ["ModelError", "Scene", "World", "WorldError", "load_scene", "methods"]
