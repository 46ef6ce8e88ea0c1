"""World(scene, driver="python"): a scoop driver written in Python. Replaying the scene's own
kinematic driver's motion step by step gives its dig bit for bit (oracle: that driver's World);
above the bed the scoop feels nothing (closed form: no contact, zero wrench) and end_pass() ends the
dig's one pass."""

import numpy as np
import pytest

import scoopsim
from conftest import scene_path


def test_a_python_driver_replaying_the_path_gives_the_same_dig_bit_for_bit(small_dig):
    # Oracle: the scene's own (kinematic) driver. Its scoop motion at each step's end, set from
    # Python step by step before each step, must give the same particles bit for bit.
    scene = scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides=small_dig)
    a = scoopsim.World(scene)
    b = scoopsim.World(scene, driver="python", scoop_motion=a.scoop_motion())
    t0, peak = a.time, 0.0
    while a.time - t0 < 0.16:  # the scoop in the bed from 0.13 s on
        a.step(1)
        b.set_scoop_pose(*a.scoop_motion())
        b.step(1)
        np.testing.assert_array_equal(b.scoop_wrench("l_scoop"), a.scoop_wrench("l_scoop"))
        peak = max(peak, np.linalg.norm(a.scoop_wrench()[:3]))
    assert b.time == a.time
    assert peak > 1.0  # [N]: it dug
    assert b.state_hash() == a.state_hash()
    with pytest.raises(RuntimeError):
        a.set_scoop_pose([0, 0, 0], [1, 0, 0, 0])


def test_a_python_driver_above_the_bed_feels_nothing_and_ends_its_passes(small_dig):
    scene = scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides=small_dig)
    world = scoopsim.World(scene, driver="python")
    world.set_scoop_pose([0.185, 0.085, 0.5], [1, 0, 0, 0])  # 0.3 m above the box's top
    assert world.step(20) == 20
    np.testing.assert_array_equal(world.scoop_wrench(), np.zeros(6))
    assert not world.done()
    world.end_pass()  # tiny_dig has one pass
    world.step(2)
    assert world.done()
