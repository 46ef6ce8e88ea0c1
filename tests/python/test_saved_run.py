"""scoopsim.open_run: a run's datasets by name with their attributes, the same values h5py reads
(oracle: h5py on the same file), on a short run of the small dig; scoopsim.run stopped by Ctrl-C
leaves its output closed and readable."""

import os
import signal
import threading

import h5py
import numpy as np
import pytest

import scoopsim
from conftest import scene_path


def test_datasets_by_name_with_units_and_frames(tmp_path, small_dig):
    out = scoopsim.run(scene_path("tiny_dig.yaml"), str(tmp_path / "run.h5"), overrides=small_dig,
                       quiet=True, stop_after=0.02)
    run = scoopsim.open_run(out)
    assert "scoop/force_world" in run and "/scoop/time" in run
    with h5py.File(out, "r") as f:
        np.testing.assert_array_equal(run["scoop/force_world"], f["scoop/force_world"][()])
        h = f.attrs["state_hash"]
        assert run.attrs["state_hash"] == (h.decode() if isinstance(h, bytes) else h)
        for k, v in f["scoop/pose"].attrs.items():
            v = v.decode() if isinstance(v, bytes) else v
            assert run["scoop/pose"].attrs[k] == v
    assert run["scoop/pose"].attrs["quaternion_order"]
    assert run["scoop/force_world"].shape[1] == 3
    # Units and frames from the layout (docs/outputs.md): every /scoop/ and /series/ dataset of
    # the run has its units, each wrench its frame.
    for name in run.keys():
        if name.startswith(("scoop/", "series/")):
            assert run[name].attrs.get("units"), name
    for kind, unit in (("force", "N"), ("torque", "N m")):
        for frame, named in (("body", "body"), ("scoop", "l_scoop"), ("world", "world")):
            a = run[f"scoop/{kind}_{frame}"].attrs
            assert (a["units"], a["frame"]) == (unit, named)
    assert run["scoop/rho"].attrs["units"] == "m"


def test_ctrl_c_stops_a_run_with_its_output_closed(tmp_path, small_dig):
    # `scoopsim run`'s own stop (exit status 130, the output closed) raised as KeyboardInterrupt;
    # Python's SIGINT handler is back afterwards.
    out = str(tmp_path / "stopped.h5")
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        scoopsim.run(scene_path("tiny_dig.yaml"), out, overrides=small_dig, quiet=True)
    timer.join()
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    run = scoopsim.open_run(out)  # a plain, readable file with the rows flushed at the stop
    assert 0 < len(run["scoop/time"])
    assert run["scoop/time"][-1] < 2.0  # stopped well before the dig's end (t = 2.97 s)


def test_series_read_at_their_groups_time_length(tmp_path):
    # A file killed inside a flush holds more rows in a group's other series than in its time
    # (scoopsim writes time last, docs/files.md): open_run reads every series at time's length;
    # a per-pass dataset (collected_mass) and a group without time keep all their rows.
    path = str(tmp_path / "killed.h5")
    with h5py.File(path, "w") as f:
        f["scoop/time"] = np.arange(5) * 1e-3
        f["scoop/force_world"] = np.ones((8, 3))
        f["scoop/collected_mass"] = np.ones(1)
        f["bonds/broken/time"] = np.arange(2.0)
        f["bonds/broken/pair"] = np.ones((3, 2))
        f["particles/radius"] = np.ones(9)
    run = scoopsim.open_run(path)
    assert run["scoop/force_world"].shape == (5, 3)
    assert run["scoop/collected_mass"].shape == (1,)
    assert run["bonds/broken/pair"].shape == (2, 2)
    assert run["particles/radius"].shape == (9,)
