"""What a hostile caller gives the module is refused with a typed error, never a crash: objects
made by __new__ without __init__, descriptions that contain themselves or nest without end, body
descriptions a method cannot step, options CLI11 would take for its own (--help), values that
look like flags, and names that are not UTF-8 text."""
import os
import pathlib
import re

import numpy as np
import pytest

import limber
from limber import _limber

SOURCE = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
RAGDOLL = str(SOURCE / "tools" / "scenes" / "ragdoll.json")


def ragdoll(method="weighted"):
    return limber.World(limber.load_scene(RAGDOLL), method)


def crate(**changes):
    description = {"name": "crate", "shape": {"type": "capsule", "length": 0.3, "radius": 0.05}, "mass": 2.0,
                   "position": [3.0, 0.0, 2.0], "axis": [0, 0, 1]}
    description.update(changes)
    return description


# --- Objects made by __new__ without __init__

UNINITIALISED_CALLS = {
    "step": lambda w: w.step(),
    "run": lambda w: w.run(1),
    "time": lambda w: w.time,
    "body_names": lambda w: w.body_names,
    "method": lambda w: w.method,
    "poses": lambda w: w.poses(),
    "observe": lambda w: w.observe(),
    "last_report": lambda w: w.last_report(),
    "wake_all": lambda w: w.wake_all(),
    "add_body": lambda w: w.add_body(crate()),
    "balls": lambda w: w.balls(),
    "segments": lambda w: w.segments(),
}


@pytest.mark.parametrize("cls", [limber.World, _limber.World], ids=["limber.World", "_limber.World"])
@pytest.mark.parametrize("call", sorted(UNINITIALISED_CALLS))
def test_a_world_never_initialised_raises_type_error(cls, call):
    world = cls.__new__(cls)
    with pytest.raises(TypeError, match="never initialised"):
        UNINITIALISED_CALLS[call](world)


def test_handles_never_initialised_raise_type_error():
    world = ragdoll()
    world.wake_all()
    ball = world.add_ball({"radius": 0.05, "mass": 1, "restitution": 0.5, "position": [1, 0, 1], "speed": 0, "direction": [1, 0, 0]})
    pin = world.pin(world.body_names[0], np.zeros(3))
    balls = world.balls()
    for cls, real in ((limber.Ball, ball), (limber.Pin, pin)):
        handle = cls.__new__(cls)
        for use in (repr, hash, lambda h: h == real, lambda h: real == h):
            with pytest.raises(TypeError, match="never initialised"):
                use(handle)
    with pytest.raises(TypeError, match="never initialised"):
        world.remove_ball(limber.Ball.__new__(limber.Ball))
    with pytest.raises(TypeError, match="never initialised"):
        world.pin_position(limber.Pin.__new__(limber.Pin))
    assert world.balls() == balls and ball in balls  # nothing removed


def test_a_second_init_is_refused_and_changes_nothing():
    world = ragdoll()
    with pytest.raises(limber.WorldError, match="made already"):
        world.__init__(limber.load_scene(RAGDOLL), "featherstone", iterations=3)
    assert world.method == "weighted" and world.options == {}


# --- Descriptions that contain themselves or nest too deep

def nested(levels, inner=None):
    value = inner if inner is not None else 0
    for _ in range(levels):
        value = {"x": value}
    return value


def test_a_description_that_contains_itself_is_a_model_error_naming_the_path():
    world = ragdoll()
    looped = crate()
    looped["x"] = looped
    with pytest.raises(limber.ModelError, match=r"add_body: bodies\[0\]\.x: contains itself"):
        world.add_body(looped)
    listed = []
    listed.append(listed)
    with pytest.raises(limber.ModelError, match=r"add_body: bodies\[0\]\.position\[0\]: contains itself"):
        world.add_body(crate(position=listed))
    with pytest.raises(limber.ModelError, match=r"add_collider: colliders\[0\]\.half_extents\[0\]: contains itself"):
        world.add_collider({"name": "box", "type": "box", "half_extents": listed, "position": [0, 0, 0]})
    assert "crate" not in world.body_names


def test_a_description_nested_deeper_than_64_levels_is_a_model_error():
    world = ragdoll()
    with pytest.raises(limber.ModelError, match="add_body: bodies\\[0\\](\\.x){64}: nests dicts and lists deeper than 64 levels"):
        world.add_body(crate(x=nested(64)))  # the description, then 64 more
    with pytest.raises(limber.ModelError, match="deeper than 64 levels"):
        world.add_body(crate(x=nested(200_000)))  # past what a recursive conversion's stack holds
    deep_list = [0]
    for _ in range(100_000):
        deep_list = [deep_list]
    with pytest.raises(limber.ModelError, match="deeper than 64 levels"):
        world.add_joint({"name": "j", "type": "fixed", "inboard": "world", "outboard": world.body_names[0], "anchor": deep_list})
    # within the cap, the description reaches the scene reader, which names the unknown field
    with pytest.raises(limber.ModelError, match='add_body: bodies\\[0\\]: unknown field "x"'):
        world.add_body(crate(x=nested(8)))


def test_numbers_and_text_json_cannot_hold_are_model_errors():
    world = ragdoll()
    with pytest.raises(limber.ModelError, match=r"bodies\[0\]\.mass: must be a finite number"):
        world.add_body(crate(mass=10**400))
    with pytest.raises(limber.ModelError, match=r"bodies\[0\]\.name: must be text UTF-8 can hold"):
        world.add_body(crate(name="crate\udcff"))
    name = world.add_body(crate(mass=10**30 + 1))  # an int past 64 bits is its nearest double
    assert world.body_description(name)["mass"] == 1e30


# --- Body descriptions every method steps or refuses by name

# Sizes, masses and speeds whose derived quantities (1/m, extent², m·extent², m·v², I·ω²) are not
# finite numbers: every method's compile failed (a bare ValueError) or its step went NaN.
OVERFLOWING_BODIES = {
    "capsule 1e300 m long": ({"shape": {"type": "capsule", "length": 1e300, "radius": 0.05}}, "shape"),
    "capsule 1e160 m long": ({"shape": {"type": "capsule", "length": 1e160, "radius": 0.05}}, "shape"),
    "capsule of radius 1e300 m": ({"shape": {"type": "capsule", "length": 0.3, "radius": 1e300}}, "shape"),
    "cylinder of radius 1e160 m": ({"shape": {"type": "cylinder", "length": 0.3, "radius": 1e160}}, "shape"),
    "box 1e200 m wide": ({"shape": {"type": "box", "half_extents": [1e200, 0.1, 0.1]}}, "shape"),
    "ellipsoid of semi-axis 1e160 m": ({"shape": {"type": "ellipsoid", "half_extents": [0.1, 1e160, 0.1]}}, "shape"),
    "mass 1e-320 kg": ({"mass": 1e-320}, "mass"),
    "speed 1e300 m/s": ({"linear_velocity": [1e300, 0, 0]}, "linear_velocity"),
    "spin 1e300 rad/s": ({"angular_velocity": [0, 1e300, 0]}, "angular_velocity"),
    "a lump 1e200 m out": ({"mass": None, "point_masses": [{"position": [0, 0, 1e200], "mass": 1}]}, "point_masses[0]"),
}


def body(changes):
    return {key: value for key, value in crate(**changes).items() if value is not None}


@pytest.mark.parametrize("method", limber.methods)
@pytest.mark.parametrize("case", sorted(OVERFLOWING_BODIES))
def test_a_body_whose_derived_quantities_overflow_is_a_model_error_naming_the_field(method, case):
    world = ragdoll(method) if method != "unweighted" else limber.World(limber.chain(links=3), method)
    before = world.body_names
    changes, field = OVERFLOWING_BODIES[case]
    with pytest.raises(limber.ModelError, match=re.escape(f"add_body: bodies[0].{field}: ")):
        world.add_body(body(changes))
    assert world.body_names == before  # checked before anything changed


# What some methods cannot take: refused by name (the rigid bodies need a rotational inertia and a
# mass they can spread over the shape; the springs no spheres), or stepped without NaN.
AWKWARD_BODIES = {
    "capsule of radius 1e-200 m": {"shape": {"type": "capsule", "length": 0.3, "radius": 1e-200}},  # its volume underflows
    "capsule of radius 1e120 m": {"shape": {"type": "capsule", "length": 0.3, "radius": 1e120}},  # its cylinder's share: 0 kg
    "cylinder 1e-300 m long": {"shape": {"type": "cylinder", "length": 1e-300, "radius": 0}},
    "one lump at the centre": {"mass": None, "point_masses": [{"position": [0, 0, 0], "mass": 1}]},
    "a lump of 1e-320 kg": {"mass": None, "point_masses": [{"position": [0, 0, 0.1], "mass": 1e-320},
                                                          {"position": [0, 0, -0.1], "mass": 1}]},
}


@pytest.mark.parametrize("method", limber.methods)
@pytest.mark.parametrize("case", sorted(AWKWARD_BODIES))
def test_an_awkward_body_is_refused_by_name_or_steps_without_nan(method, case):
    world = ragdoll(method) if method != "unweighted" else limber.World(limber.chain(links=3), method)
    before = world.body_names
    try:
        world.add_body(body(AWKWARD_BODIES[case]))
    except limber.ModelError as error:
        assert re.match(r"add_body: bodies\[\d+\]", str(error)), str(error)  # the call and the body
        assert world.body_names == before  # checked before anything changed
        return
    for _ in range(20):
        status = world.step()
        if status != "ok":
            break  # a divergence the step reports is a verdict, not a silent NaN
        positions, orientations = world.poses()
        assert np.isfinite(positions).all() and np.isfinite(orientations).all()


def test_bad_vectors_are_world_errors():
    world = ragdoll()
    with pytest.raises(limber.WorldError, match="force: expected 3 numbers"):
        world.apply_force(world.body_names[0], np.zeros(2), np.zeros(3))
    with pytest.raises(limber.WorldError, match="orientation: expected 4 numbers"):
        world.teleport(world.body_names[0], np.zeros(3), np.zeros(3))
    with pytest.raises(limber.WorldError, match="run: steps must be"):
        world.run(-1)
    with pytest.raises(limber.ModelError, match="chain.anchor: expected 3 numbers"):
        limber.chain(links=2, anchor=np.zeros(2))


# --- Options

def test_help_and_version_are_refused_by_name_in_one_line():
    scene = limber.load_scene(RAGDOLL)
    for option in ("help", "h", "help_all", "version"):
        with pytest.raises(limber.OptionError) as raised:
            limber.World(scene, "weighted", **{option: True})
        message = str(raised.value)
        assert "\n" not in message and "main function" not in message
        assert "--" + option.replace("_", "-") in message or "-" + option in message


def test_a_value_that_looks_like_a_flag_is_refused_naming_the_flag_and_type():
    scene = limber.load_scene(RAGDOLL)
    with pytest.raises(limber.OptionError, match="--iterations") as raised:
        limber.World(scene, "weighted", iterations="--dt")
    assert "INT" in str(raised.value) or "integer" in str(raised.value)
    assert "\n" not in str(raised.value)
    with pytest.raises(limber.OptionError, match="--dt"):
        limber.World(scene, "weighted", dt="--iterations=1")


def test_option_names_are_keywords_not_text_for_the_command_line():
    scene = limber.load_scene(RAGDOLL)
    for name in ("iterations=5", "iterations 5", "-iterations", ""):
        with pytest.raises(limber.OptionError, match="not an option"):
            limber.World(scene, "weighted", **{name: True})


def test_an_option_value_that_nests_or_contains_itself_is_an_option_error():
    scene = limber.load_scene(RAGDOLL)
    looped = []
    looped.append(looped)
    for value in (looped, [[1, 0, 0]], {"x": 1}):
        with pytest.raises(limber.OptionError, match="--ball-direction"):
            limber.World(scene, "weighted", ball_direction=value)


def test_a_scene_the_method_cannot_take_with_its_options_is_an_option_error():
    with pytest.raises(limber.OptionError, match="World: options: joints beyond spherical joints"):
        limber.World(limber.load_scene(RAGDOLL), "unweighted")  # hinges need the weighted rule


# --- Names that are not UTF-8

LATIN1_MJCF = (b'<mujoco model="m">\n<worldbody>\n<body name="caf\xe9" pos="0 0 1">\n<freejoint/>\n'
               b'<geom type="capsule" size="0.05 0.1"/>\n</body>\n</worldbody>\n</mujoco>\n')


def test_a_model_file_with_a_latin1_name_is_a_model_error_not_a_unicode_error(tmp_path):
    path = tmp_path / "latin1.xml"
    path.write_bytes(LATIN1_MJCF)
    with pytest.raises(limber.ModelError) as raised:
        limber.load_scene(str(path))
    assert "latin1.xml" in str(raised.value) and "UTF-8" in str(raised.value)


def test_a_json_scene_with_a_latin1_name_is_a_model_error_not_a_unicode_error(tmp_path):
    path = tmp_path / "latin1.json"
    text = (SOURCE / "tools" / "scenes" / "chain.json").read_bytes()
    path.write_bytes(text.replace(b'"name": "', b'"name": "caf\xe9', 1))
    with pytest.raises(limber.ModelError) as raised:
        limber.load_scene(str(path))
    assert "latin1.json" in str(raised.value)
