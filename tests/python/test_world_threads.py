"""One World, one call at a time (tools/python/locked_world.hpp): two threads stepping one World
make the steps one thread would, bit for bit, under every method; edits on one thread land
between the steps of another; and World.run stops for Ctrl-C and for its wall_limit between two
steps (tools/python/run.cpp)."""
import os
import pathlib
import signal
import subprocess
import sys
import textwrap
import threading

import numpy as np
import pytest

import limber

SOURCE = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
SCENES = SOURCE / "tools" / "scenes"

# Every method, and the particles with worker threads of their own inside each step.
METHODS = [("weighted", {}), ("weighted", {"threads": 2}), ("unweighted", {}), ("springs-explicit", {}),
           ("springs-implicit", {}), ("lagrange", {}), ("featherstone", {})]


def scene(method):
    """The ragdoll (hinges, limits, a ball), or for the unweighted particles, which take only
    spherical joints at limb ends, the humanoid."""
    return limber.load_scene(str(SCENES / ("humanoid.json" if method == "unweighted" else "ragdoll.json")))


def ragdoll(method, options):
    world = limber.World(scene(method), method, **options)
    world.wake_all()  # the ragdoll starts asleep: stepping it must move something
    return world


def on_threads(count, work):
    """Runs work(k) on `count` threads started together; returns what each raised (None: nothing)."""
    start = threading.Barrier(count)
    raised = [None] * count

    def run(k):
        try:
            start.wait()
            work(k)
        except BaseException as error:  # reported to the test, which names it
            raised[k] = error

    threads = [threading.Thread(target=run, args=(k,)) for k in range(count)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=600)
        assert not thread.is_alive(), "a thread calling the World never returned"
    return raised


def state(world):
    return world.poses() + world.motions()


@pytest.mark.parametrize("method, options", METHODS, ids=[m + ("-threads" if o else "") for m, o in METHODS])
def test_two_threads_stepping_one_world_make_the_steps_of_one_thread(method, options):
    steps = 400
    alone = ragdoll(method, options)
    for _ in range(2 * steps):
        assert alone.step() == "ok"
    shared = ragdoll(method, options)
    statuses = [[], []]
    raised = on_threads(2, lambda k: statuses[k].extend(shared.step() for _ in range(steps)))
    assert raised == [None, None]
    assert statuses == [["ok"] * steps] * 2
    assert shared.time == alone.time
    for together, serial in zip(state(shared), state(alone)):
        np.testing.assert_array_equal(together, serial)


def crate(name):
    return {"name": name, "shape": {"type": "capsule", "length": 0.3, "radius": 0.05}, "mass": 2.0, "position": [3.0, 0.0, 2.0],
            "axis": [0, 0, 1]}


@pytest.mark.parametrize("method", limber.methods)
def test_edits_on_one_thread_land_between_the_steps_of_another(method):
    steps, edits = 150, 20
    serial = ragdoll(method, {})
    for _ in range(steps):
        serial.step()
    world = ragdoll(method, {})
    start = len(world.body_names)
    outcomes = []

    def work(k):
        if k == 0:
            for _ in range(steps):
                world.step()
            return
        for n in range(edits):
            for call, argument in (("add_body", crate(f"crate{n}")), ("remove_body", f"crate{n}")):
                try:
                    getattr(world, call)(argument)
                    outcomes.append((call, "done"))
                except (limber.ModelError, limber.WorldError) as error:  # a refusal is a typed error, never a crash
                    outcomes.append((call, type(error).__name__))

    assert on_threads(2, work) == [None, None]
    added = outcomes.count(("add_body", "done"))
    removed = outcomes.count(("remove_body", "done"))
    assert added == removed == edits  # each added crate was removed again: every edit made, whole
    assert len(world.body_names) == start
    assert world.time == serial.time  # every step taken, each of the scene's time step
    for array in state(world):
        assert np.isfinite(array).all()


def test_run_stops_after_the_step_that_passes_its_wall_limit_and_says_so():
    world = limber.World(limber.chain(links=2000), "weighted")
    result = world.run(10**9, wall_limit=0.2)
    assert result["stopped"] == "wall_limit"
    assert 0 < result["steps"] < 10**9
    # How far the chain gets in 0.2 s depends on the machine, and a long weighted chain turns
    # "inaccurate" after enough steps: the status must be the one those steps give, not "ok".
    replay = limber.World(limber.chain(links=2000), "weighted").run(result["steps"])
    assert replay["stopped"] == "steps" and replay["status"] == result["status"]
    assert world.time == pytest.approx(result["steps"] * limber.chain(links=2000).time_step)
    whole = world.run(3)
    assert whole["stopped"] == "steps" and whole["steps"] == 3
    with pytest.raises(limber.WorldError, match="wall_limit must be > 0"):
        world.run(1, wall_limit=0)
    with pytest.raises(limber.WorldError, match="wall_limit must be > 0"):
        world.run(1, wall_limit=float("nan"))


def test_a_run_that_diverges_says_it_stopped_at_the_status():
    world = limber.World(limber.chain(links=5), "weighted", dt=0.01)
    world.apply_impulse("link_4", np.array([0, 0, 1e9]), world.pose("link_4")[0])
    result = world.run(100)
    assert result["status"] != "ok" and result["stopped"] == "status" and result["steps"] < 100


CTRL_C = textwrap.dedent("""
    import limber
    world = limber.World(limber.chain(links=2000), "weighted")
    try:
        print("running", flush=True)
        world.run(10**9)  # hours
    except KeyboardInterrupt:
        print("interrupted at", repr(world.time), flush=True)
        assert world.step() == "ok"  # left consistent: it steps on
        raise
""")


def test_ctrl_c_stops_a_run_between_two_steps_with_keyboard_interrupt():
    child = subprocess.Popen([sys.executable, "-c", CTRL_C], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline() == "running\n"
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=60)  # ~50 ms unloaded; the limit only stops a run that ignores Ctrl-C
    finally:
        child.kill()
    assert err.rstrip().endswith("KeyboardInterrupt"), err
    assert child.returncode == -signal.SIGINT  # how Python ends on a KeyboardInterrupt nothing caught
    assert float(out.split("interrupted at ")[1]) >= 0  # the World says how far it went
