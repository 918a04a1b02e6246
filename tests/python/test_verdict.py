"""One verdict everywhere: World.run judges a run over every step with the command line's own
words (kernel/study/run_metrics.hpp's verdict), so a run the summary calls inaccurate is not 'ok'
in Python or in a sweep."""
import os
import pathlib
import subprocess

import limber

SOURCE = pathlib.Path(os.environ.get("LIMBER_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
RAGDOLL = str(SOURCE / "tools" / "scenes" / "ragdoll.json")
PROGRAM = os.environ.get("LIMBER_PROGRAM", str(pathlib.Path(limber.__file__).parents[2] / "tools" / "limber"))


def summary_status(*arguments):
    """The status line of `limber run ARGUMENTS`, without its label."""
    done = subprocess.run([PROGRAM, "run", *arguments], capture_output=True, text=True, timeout=600, check=True)
    line = next(line for line in done.stdout.splitlines() if line.startswith("status "))
    return line[len("status"):].strip()


def test_a_coarse_ragdoll_is_inaccurate_in_python_as_on_the_command_line():
    # At 1/30 s reduced coordinates end the fall at rest with the joints closed, but a shin went
    # into the ground on the way (4.5 cm; its thinnest limb is 1.5 cm thick) and a limit was passed by a radian.
    scene = limber.load_scene(RAGDOLL)
    world = limber.World(scene, "featherstone", dt=0.0333)
    run = world.run(round(5 / 0.0333))
    assert run["status"] == "inaccurate"
    assert "into the ground" in run["verdict"] and "a limit passed by" in run["verdict"]
    assert run["deepest_penetration"] > 0.03 and run["max_limit_violation"] > 0.5
    assert run["verdict"] == summary_status(RAGDOLL, "--method", "featherstone", "--dt", "0.0333")


def test_a_converged_run_is_ok_in_both():
    scene = limber.load_scene(str(SOURCE / "tools" / "scenes" / "chain.json"))
    run = limber.World(scene, "weighted").run(240)
    assert run["status"] == "ok" and run["verdict"] == "ok"
    assert summary_status(str(SOURCE / "tools" / "scenes" / "chain.json"), "--steps", "240") == "ok"


def test_without_observing_the_status_is_the_last_steps():
    run = limber.World(limber.load_scene(RAGDOLL), "featherstone", dt=0.0333).run(10, observe=False)
    assert run["status"] == "ok" and "verdict" not in run


SERVO = """<mujoco model="servo">
  <option timestep="0.01"/>
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.02" mass="1"/>
    </body>
  </worldbody>
  <actuator><position name="servo" joint="hinge" kp="300"/></actuator>
</mujoco>"""


def test_a_servo_that_pumps_energy_in_is_not_ok(tmp_path):
    # A stiff position servo held at its start, stepped past what the particles' explicit servo
    # takes at 10 ms: no step diverges, but the arm gains several times the scene's energy scale.
    (tmp_path / "servo.xml").write_text(SERVO)
    world = limber.World(limber.load_scene(str(tmp_path / "servo.xml")), "weighted")
    run = world.run(300)
    assert run["status"] == "inaccurate" and "energy gained" in run["verdict"]


def test_observe_names_the_deepest_penetration_now():
    # A log of radius 0.1 m lying with its axis 0.06 m above the ground is 0.04 m into it; the
    # ragdoll (asleep, standing) touches nothing deeper.
    world = limber.World(limber.load_scene(RAGDOLL), "featherstone")
    assert world.observe()["deepest_penetration"] < 0.04
    world.add_body({"name": "log", "shape": {"type": "capsule", "length": 0.5, "radius": 0.1}, "mass": 1,
                    "position": [5, 0, 0.06], "axis": [1, 0, 0]})
    now = world.observe()
    assert abs(now["deepest_penetration"] - 0.04) < 1e-9
    assert now["penetration"] == "log into the ground"


def test_observe_names_the_widest_joint():
    world = limber.World(limber.load_scene(RAGDOLL), "lagrange")
    assert world.observe()["max_joint_gap"] < 1e-9
    position, orientation = world.poses()
    names = world.body_names
    shin = names.index("tibia_left")
    position[shin, 0] += 0.1  # pull the left shin 0.1 m forward, off its knee
    world.teleport("tibia_left", position[shin], orientation[shin])
    now = world.observe()
    assert now["max_joint_gap"] > 0.1
    assert now["widest_joint"] == "upper_leg_left-tibia_left"  # the knee: the shin's one joint
