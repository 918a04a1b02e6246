"""The Python module against the C++ World it binds (tools/python/limber_module.cpp): shapes,
dtypes and units of the arrays, errors carrying the C++ message, joint space, and two Worlds
stepping on two threads giving the bits they give one after the other."""
import os
import pathlib
import threading

import numpy as np
import pytest

import limber

SCENES = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2])) / "tools" / "scenes"


def ragdoll(method="weighted"):
    return limber.World(limber.load_scene(str(SCENES / "ragdoll.json")), method=method)


def test_poses_and_motions_are_one_float64_row_per_body():
    world = ragdoll()
    count = len(world.body_names)
    positions, orientations = world.poses()
    linear, angular = world.motions()
    assert positions.shape == (count, 3) and orientations.shape == (count, 4)
    assert linear.shape == (count, 3) and angular.shape == (count, 3)
    assert positions.dtype == np.float64 and orientations.dtype == np.float64
    np.testing.assert_allclose(np.linalg.norm(orientations, axis=1), 1, atol=1e-12)


def test_a_ragdoll_falls_under_gravity_alone():
    world = ragdoll()
    start = world.observe()
    for _ in range(60):
        assert world.step() == "ok"
    now = world.observe()
    assert world.time == pytest.approx(60 * limber.load_scene(str(SCENES / "ragdoll.json")).time_step)
    assert now["body_centre_of_mass"][2] < start["body_centre_of_mass"][2]
    assert now["energy"] <= start["energy"] + 1e-6 * abs(start["energy"])  # no energy made


def test_a_force_moves_the_body_it_is_applied_to():
    world = ragdoll("featherstone")
    body = world.body_names[0]
    positions, _ = world.poses()
    world.apply_impulse(body, np.array([0.0, 50.0, 0.0]), positions[0])
    world.step()
    linear, _ = world.motions()
    assert linear[0, 1] > 0.1  # m/s, along the impulse


def test_a_bad_scene_raises_with_the_files_name_and_field(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text((SCENES / "ragdoll.json").read_text().replace('"limber_scene": 1', '"limber_scene": 7', 1))
    with pytest.raises(limber.ModelError, match=r"bad\.json: limber_scene: unsupported version 7"):
        limber.load_scene(str(bad))
    with pytest.raises(limber.ModelError, match="cannot read file"):
        limber.load_scene(str(tmp_path / "missing.json"))


def test_bad_calls_raise_world_errors_and_change_nothing():
    world = ragdoll()
    with pytest.raises(limber.WorldError, match="no body"):
        world.apply_torque("no such body", np.zeros(3))
    with pytest.raises(limber.WorldError):
        world.set_controls(np.ones(3))  # the ragdoll has no actuators
    with pytest.raises(limber.WorldError, match="featherstone has"):
        world.joint_positions()
    with pytest.raises(limber.OptionError, match="--method: verlet not in"):
        limber.World(limber.load_scene(str(SCENES / "ragdoll.json")), method="verlet")
    with pytest.raises(ValueError, match="expected 3 numbers"):
        world.apply_torque(world.body_names[0], np.zeros(2))
    assert world.time == 0


def test_joint_space_reads_back_and_its_dynamics_close():
    world = ragdoll("featherstone")
    q, v = world.joint_positions(), world.joint_velocities()
    assert len(world.joint_space_names()) == v.shape[0]
    assert len(world.joint_position_names()) == q.shape[0] and all(world.joint_position_names())
    v = np.linspace(-1, 1, v.shape[0])
    world.set_joint_state(q, v)
    np.testing.assert_array_equal(world.joint_velocities(), v)
    forces = np.linspace(2, -3, v.shape[0])
    acceleration = world.joint_accelerations(forces)
    np.testing.assert_allclose(world.joint_mass_matrix() @ acceleration + world.joint_bias_forces(), forces, atol=1e-9)
    np.testing.assert_allclose(world.inverse_dynamics(acceleration), forces, atol=1e-9)
    reaction_forces, reaction_torques = world.joint_reactions(acceleration)
    assert reaction_forces.shape == (len(limber.load_scene(str(SCENES / "ragdoll.json")).joint_names), 3)
    assert reaction_torques.shape == reaction_forces.shape


def run(world, steps):
    for _ in range(steps):
        world.step()


def test_two_worlds_on_two_threads_give_the_bits_of_one_after_the_other():
    alone = [ragdoll(), ragdoll("featherstone")]
    for world in alone:
        run(world, 120)
    together = [ragdoll(), ragdoll("featherstone")]
    threads = [threading.Thread(target=run, args=(world, 120)) for world in together]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for a, b in zip(alone, together):
        for x, y in zip(a.poses() + a.motions(), b.poses() + b.motions()):
            np.testing.assert_array_equal(x, y)


def test_step_with_poses_fills_the_arrays_poses_returns_after_the_step():
    stepped, read = ragdoll("featherstone"), ragdoll("featherstone")
    count = len(stepped.body_names)
    out = (np.full((count, 3), np.nan), np.full((count, 4), np.nan))
    for _ in range(5):
        assert stepped.step(poses=out) == "ok" and read.step() == "ok"
    positions, orientations = read.poses()
    assert np.array_equal(out[0], positions) and np.array_equal(out[1], orientations)
    time = stepped.time
    with pytest.raises(ValueError, match="out"):
        stepped.step(poses=(np.zeros((count, 3)), np.zeros((count, 3))))  # orientations need 4 columns
    assert stepped.time == time  # refused before the step
