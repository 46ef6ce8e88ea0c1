#!/usr/bin/python3
"""tools/fz_by_pass.py on a synthetic dig file (the /scoop/ rows of sim/loop/world.cpp, no DEM): two
passes, each a vertical descent (pitch 90 deg, 10 rows, contact from its 6th row), a quarter turn
to level (30 rows), a push along x (40 rows) and a quarter turn up (30 rows). The force in l_scoop
is constant per segment, Fz = 1, 2, 3, 4 N (x 10 in pass 2) and Fx = -Fz, so, closed forms: the
segment means are those values; "all" is the row-weighted mean over the rows from first contact
(5 descent rows + 30 + 40 + 30), (5*1 + 30*2 + 40*3 + 30*4) / 105 N in pass 1; first contact is
in the descent at pitch 90 deg (row 5, t = 10 ms), and its depths below the surface attribute:
the l_scoop origin 95 mm above it (-95 mm); blade down, l_scoop +x points down and +z along world
-x, so the CoM (1.315, 0, 45.328) mm in l_scoop is 1.315 mm lower (-93.685 mm).
Tolerance 1e-9 (the CSV keeps 5 significant digits: relative 1e-4 there). A file without /scoop/
rows: one line, exit non-zero."""

import csv
import os
import subprocess
import sys

import h5py
import numpy as np

from cli_check import test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "fz_by_pass.py")
SURFACE = 0.1


def quat_pitch(theta):
    """l_scoop orientation at pitch theta (sim/input/trajectory.h): R_y(theta) R0, R0 = rpy(pi, 0, 0),
    as w, x, y, z."""
    c, s = np.cos(theta / 2), np.sin(theta / 2)
    # (c, 0, s, 0) * (0, 1, 0, 0) = (0, c, 0, -s)
    return np.stack([np.zeros_like(theta), c, np.zeros_like(theta), -s], axis=1)


def write_case(path):
    theta = np.concatenate([np.full(10, np.pi / 2), np.linspace(np.pi / 2, 0, 31)[1:],
                            np.zeros(40), np.linspace(0, -np.pi / 2, 31)[1:]])
    n = len(theta)
    pos = np.zeros((n, 3))
    pos[:10, 2] = SURFACE + 0.1 - 0.001 * np.arange(10)  # the descent
    pos[10:, 2] = pos[9, 2]
    pos[40:80, 0] = 0.002 * np.arange(1, 41)  # the push
    pos[80:, 0] = pos[79, 0]
    seg_fz = np.concatenate([np.full(10, 1.0), np.full(30, 2.0), np.full(40, 3.0),
                             np.full(30, 4.0)])
    rows = {k: [] for k in ("time", "pass", "rho_path", "contacts", "force_scoop", "pose")}
    t = 0.0
    for p, scale in ((1, 1.0), (2, 10.0)):
        for k in range(n):
            rows["time"].append(t)
            rows["pass"].append(float(p))
            rows["rho_path"].append(0.001 * max(0, k - 5))
            rows["contacts"].append(0.0 if k < 5 else 3.0)
            fz = scale * seg_fz[k]
            rows["force_scoop"].append([-fz, 0.0, fz])
            rows["pose"].append(list(pos[k]) + list(quat_pitch(np.array([theta[k]]))[0]))
            t += 0.002
    with h5py.File(path, "w") as f:
        f.attrs["surface"] = SURFACE
        for k, v in rows.items():
            f["scoop/" + k] = np.array(v, dtype=float)


def main():
    with test_dir("fz_by_pass") as tmp:
        case = os.path.join(tmp, "snow_b3.h5")
        write_case(case)
        out = os.path.join(tmp, "out")
        subprocess.run([sys.executable, SCRIPT, case, "-o", out], check=True,
                       capture_output=True)
        with open(os.path.join(out, "fz_by_pass.csv")) as f:
            got = {(r["pass"], r["segment"]): r for r in csv.DictReader(f)}
        for p, scale in (("1", 1.0), ("2", 10.0)):
            want = {"descent": 1.0, "rotation 1": 2.0, "push": 3.0, "rotation 2": 4.0,
                    "all": (5 * 1 + 30 * 2 + 40 * 3 + 30 * 4) / 105.0}
            for seg, fz in want.items():
                r = got[(p, seg)]
                assert abs(float(r["mean_Fz_N"]) - scale * fz) <= 1e-4 * scale * fz, (p, seg, r)
                assert abs(float(r["mean_Fx_N"]) + scale * fz) <= 1e-4 * scale * fz, (p, seg, r)
            assert got[(p, "all")]["rows"] == "105", got[(p, "all")]
        with open(os.path.join(out, "first_contact.csv")) as f:
            first = list(csv.DictReader(f))
        assert [r["pass"] for r in first] == ["1", "2"], first
        for r, t0 in zip(first, (0.010, 0.010 + 0.002 * 110)):
            assert abs(float(r["time_s"]) - t0) < 1e-9, r
            assert abs(float(r["pitch_deg"]) - 90) < 1e-3, r
            assert r["segment"] == "descent", r
            assert abs(float(r["origin_depth_mm"]) - (-95.0)) < 1e-3, r  # 0.1 m - 5 mm above
            assert abs(float(r["com_depth_mm"]) - (-95.0 + 1.315)) < 1e-3, r
        assert os.path.getsize(os.path.join(out, "fz_by_pass.png")) > 0
        # Not a dig's output: one line naming the file, non-zero exit.
        bad = os.path.join(tmp, "bad.h5")
        with h5py.File(bad, "w") as f:
            f["x"] = np.zeros(3)
        r = subprocess.run([sys.executable, SCRIPT, bad, "-o", out], capture_output=True,
                           text=True)
        assert r.returncode != 0 and bad in r.stderr and len(r.stderr.strip().splitlines()) == 1, \
            r.stderr
    print("fz_by_pass_test: passed")


if __name__ == "__main__":
    main()
