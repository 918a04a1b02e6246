"""limber from Python: scenes, and the World with its state as NumPy arrays.

    import limber
    scene = limber.load_scene("tools/scenes/ragdoll.json")
    world = limber.World(scene, method="featherstone")
    for _ in range(240):
        assert world.step() == "ok"
    positions, orientations = world.poses()   # N×3 m, N×4 (w, x, y, z)

Scenes come from files (load_scene) or the generators (chain, tree, grid, humanoid_pile, copies).
A World is edited while it runs: add_body, add_joint, add_collider and add_ball take dicts in the
scene file's terms (kernel/scene/scene_file.hpp), read by the scene loader itself; pin returns a
limber.Pin and add_ball a limber.Ball (handles; bodies, joints and colliders go by name).

Units are SI. A World's options are `limber run`'s flags, spelled with underscores
(World(scene, "weighted", iterations=20, substeps=4, dt=1/240)); limber.sweep runs grids of them.
Errors are limber.ModelError (a bad scene or description: the message names the file or call,
and the field), limber.OptionError (a bad option) and limber.WorldError (a bad call), all
ValueErrors; besides them only TypeError (an argument of the wrong type, or an object made by
__new__ without __init__) and KeyboardInterrupt (Ctrl-C stops World.run between two steps).

Threads: World.step and World.run release the GIL, so Worlds on several threads step at once.
One World takes one call at a time: calls on it from several threads wait their turn (with the
GIL released), so two threads stepping one World make the steps one thread would, bit for bit,
and an edit on one thread lands between two steps of another. The C++ reference is
kernel/world/world.hpp; tools/python/README.md maps each C++ call to its Python counterpart.
"""
from . import _limber
from ._limber import (Ball, ModelError, OptionError, Pin, Scene, WorldError, chain, copies, grid, humanoid_pile, load_scene,
                      methods, tree)


class World(_limber.World):
    """One scene under one method, stepped and read (kernel/world/world.hpp).

    method: 'weighted', 'unweighted', 'springs-explicit', 'springs-implicit', 'lagrange' or
    'featherstone' (`limber run --method`). options: `limber run`'s other flags with '_' for '-'
    (dt, iterations, substeps, projection, solver, newton_iterations, integrator, stiffness,
    threads, ...; `limber run --help` lists them): True is a bare flag, a sequence is
    comma-joined. The flags that load a scene (body, links, copies, floating_base) belong to
    load_scene. The World steps a copy of `scene` with the options' changes (dt, friction, ball_*).
    Raises OptionError with limber run's message for a bad option. `method` (read-only) is the
    method's name as given. One call at a time (the module's docstring, "Threads").
    """

    def __init__(self, scene, method="weighted", **options):
        if "options" in self.__dict__:  # pybind11 would ignore a second construction, leaving `options` to lie
            raise WorldError("World.__init__: this World is made already; make another with limber.World(scene, method)")
        super().__init__(scene, method, options)
        self.options = dict(options)

    def __repr__(self):
        return f"limber.World(method={self.method!r}, bodies={len(self.body_names)}, time={self.time:g} s)"


__all__ = ["Ball", "ModelError", "OptionError", "Pin", "Scene", "World", "WorldError", "chain", "copies", "grid", "humanoid_pile",
           "load_scene", "methods", "tree"]
