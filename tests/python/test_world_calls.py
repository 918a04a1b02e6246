"""Every C++ World call's Python counterpart (tools/python/edits.cpp, reports.cpp, generators.cpp),
each held to a physical fact: a pinned point stays put, a teleported body is where it was sent, an
added body falls, a drive pulls its joint to its target; and tools/python/README.md's table names
every public member of kernel/world/world.hpp's World."""
import json
import os
import pathlib
import re

import numpy as np
import pytest

import limber

SOURCE = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
SCENES = SOURCE / "tools" / "scenes"


def ragdoll(method="weighted"):
    world = limber.World(limber.load_scene(str(SCENES / "ragdoll.json")), method=method)
    world.wake_all()  # the ragdoll starts asleep
    return world


def steps(world, count):
    for _ in range(count):
        assert world.step() == "ok"


def crate(name="crate", position=(3.0, 0.0, 2.0)):
    return {"name": name, "shape": {"type": "capsule", "length": 0.3, "radius": 0.05}, "mass": 2.0, "position": list(position),
            "axis": [0, 0, 1]}


def rotation(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def world_point(world, body, local):
    position, orientation = world.pose(body)
    return position + rotation(orientation) @ np.asarray(local)


# --- The table in tools/python/README.md

def world_member_names():
    """The public member functions of class World in kernel/world/world.hpp."""
    text = (SOURCE / "kernel" / "world" / "world.hpp").read_text()
    body = text[text.index("class World {"):]
    public = body[body.index(" public:"):body.index(" private:")]
    names = set()
    for line in public.splitlines():
        code = line.split("//")[0]
        match = re.match(r"\s*(?:explicit\s+)?(?:[\w:<>,&*\s]+?[\s&*])?(~?\w+|operator=)\s*\(", code)
        if match:
            names.add(match.group(1))
    return names


def test_the_readme_table_names_every_public_world_call():
    names = world_member_names()
    assert {"step", "teleport", "add_ball", "internals", "World", "~World", "operator="} <= names  # the parse sees them
    table = (SOURCE / "tools" / "python" / "README.md").read_text()
    cpp_column = {m.group(1) for m in re.finditer(r"^\|\s*`([^`]+)`", table, re.MULTILINE)}
    missing = sorted(name for name in names if name not in cpp_column)
    assert not missing, f"tools/python/README.md's table lacks {missing}"


# --- Reading

def test_one_bodys_pose_and_motion_are_its_rows_of_the_bulk_read_outs():
    world = ragdoll()
    steps(world, 10)
    positions, orientations = world.poses()
    linear, angular = world.motions()
    for row, name in enumerate(world.body_names):
        position, orientation = world.pose(name)
        np.testing.assert_array_equal(position, positions[row])
        np.testing.assert_array_equal(orientation, orientations[row])
        velocity, spin = world.motion(name)
        np.testing.assert_array_equal(velocity, linear[row])
        np.testing.assert_array_equal(spin, angular[row])


def test_poses_and_motions_fill_given_arrays_with_the_bits_they_return():
    world = ragdoll()
    steps(world, 5)
    n = len(world.body_names)
    out = (np.empty((n, 3)), np.empty((n, 4)))
    assert world.poses(out=out) is out
    for given, fresh in zip(out, world.poses()):
        np.testing.assert_array_equal(given, fresh)
    motion_out = (np.empty((n, 3)), np.empty((n, 3)))
    assert world.motions(out=motion_out) is motion_out
    for given, fresh in zip(motion_out, world.motions()):
        np.testing.assert_array_equal(given, fresh)


@pytest.mark.parametrize("bad, named", [
    (lambda n: (np.empty((n, 3), np.float32), np.empty((n, 4))), r"out\[0\] \(positions\).*got float32"),
    (lambda n: (np.empty((n, 3)), np.empty((n, 3))), r"out\[1\] \(orientations\).*shape \(\d+, 4\)"),
    (lambda n: (np.empty((n, 3)), np.empty((n, 4), order="F")), r"out\[1\].*not C-contiguous"),
    (lambda n: (np.empty((n, 3)), [[0.0] * 4] * n), r"out\[1\].*got list"),
    (lambda n: np.empty((n, 3)), r"out must be a tuple"),
])
def test_poses_refuses_arrays_it_cannot_fill_naming_them(bad, named):
    world = ragdoll()
    with pytest.raises(ValueError, match=named):
        world.poses(out=bad(len(world.body_names)))


def test_the_last_report_has_the_documented_keys():
    world = ragdoll()
    world.step()
    report = world.last_report()
    assert set(report) == {"status", "contacts", "stop", "iterations", "largest_correction", "substeps", "fallbacks",
                           "linear_solver_iterations", "linear_solver_error", "constraint_error", "angular_error", "profile"}
    assert report["status"] == "ok" and report["stop"] in {"iterations", "tolerance", "budget", "idle"}
    assert report["iterations"] > 0 and report["substeps"] >= 1  # the weighted relaxation ran
    assert {"step", "integrate", "relax", "contacts", "substeps"} <= set(report["profile"])
    trees = {"tree_staging", "tree_elimination", "tree_moves", "tree_contacts"}  # parts of relax, in s
    assert trees <= set(report["profile"])
    assert sum(report["profile"][key] for key in trees) <= report["profile"]["relax"] + report["profile"]["velocity"]
    assert world.step(dt=0.0) == "invalid_time_step" and world.last_report()["status"] == "invalid_time_step"


def test_segments_are_the_limbs_and_balls_as_collision_sees_them():
    world = ragdoll()
    ball = world.add_ball({"radius": 0.1, "mass": 1, "restitution": 0.5, "position": [2, 0, 1], "speed": 0, "direction": [1, 0, 0]})
    heads, tails, radii = world.segments()
    count = len(world.body_names) + len(world.balls())
    assert heads.shape == tails.shape == (count, 3) and radii.shape == (count,)
    for row, name in enumerate(world.body_names):
        shape = world.body_description(name)["shape"]
        assert radii[row] == pytest.approx(shape["radius"])
        assert np.linalg.norm(heads[row] - tails[row]) == pytest.approx(shape["length"], rel=1e-6)
    np.testing.assert_allclose(heads[-1], world.ball(ball)[0])
    np.testing.assert_array_equal(heads[-1], tails[-1])
    assert radii[-1] == 0.1


# --- Structure

def test_an_added_body_appears_and_falls_under_gravity():
    world = ragdoll()
    assert world.add_body(crate()) == "crate"
    assert world.body_names[-1] == "crate"
    world.wake("crate")  # the ragdoll's bodies start asleep (settings.sleep.start_asleep), and so does one added
    start = world.pose("crate")[0]
    np.testing.assert_allclose(start, [3, 0, 2])
    steps(world, 30)
    now = world.pose("crate")[0]
    assert now[2] < start[2] - 0.01 and abs(now[0] - 3) < 1e-6  # straight down
    description = world.body_description("crate")
    assert description["mass"] == 2 and description["shape"]["length"] == 0.3


def test_a_body_description_reads_back_into_the_same_body():
    world = ragdoll()
    twin = world.body_description("head")
    twin["name"] = "head_twin"
    twin["position"] = np.array(twin["position"]) + [0, 2, 0]  # NumPy arrays are taken too
    world.add_body(twin)
    again = world.body_description("head_twin")
    for key in ("shape", "mass", "axis", "collision"):
        assert again[key] == world.body_description("head")[key]


def test_a_box_and_an_ellipsoid_are_described_as_themselves_and_read_back():
    world = ragdoll()
    turn = [np.cos(0.3), 0.0, 0.0, np.sin(0.3)]  # 0.6 rad about the body's axis
    world.add_body({"name": "box", "shape": {"type": "box", "half_extents": [0.1, 0.2, 0.3], "rotation": turn}, "mass": 2.0,
                    "position": [3, 0, 2], "axis": [0, 0, 1]})
    world.add_body({"name": "egg", "shape": {"type": "ellipsoid", "half_extents": (0.05, 0.04, 0.08)}, "density": 1000.0,
                    "position": [4, 0, 2], "axis": [1, 0, 0]})
    assert world.body_description("box")["shape"] == {"type": "box", "half_extents": [0.1, 0.2, 0.3], "rotation": turn}
    egg = world.body_description("egg")
    assert egg["shape"] == {"type": "ellipsoid", "half_extents": [0.05, 0.04, 0.08], "rotation": [1, 0, 0, 0]}  # the identity
    assert egg["mass"] == pytest.approx(1000 * 4 / 3 * np.pi * 0.05 * 0.04 * 0.08, rel=1e-15)
    for name in ("box", "egg"):
        twin = world.body_description(name)
        twin["name"] = name + "_twin"
        twin["position"] = np.array(twin["position"]) + [0, 2, 0]
        world.add_body(twin)
        again = world.body_description(name + "_twin")
        for key in ("shape", "mass", "axis", "collision"):
            assert again[key] == world.body_description(name)[key]


@pytest.mark.parametrize("shape, named", [
    ({"type": "box", "half_extents": [0.1, 0.2, 0.3], "length": 0.3},
     r"add_body: bodies\[0\]\.shape\.length: a box has half_extents, not this field; leave it out"),
    ({"type": "ellipsoid", "half_extents": [0.1, 0.0, 0.3]}, r"add_body: bodies\[0\]\.shape\.half_extents\[1\]: must be > 0, got 0"),
    ({"type": "box", "half_extents": [0.1, 0.2, 0.3], "rotation": [1, 0, 0, 0.5]},
     r"add_body: bodies\[0\]\.shape\.rotation: must be a unit quaternion \[w, x, y, z\]"),
    ({"type": "capsule", "length": 0.3, "radius": 0.05, "half_extents": [0.1, 0.1, 0.1]},
     r"add_body: bodies\[0\]\.shape\.half_extents: a capsule has a length and a radius, not this field; leave it out"),
])
def test_a_bad_box_or_ellipsoid_is_a_model_error_naming_the_field(shape, named):
    world = ragdoll()
    before = world.body_names
    with pytest.raises(limber.ModelError, match=named):
        world.add_body(dict(crate(), shape=shape))
    assert world.body_names == before


@pytest.mark.parametrize("change, named", [
    ({"mass": -1.0}, r"add_body: bodies\[0\]\.mass: must be > 0, got -1"),
    ({"colour": "red"}, r"add_body: bodies\[0\]: unknown field \"colour\""),
    ({"position": [0, float("nan"), 1]}, r"add_body: bodies\[0\]\.position\[1\]: must be a finite number, got nan"),
    ({"shape": {"type": "cube", "length": 1, "radius": 1}}, r"bodies\[0\]\.shape\.type: must be \"cylinder\", \"capsule\", \"box\" or \"ellipsoid\", got \"cube\""),
    ({"axis": [0, 0, 0]}, r"bodies\[0\]\.axis"),
])
def test_a_bad_body_field_raises_a_model_error_naming_it_and_changes_nothing(change, named):
    world = ragdoll()
    before = world.body_names
    with pytest.raises(limber.ModelError, match=named):
        world.add_body({**crate(), **change})
    assert world.body_names == before
    world.step()


def test_a_duplicate_body_name_is_refused():
    world = ragdoll()
    with pytest.raises(limber.ModelError, match="head"):
        world.add_body(crate(name="head"))
    assert world.body_names.count("head") == 1


def test_a_removed_body_disappears_with_its_joints_and_the_world_steps():
    world = ragdoll()
    world.remove_body("forearm_left")
    assert "forearm_left" not in world.body_names
    assert "upper_arm_left-forearm_left" not in world.joint_names
    steps(world, 20)
    assert world.poses()[0].shape == (len(world.body_names), 3)
    with pytest.raises(limber.WorldError, match="no body called 'forearm_left'"):
        world.pose("forearm_left")


def test_an_added_joint_holds_its_body_and_removing_it_lets_go():
    world = ragdoll("lagrange")
    world.add_body(crate())
    world.wake("crate")
    hook = {"name": "hook", "type": "spherical", "inboard": "world", "outboard": "crate", "inboard_anchor": [3, 0, 2.15],
            "outboard_anchor": "head"}
    assert world.add_joint(hook) == "hook" and "hook" in world.joint_names
    steps(world, 60)
    np.testing.assert_allclose(world_point(world, "crate", [0, 0, 0.15]), [3, 0, 2.15], atol=1e-3)
    world.remove_joint("hook")
    world.wake("crate")
    steps(world, 30)
    assert world.pose("crate")[0][2] < 2.0 - 0.01


def test_a_joint_between_two_bodies_reads_head_and_tail_by_their_shapes():
    world = ragdoll("lagrange")
    world.add_body(crate("a", (3, 0, 2)))
    world.add_body(crate("b", (3, 0, 1.7)))
    world.add_joint({"name": "ab", "type": "spherical", "inboard": "a", "outboard": "b", "inboard_anchor": "tail",
                     "outboard_anchor": "head"})
    steps(world, 30)
    np.testing.assert_allclose(world_point(world, "a", [0, 0, -0.15]), world_point(world, "b", [0, 0, 0.15]), atol=1e-3)


@pytest.mark.parametrize("change, named", [
    ({"outboard": "nobody"}, r"add_joint: joints\[0\]\.outboard: no body named \"nobody\""),
    ({"type": "hinge"}, r"joints\[0\]\.type: must be \"spherical\""),
    ({"outboard_anchor": "middle"}, r"joints\[0\]\.outboard_anchor: must be \"head\", \"tail\" or \[x, y, z\]"),
    ({"inboard_anchor": "head"}, r"joints\[0\]\.inboard_anchor: must be a world point"),
])
def test_a_bad_joint_field_raises_a_model_error_naming_it(change, named):
    world = ragdoll()
    world.add_body(crate())
    before = world.joint_names
    hook = {"name": "hook", "type": "spherical", "inboard": "world", "outboard": "crate", "inboard_anchor": [3, 0, 2.15],
            "outboard_anchor": "head"}
    with pytest.raises(limber.ModelError, match=named):
        world.add_joint({**hook, **change})
    assert world.joint_names == before


def test_an_added_model_arrives_moved_by_its_offset():
    scene = limber.load_scene(str(SCENES / "ragdoll.json"))
    world = limber.World(scene, method="weighted")
    names = world.add_model(scene, "b.", offset=np.array([2.0, 0, 0]))
    assert names == ["b." + name for name in scene.body_names]
    positions = world.poses()[0]
    count = len(scene.body_names)
    np.testing.assert_allclose(positions[count:], positions[:count] + [2, 0, 0], atol=1e-12)
    world.step()


def test_an_added_collider_holds_up_what_falls_on_it_until_removed():
    world = ragdoll()
    world.add_body(crate(position=(3, 0, 1.0)))
    world.wake("crate")
    box = {"name": "table", "type": "box", "position": [3, 0, 0.5], "half_extents": [0.5, 0.5, 0.1]}
    assert world.add_collider(box) == "table" and world.collider_names == ["table"]
    steps(world, 240)
    assert world.pose("crate")[0][2] > 0.6 - 0.01  # resting on the table top (z 0.6)
    world.remove_collider("table")
    assert world.collider_names == []
    world.wake("crate")
    steps(world, 60)
    assert world.pose("crate")[0][2] < 0.5


def test_a_bad_collider_or_ball_field_raises_a_model_error_naming_it():
    world = ragdoll()
    with pytest.raises(limber.ModelError, match=r"add_collider: colliders\[0\]\.half_extents"):
        world.add_collider({"name": "t", "type": "box", "position": [0, 0, 0], "half_extents": [0.5, -1, 0.1]})
    with pytest.raises(limber.ModelError, match=r"add_ball: balls\[0\]\.radius: must be > 0"):
        world.add_ball({"radius": 0, "mass": 1, "restitution": 0.5, "position": [0, 0, 1], "speed": 1, "direction": [1, 0, 0]})
    assert world.collider_names == [] and len(world.balls()) == 1  # the ragdoll's own ball


def test_a_thrown_ball_flies_and_is_gone_once_removed():
    world = ragdoll()
    own = world.balls()  # the ragdoll's
    ball = world.add_ball({"radius": 0.05, "mass": 1, "restitution": 0.5, "position": [-3, 0, 1], "speed": 5, "direction": [-1, 0, 0]})
    assert world.balls() == own + [ball]
    position, velocity = world.ball(ball)
    np.testing.assert_allclose(position, [-3, 0, 1])
    np.testing.assert_allclose(velocity, [-5, 0, 0])
    steps(world, 10)
    assert world.ball(ball)[0][0] < -3  # moving away along -x
    world.remove_ball(ball)
    assert world.balls() == own
    with pytest.raises(limber.WorldError):
        world.ball(ball)


def test_another_worlds_handles_are_refused():
    a, b = ragdoll(), ragdoll()
    ball = a.add_ball({"radius": 0.05, "mass": 1, "restitution": 0.5, "position": [-3, 0, 1], "speed": 0, "direction": [1, 0, 0]})
    with pytest.raises(limber.WorldError, match="another World"):
        b.ball(ball)


# --- Held points, teleports, sleep, drives

@pytest.mark.parametrize("method", ["weighted", "lagrange"])  # the springs' hold is a spring: it gives
def test_a_pinned_point_stays_where_it_was_held(method):
    world = ragdoll(method)
    head = [0, 0, world.body_description("head")["shape"]["length"] / 2]
    pin = world.pin("head", np.array(head, dtype=float))
    held = world.pin_position(pin)
    np.testing.assert_allclose(held, world_point(world, "head", head), atol=1e-9)
    steps(world, 120)
    np.testing.assert_allclose(world_point(world, "head", head), held, atol=2e-3)
    world.unpin(pin)
    with pytest.raises(limber.WorldError, match="pin"):
        world.pin_position(pin)


def test_a_moved_pin_carries_its_point_to_the_target():
    world = ragdoll("weighted")
    head = [0, 0, world.body_description("head")["shape"]["length"] / 2]
    pin = world.pin("head", np.array(head, dtype=float))
    target = world.pin_position(pin) + [0.01, 0, 0]
    world.move_pin(pin, target)
    world.step()
    np.testing.assert_allclose(world.pin_position(pin), target, atol=1e-9)
    np.testing.assert_allclose(world_point(world, "head", head), target, atol=2e-3)


def test_featherstone_refuses_a_pin():
    world = ragdoll("featherstone")
    with pytest.raises(limber.WorldError, match="pin"):
        world.pin("head", np.zeros(3))


@pytest.mark.parametrize("method", ["weighted", "featherstone", "lagrange"])
def test_a_teleport_puts_the_body_where_asked(method):
    world = limber.World(limber.chain(links=1, pinned=False, anchor=np.array([0, 0, 1.0])), method=method)
    body = world.body_names[0]
    position, orientation = np.array([1.0, 2.0, 3.0]), np.array([np.cos(0.3), 0, np.sin(0.3), 0])
    velocity, spin = np.array([0.5, 0, 0]), np.array([0, 0, 1.0])
    world.teleport(body, position, orientation, linear_velocity=velocity, angular_velocity=spin)
    now, turned = world.pose(body)
    np.testing.assert_allclose(now, position, atol=1e-9)
    np.testing.assert_allclose(rotation(turned)[:, 2], rotation(orientation)[:, 2], atol=1e-9)  # its axis
    np.testing.assert_allclose(world.motion(body)[0], velocity, atol=1e-9)
    with pytest.raises(limber.WorldError, match="teleport: orientation must be a finite unit quaternion"):
        world.teleport(body, position, np.zeros(4))
    np.testing.assert_allclose(world.pose(body)[0], position, atol=1e-9)  # nothing changed


def test_sleep_and_wake_round_trip():
    world = ragdoll()
    steps(world, 5)
    assert not world.sleeping("head")
    world.sleep("head")
    assert world.sleeping("head")
    np.testing.assert_array_equal(world.motion("head")[0], 0)
    world.wake("head")
    assert not world.sleeping("head")


def hinge(tmp_path):
    scene = {"limber_scene": 1, "name": "hinge", "settings": {"gravity": [0, 0, 0], "time_step": 0.004, "duration": 2},
             "bodies": [{"name": "arm", "shape": {"type": "capsule", "length": 0.5, "radius": 0.03}, "mass": 1,
                         "position": [0.25, 0, 1], "axis": [-1, 0, 0]}],
             "joints": [{"name": "hinge", "type": "revolute", "inboard": "world", "outboard": "arm", "inboard_anchor": [0, 0, 1],
                         "outboard_anchor": "head", "axis": [0, 1, 0]}]}
    path = tmp_path / "hinge.json"
    path.write_text(json.dumps(scene))
    return limber.load_scene(str(path))


@pytest.mark.parametrize("method", ["featherstone", "lagrange", "weighted"])
def test_a_drive_with_a_target_angle_brings_the_joint_to_it(tmp_path, method):
    world = limber.World(hinge(tmp_path), method=method)
    assert world.joint_drive("hinge") is None and not world.drives_released
    world.set_joint_drive("hinge", stiffness=5.0, damping=1.0, target=0.5)
    drive = world.joint_drive("hinge")
    assert drive["stiffness"] == 5 and drive["target"] == 0.5
    steps(world, 500)
    axis = rotation(world.pose("arm")[1])[:, 2]
    angle = np.arccos(np.clip(axis @ [-1, 0, 0], -1, 1))
    assert angle == pytest.approx(0.5, abs=0.05)
    world.set_joint_drive("hinge", **drive)  # the dict sets it again
    assert world.joint_drive("hinge")["target"] == 0.5
    world.set_joint_drive("hinge", None)
    assert world.joint_drive("hinge") is None


def test_a_bad_drive_raises_a_world_error_and_changes_nothing(tmp_path):
    world = limber.World(hinge(tmp_path), method="featherstone")
    with pytest.raises(limber.WorldError, match="set_joint_drive"):
        world.set_joint_drive("hinge", stiffness=-1.0)
    assert world.joint_drive("hinge") is None
    with pytest.raises(TypeError):
        world.set_joint_drive("hinge", stifness=1.0)


# --- Generators

def test_generators_give_the_bodies_asked_for_and_a_world_steps_them():
    assert len(limber.chain(links=7).body_names) == 7
    assert len(limber.tree(links=15, branching=2).body_names) == 15
    assert len(limber.grid(columns=3, rows=4).body_names) == 4 * 2 + 3 * 3
    humanoid = len(limber.load_scene(str(SCENES / "humanoid.json")).body_names)
    assert len(limber.humanoid_pile(3).body_names) == 3 * humanoid
    assert len(limber.copies(limber.chain(links=5), count=4, spacing=2.0).body_names) == 20
    chain = limber.chain(links=4, link_length=0.2, direction=np.array([0, 0, -1.0]), anchor=np.array([0, 0, 2.0]))
    world = limber.World(chain, method="featherstone")
    steps(world, 10)
    np.testing.assert_allclose(world.poses()[0][:, 2], 2 - 0.1 - 0.2 * np.arange(4), atol=1e-6)  # hanging at rest


@pytest.mark.parametrize("make, named", [
    (lambda: limber.chain(links=0), r"chain\.links: must be >= 1, got 0"),
    (lambda: limber.chain(links=-3), r"chain\.links: must be >= 1, got -3"),
    (lambda: limber.chain(links=3, link_mass=0.0), r"chain\.link_mass: must be > 0"),
    (lambda: limber.chain(links=3, direction=np.zeros(3)), r"chain\.direction"),
    (lambda: limber.chain(links=10**9), r"chain\.links: .*more than the 10000000"),
    (lambda: limber.tree(links=5, branching=0), r"tree\.branching: must be >= 1"),
    (lambda: limber.grid(columns=1, rows=3), r"grid\.columns: must be >= 2, got 1"),
    (lambda: limber.copies(limber.chain(links=5), count=2, spacing=0.01), r"copies\.spacing"),
])
def test_bad_generator_parameters_raise_value_errors_naming_them(make, named):
    with pytest.raises(ValueError, match=named):
        make()
