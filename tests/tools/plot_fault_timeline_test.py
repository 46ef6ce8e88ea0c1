#!/usr/bin/python3
"""tools/plot_fault_timeline.py on synthetic arm run files: a run whose j_b demand crosses its
limit and raises JOINT_TORQUE_LIMIT one hold time later, and one without a fault, plotted together
(the fault's joint and its time as written in /arm/fault_events: the run's one clock, README "One
clock", not shifted by the root attribute start_time);
--joint picks another joint; a missing dataset or file, an unknown joint or a wrong number of labels
gives one line and exit status 2."""

import os
import subprocess
import sys

import h5py
import numpy as np
from cli_check import expect_refused, test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "plot_fault_timeline.py")


EVENT = np.dtype([("time", "<f8"), ("flag", "<u8"), ("flag_name", "S19"), ("joint", "<i4"),
                  ("joint_name", "S4"), ("value", "<f8"), ("limit", "<f8")])


def make_run(path, fault=True, drop=None, old=False):
    """Three joints a, b, c; 1 ms rows from t = 2 s (start_time) for 1 s; j_b's demand ramps to
    twice its 10 N m limit, crossing it at 0.5 s; the flag (32) on joint 1 at 0.6 s. The fault
    datasets as scoopsim writes them (uint64 bits, /arm/fault_events a table of records, zero rows
    without a fault; j_b's limit as the URDF's 40 N m in /arm/effort_limit derated by 0.25 in
    /arm/effort_derate), or with `old` as before issue 40 (float64, e x 5, absent without a fault;
    /arm/effort_limit the derated limit itself, no /arm/effort_derate)."""
    t = 2.0 + np.arange(1000) * 1e-3
    limit = np.tile([50.0, 10.0, 5.0], (t.size, 1))
    demanded = np.stack([np.full(t.size, 5.0), 20.0 * (t - 2.0) if fault else 0.5 * (t - 2.0),
                         np.full(t.size, 1.0)], axis=1)
    data = {"time": t, "torque_demanded": demanded,
            "torque_applied": np.clip(demanded, -limit, limit),
            "effort_limit": limit if old else np.tile([50.0, 40.0, 5.0], (t.size, 1)),
            "fault_latched": np.where(t >= 2.6, 32, 0).astype(np.uint64) if fault
            else np.zeros(t.size, np.uint64)}
    if not old:
        data["effort_derate"] = np.tile([1.0, 0.25, 1.0], (t.size, 1))
    if old:
        data["fault_latched"] = data["fault_latched"].astype(np.float64)
        if fault:
            data["fault_events"] = np.array([[2.6, 32.0, 1.0, 12.0, 10.0]])
    else:
        data["fault_events"] = (np.array([(2.6, 32, b"JOINT_TORQUE_LIMIT", 1, b"j_b", 12.0, 10.0)],
                                         dtype=EVENT) if fault else np.zeros(0, dtype=EVENT))
    with h5py.File(path, "w") as f:
        f.attrs["arm_joints"] = "j_a,j_b,j_c"
        f.attrs["start_time"] = 2.0
        for name, value in data.items():
            if name != drop:
                f["arm/" + name] = value


def run(args):
    return subprocess.run([sys.executable, SCRIPT] + args, capture_output=True, text=True)


def main():
    with test_dir("plot_fault_timeline") as d:
        fault, calm = os.path.join(d, "fault.h5"), os.path.join(d, "calm.h5")
        make_run(fault)
        make_run(calm, fault=False)
        png = os.path.join(d, "timeline.png")
        result = run([fault, calm, "-o", png, "--labels", "fault,calm", "--title", "test"])
        assert result.returncode == 0, result.stderr
        assert "fault: JOINT_TORQUE_LIMIT on j_b at 2.600 s" in result.stdout, result.stdout
        # The limit in force: the URDF's 40 N m x the derate 0.25 (new files), or as written (old).
        assert "fault: JOINT_TORQUE_LIMIT on j_b at 2.600 s (|demanded| 12 N m, limit 10 N m); " \
            "j_b's limit 10 N m" in result.stdout, result.stdout
        assert "calm: no fault" in result.stdout, result.stdout
        with open(png, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"
        assert os.path.getsize(png) > 10000
        old = os.path.join(d, "old.h5")
        make_run(old, old=True)
        result = run([old, "-o", os.path.join(d, "old.png")])
        assert result.returncode == 0, result.stderr
        assert "JOINT_TORQUE_LIMIT on j_b at 2.600 s" in result.stdout, result.stdout
        assert "j_b's limit 10 N m" in result.stdout, result.stdout
        png2 = os.path.join(d, "sub", "joint_c.png")
        result = run([fault, "-o", png2, "--joint", "j_c"])
        assert result.returncode == 0 and os.path.exists(png2), result.stderr

        broken = os.path.join(d, "broken.h5")
        make_run(broken, drop="effort_limit")
        expect_refused(run, (([broken, "-o", os.path.join(d, "x.png")], "/arm/effort_limit"),
                             ([os.path.join(d, "none.h5"), "-o", os.path.join(d, "x.png")],
                              "no such file"),
                             ([fault, "-o", os.path.join(d, "x.png"), "--joint", "j_z"],
                              "--joint j_z"),
                             ([fault, calm, "-o", os.path.join(d, "x.png"), "--labels", "one"],
                              "--labels")))
        assert not os.path.exists(os.path.join(d, "x.png"))
    print("plot_fault_timeline_test: 2 plots written, 4 bad inputs refused with exit 2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
