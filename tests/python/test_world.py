"""scoopsim.World: a coupled dig stepped from Python gives bit for bit the state `scoopsim run`
gives (oracle: the CLI's state_hash and time); particles() as read-only views; the
scoop's wrench in its three frames (closed form: a rotation keeps |F| and |T|); Ctrl-C during a
long step(n) raises KeyboardInterrupt between two steps."""

import os
import signal
import threading

import h5py
import numpy as np
import pytest

import scoopsim
from conftest import STOP_AFTER, cli_run, scene_path, sets_of


@pytest.fixture(scope="module")
def small_world(small_dig):
    scene = scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides=small_dig)
    return scoopsim.World(scene)


def step_for(world, seconds):
    """Steps as `scoopsim run --stop-after` does: until `seconds` past the dig's start."""
    t0 = world.time
    while world.time - t0 < seconds and not world.done():
        world.step(1)


def test_python_step_loop_equals_the_cli_bit_for_bit(tmp_path, small_dig):
    scene = scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides=small_dig)
    world = scoopsim.World(scene)
    step_for(world, STOP_AFTER)
    out = str(tmp_path / "cli.h5")
    cli_hash = cli_run(scene_path("tiny_dig.yaml"), out, sets_of(small_dig),
                       ["--stop-after", str(STOP_AFTER)])
    assert world.state_hash() == cli_hash
    with h5py.File(out, "r") as f:
        assert f.attrs["time"] == world.time
    # scoopsim.run is the same command.
    out2 = str(tmp_path / "py.h5")
    assert scoopsim.run(scene_path("tiny_dig.yaml"), out2, overrides=small_dig, quiet=True,
                        stop_after=STOP_AFTER) == out2
    with h5py.File(out2, "r") as f:
        assert int(f.attrs["state_hash"], 16) == cli_hash


def test_particles_are_read_only_views_of_the_world(small_world):
    small_world.step(5)
    p = small_world.particles()
    n = len(p["ids"])
    assert p["positions"].shape == (n, 3) and p["velocities"].shape == (n, 3)
    assert p["radii"].shape == (n,)
    assert not p["positions"].flags.writeable and not p["positions"].flags.owndata
    with pytest.raises(ValueError):
        p["positions"][0, 0] = 1.0
    np.testing.assert_array_equal(p["radii"], 8.0e-3)  # bed.radius: 8 mm, every sphere
    assert sorted(set(p["ids"].tolist())) == sorted(p["ids"].tolist())
    copy = small_world.particles(copy=True)
    assert copy["positions"].flags.owndata
    np.testing.assert_array_equal(copy["positions"], p["positions"])


def test_scoop_wrench_frames_agree_in_magnitude(small_world):
    small_world.step(50)
    w = {f: small_world.scoop_wrench(f) for f in ("world", "body", "l_scoop")}
    for f in ("body", "l_scoop"):
        assert np.linalg.norm(w[f][:3]) == pytest.approx(np.linalg.norm(w["world"][:3]),
                                                         rel=1e-12, abs=1e-12)
        assert np.linalg.norm(w[f][3:]) == pytest.approx(np.linalg.norm(w["world"][3:]),
                                                         rel=1e-12, abs=1e-12)
    with pytest.raises(ValueError):
        small_world.scoop_wrench("base")


def test_ctrl_c_stops_a_long_step_between_steps(small_world):
    t0 = small_world.time
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        small_world.step(10**9)
    timer.join()
    assert small_world.time > t0
    small_world.step(1)  # the world goes on after it
