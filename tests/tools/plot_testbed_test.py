#!/usr/bin/python3
"""tools/plot_testbed.py on synthetic testbed runs with known forces: three beds pushed 40 mm
along x at 0.01 m/s (rows every 5 ms), body-frame force F = (0, -(a_b + 100 d), -2) N with
a_b = 1, 2, 3 N per bed and d the distance [m]. Closed forms (--smooth 1, so no smoothing): over
the last 90% of the push (d in (4, 40] mm) FY's mean over beds is -(2 + 100 x 22 mm) = -4.2 N
(the grid's mean distance, 22.0 mm to 0.1 mm), its sd over beds 1 N, its slope -100 N/m (sd 0)
exactly for a straight line; FZ is -2 N everywhere. A missing dataset or file: one line, exit 2."""

import csv
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np
from cli_check import expect_refused

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "plot_testbed.py")


def make_run(path, offset, drop=None):
    t = np.arange(0, 4.0 + 1e-9, 5e-3)
    d = 0.01 * t
    pose = np.zeros((t.size, 7))
    pose[:, 0] = 0.09 + d
    pose[:, 2] = 0.05
    pose[:, 4] = 1.0  # rpy(pi, 0, 0): q = (0, 1, 0, 0)
    force = np.stack([np.zeros_like(d), -(offset + 100 * d), np.full_like(d, -2.0)], axis=1)
    with h5py.File(path, "w") as f:
        f["scoop/time"] = t
        f["scoop/pose"] = pose
        if drop != "force_body":
            f["scoop/force_body"] = force


def main():
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for b in (1, 2, 3):
            runs.append(os.path.join(tmp, "bed%d.h5" % b))
            make_run(runs[-1], float(b))
        png, summary = os.path.join(tmp, "testbed.png"), os.path.join(tmp, "summary.csv")
        r = subprocess.run([sys.executable, SCRIPT] + runs + ["-o", png, "--smooth", "1",
                                                              "--csv", summary],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        with open(png, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"
        rows = {row["component"]: row for row in csv.DictReader(open(summary))}
        fy, fz = rows["FY"], rows["FZ"]
        assert int(fy["beds"]) == 3
        assert abs(float(fy["rest_mean_N"]) + 4.2) < 0.01, fy
        assert abs(float(fy["rest_sd_N"]) - 1.0) < 1e-9, fy
        assert abs(float(fy["slope_mean_N_per_m"]) + 100.0) < 1e-6, fy
        assert abs(float(fy["slope_sd_N_per_m"])) < 1e-6, fy
        assert abs(float(fz["rest_mean_N"]) + 2.0) < 1e-12, fz
        assert "| FY (along the push) |" in r.stdout, r.stdout

        broken = os.path.join(tmp, "broken.h5")
        make_run(broken, 1.0, drop="force_body")
        run = lambda args: subprocess.run([sys.executable, SCRIPT] + args, capture_output=True,
                                          text=True)
        expect_refused(run, (([broken, "-o", os.path.join(tmp, "x.png")], "/scoop/force_body"),
                             ([os.path.join(tmp, "none.h5"), "-o", os.path.join(tmp, "x.png")],
                              "none.h5"),
                             ([runs[0], "-o", os.path.join(tmp, "x.png"), "--smooth", "0"],
                              "--smooth")))
    print("plot_testbed_test: summary matches the closed forms, 3 bad inputs refused with exit 2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
