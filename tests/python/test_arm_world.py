"""World for an arm scene (scenes/arm/nominal_snow.yaml, a smaller bed): stepped from Python with
no joint reference set, the coupled arm dig equals `scoopsim run --stop-after` bit for bit (oracle:
the CLI's state_hash: the ArmDriver's hook changes nothing unused); with a reference set from
Python the PID takes the joints to it (the reference reported back exactly, the error shrinking);
joint_state() and fault_bits() shapes and types."""

import numpy as np
import pytest

import scoopsim
from conftest import cli_run, scene_path, sets_of

STOP_AFTER = 0.03


def test_arm_dig_stepped_from_python_equals_the_cli(tmp_path, small_arm):
    scene = scoopsim.load_scene(scene_path("arm/nominal_snow.yaml"), overrides=small_arm)
    world = scoopsim.World(scene)
    t0 = world.time
    while world.time - t0 < STOP_AFTER:
        world.step(1)
    cli = cli_run(scene_path("arm/nominal_snow.yaml"), str(tmp_path / "arm.h5"),
                  sets_of(small_arm),
                  ["--stop-after", str(STOP_AFTER)])
    assert world.state_hash() == cli


def test_a_joint_reference_from_python_drives_the_arm(small_arm):
    scene = scoopsim.load_scene(scene_path("arm/nominal_snow.yaml"), overrides=small_arm)
    world = scoopsim.World(scene)
    world.step(1)
    s = world.joint_state()
    assert {k: v.shape for k, v in s.items()} == {k: (6,) for k in ("q", "qdot", "tau",
                                                                   "reference")}
    target = s["q"].copy()
    target[0] += 0.01  # 10 mrad on the first joint (azimuth)
    world.set_joint_reference(target)
    world.step(1)
    np.testing.assert_array_equal(world.joint_state()["reference"], target)
    error0 = abs(world.joint_state()["q"][0] - target[0])
    world.step(2000)
    error = abs(world.joint_state()["q"][0] - target[0])
    assert error < 0.5 * error0
    active, latched = world.fault_bits()
    assert isinstance(active, int) and isinstance(latched, int)
    assert isinstance(scoopsim.fault_names(latched), str)
    with pytest.raises(ValueError):
        world.set_joint_reference([0.0, 0.0])
    world.set_joint_reference(None)  # back to the path


def test_arm_calls_on_a_scene_without_an_arm_raise(small_dig):
    scene = scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides=small_dig)
    world = scoopsim.World(scene)
    with pytest.raises(RuntimeError):
        world.joint_state()
