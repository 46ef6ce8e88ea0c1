"""scoopsim.open_run: a run's datasets by name with their attributes, the same values h5py reads
(oracle: h5py on the same file), on a short run of the small dig."""

import h5py
import numpy as np

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
