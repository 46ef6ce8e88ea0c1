"""scoopsim.Table.query against the table file itself (oracle: its stored samples, read with h5py):
at grid nodes the stored values exactly, halfway between two rho nodes their mean (linear in rho,
closed form), vectorised over broadcast arrays in metres; out of the domain an InputError. The
table is built by `scoopsim table build` from synthetic case files (tests/tools/table_csv_test.py)."""

import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

import scoopsim
from conftest import BIN, SOURCE

sys.path.insert(0, os.path.join(SOURCE, "tests", "tools"))
from table_csv_test import write_case  # noqa: E402


@pytest.fixture(scope="module")
def table_path(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("table")
    os.makedirs(tmp / "cases")
    for k, (material, bite) in enumerate([("snow", 0.015), ("snow", 0.003), ("ice", 0.009)]):
        write_case(str(tmp / "cases" / f"{material}_{bite}.h5"), material, bite, seed=k)
    path = str(tmp / "table.h5")
    subprocess.run([BIN, "table", "build", str(tmp), "-o", path], check=True,
                   capture_output=True)
    return path


def test_grid_nodes_are_the_stored_samples_and_midpoints_their_mean(table_path):
    table = scoopsim.Table(table_path)
    with h5py.File(table_path, "r") as f:
        force = f["scoop/force_scoop"][()]
        torque = f["scoop/torque_scoop"][()]
        depths, passes, rho = f["bite_depth"][()], f["pass"][()], f["rho"][()]
        names = [n.decode() if isinstance(n, bytes) else n for n in f["materials/name"][()]]
    assert table.materials == names
    np.testing.assert_array_equal(table.bite_depths, depths)
    m = names.index("snow")
    b = int(np.argmin(depths))
    p = 0
    stored = np.concatenate([force[m, b, p], torque[m, b, p]], axis=1)  # (R, 6)
    r = np.flatnonzero(np.isfinite(stored).all(axis=1))[:10]
    got = table.query("snow", depths[b], passes[p], rho[r])  # broadcast: scalars against (10,)
    assert got.shape == (len(r), 6)
    np.testing.assert_array_equal(got, stored[r])
    mid = table.query("snow", depths[b], passes[p], 0.5 * (rho[r[:-1]] + rho[r[1:]]))
    np.testing.assert_allclose(mid, 0.5 * (stored[r[:-1]] + stored[r[1:]]), rtol=1e-9, atol=1e-12)
    # A (2, 3) grid of queries keeps its shape.
    grid = table.query("snow", depths[b], passes[p], rho[r[:6]].reshape(2, 3))
    assert grid.shape == (2, 3, 6)


def test_out_of_domain_is_input_error_unless_clamped(table_path):
    table = scoopsim.Table(table_path)
    with pytest.raises(scoopsim.InputError):
        table.query("snow", 1.0, 1, 0.0)  # a bite depth of 1 m
    assert np.isfinite(table.query("snow", 1.0, 1, 0.0, clamp=True)).all()
    with pytest.raises(scoopsim.InputError):
        scoopsim.Table(os.path.join(SOURCE, "scenes", "tiny_dig.yaml"))
