"""Shared by the module's tests (ctest runs each file with PYTHONPATH=build/python, SCOOPSIM_BIN
the CLI and SCOOPSIM_SOURCE_DIR the source tree; tests/CMakeLists.txt)."""

import os
import subprocess

import h5py
import pytest

SOURCE = os.environ.get("SCOOPSIM_SOURCE_DIR",
                        os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
BIN = os.environ.get("SCOOPSIM_BIN", os.path.join(SOURCE, "build", "tools", "scoopsim"))


def scene_path(name):
    return os.path.join(SOURCE, "scenes", name)


STOP_AFTER = 0.2  # [s] of the dig the tests step (--stop-after): the scoop touches at 0.13 s


def make_bed(scene, out):
    """`scoopsim bed SCENE -o OUT` (a second or two): the worlds of a test load it (bed.file)
    instead of each pouring its own."""
    subprocess.run([BIN, "bed", scene, "-o", out, "--quiet", "--threads", "2"], check=True)
    return out


@pytest.fixture(scope="session")
def small_dig(tmp_path_factory):
    """Overrides of scenes/tiny_dig.yaml: its bed, made once, and two threads."""
    bed = make_bed(scene_path("tiny_dig.yaml"), str(tmp_path_factory.mktemp("beds") / "tiny.h5"))
    return {"bed.file": bed, "threads": 2}


@pytest.fixture(scope="session")
def small_arm(tmp_path_factory):
    """Overrides of scenes/arm/nominal_snow.yaml: its bed, made once, two threads, no snapshots."""
    bed = make_bed(scene_path("arm/nominal_snow.yaml"),
                   str(tmp_path_factory.mktemp("beds") / "arm.h5"))
    return {"bed.file": bed, "threads": 2, "output.snapshot_every": 0}


def sets_of(overrides):
    return [f"{k}={v}" for k, v in overrides.items()]


def cli_run(scene, out, sets=(), extra=()):
    """`scoopsim run SCENE -o OUT --set ...`; returns the output's root attribute state_hash."""
    cmd = [BIN, "run", scene, "-o", out, "--quiet"] + list(extra)
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True)
    with h5py.File(out, "r") as f:
        return int(f.attrs["state_hash"], 16)  # stored as hex text
