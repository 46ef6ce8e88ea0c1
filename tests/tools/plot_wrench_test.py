#!/usr/bin/python3
"""tools/plot_wrench.py on synthetic run files: writes a PNG for one and several runs, every frame
and a single pass, and for a shape-study file (one run per template group, --force-only); a
missing dataset or file gives one line and exit status 2."""

import os
import subprocess
import sys

import h5py
import numpy as np
from cli_check import expect_refused, test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "plot_wrench.py")


def make_run(path, passes=2, n=400, drop=None, seed=0, time_short_by=0):
    """A run file shaped like scoopsim's: per pass, rho 0..0.45 m and a noisy wrench. With
    time_short_by, /scoop/time lacks that many last rows, as in a file killed inside a flush
    (scoopsim writes a group's time last)."""
    rng = np.random.default_rng(seed)
    rho = np.tile(np.linspace(0.0, 0.45, n), passes)
    pass_ = np.repeat(np.arange(1, passes + 1), n).astype(float)
    time = np.arange(rho.size) * 1e-3
    base = np.stack([np.sin(8 * rho), 0.1 * rho, -2 * rho * pass_], axis=1)
    data = {"time": time, "pass": pass_, "rho": rho, "pose": np.zeros((rho.size, 7)),
            "collected_mass": 0.01 * np.arange(1, passes + 1)}
    for frame in ("body", "scoop", "world"):
        data["force_" + frame] = base + 0.2 * rng.standard_normal(base.shape)
        data["torque_" + frame] = 0.05 * base + 0.01 * rng.standard_normal(base.shape)
    if time_short_by:
        data["time"] = data["time"][:-time_short_by]
    with h5py.File(path, "w") as f:
        for name, value in data.items():
            if name != drop:
                f["scoop/" + name] = value


def make_table1_run(path):
    """One pass along a Table 1-like path in its poses: a rotation (pitch 90 -> 0 deg about the
    l_scoop origin), a horizontal push of 0.05 m, a rotation back (0 -> -90 deg); rho is the
    running travel from the push's start (first contact there), 1 mm at the first rotation's end
    (as the CoM moves while turning)."""
    n_rot, n_push = 60, 100
    theta = np.concatenate([np.linspace(np.pi / 2, 0, n_rot), np.zeros(n_push),
                            np.linspace(0, -np.pi / 2, n_rot)])
    x = np.concatenate([np.zeros(n_rot), np.linspace(0, 0.05, n_push), np.full(n_rot, 0.05)])
    rho = np.concatenate([np.linspace(0, 0.001, n_rot), 0.001 + np.linspace(0, 0.05, n_push),
                          0.051 + np.linspace(0, 0.02, n_rot)])
    # Level orientation rpy(pi, 0, 0) pitched about world y by theta: q = q_y(theta) q_x(pi).
    c, s_ = np.cos(theta / 2), np.sin(theta / 2)
    quat = np.stack([np.zeros_like(c), c, np.zeros_like(c), -s_], axis=1)  # w x y z
    pose = np.concatenate([np.stack([x, np.zeros_like(x), np.full_like(x, 0.1)], axis=1), quat],
                          axis=1)
    n = rho.size
    wrench = np.zeros((n, 3))
    with h5py.File(path, "w") as f:
        f["scoop/time"] = np.arange(n) * 1e-3
        f["scoop/pass"] = np.ones(n)
        f["scoop/rho"] = rho
        f["scoop/pose"] = pose
        for frame in ("body", "scoop", "world"):
            f["scoop/force_" + frame] = wrench
            f["scoop/torque_" + frame] = wrench


def make_study(path, drop_group=None):
    """A shape-study file shaped like scoopsim's: one group per template with a run's /scoop."""
    templates = ["tetra1", "tetra4", "tetra8", "tetra12"]
    with h5py.File(path, "w") as f:
        f.attrs["study"] = "shape"
        f.attrs["templates"] = ",".join(templates)
        for k, name in enumerate(templates):
            if name == drop_group:
                continue
            run = os.path.join(os.path.dirname(path), name + "_tmp.h5")
            make_run(run, passes=1, n=200, seed=k)
            with h5py.File(run, "r") as src:
                src.copy("scoop", f, name + "/scoop")
            f[name].attrs["spheres_per_clump"] = float([1, 4, 8, 12][k])


def run(args):
    return subprocess.run([sys.executable, SCRIPT] + args, capture_output=True, text=True)


def check_png(result, path, what):
    assert result.returncode == 0, "%s: exit %d: %s" % (what, result.returncode, result.stderr)
    with open(path, "rb") as f:
        head = f.read(8)
    assert head == b"\x89PNG\r\n\x1a\n", "%s: %s is not a PNG" % (what, path)
    assert os.path.getsize(path) > 10000, "%s: %s is nearly empty" % (what, path)


def main():
    with test_dir("plot_wrench") as d:
        a, b = os.path.join(d, "ice_bd15.h5"), os.path.join(d, "snow_bd15.h5")
        make_run(a, seed=1)
        make_run(b, passes=3, seed=2)

        png = os.path.join(d, "one.png")
        check_png(run([a, "-o", png]), png, "one run, body frame")
        for frame in ("scoop", "world"):
            png = os.path.join(d, frame + ".png")
            check_png(run([a, b, "-o", png, "--frame", frame, "--pass", "2", "--smooth", "10",
                           "--labels", "ice,snow"]), png, "two runs, %s frame, pass 2" % frame)
        # Killed inside a flush: the other series 7 rows past time; read at time's length.
        killed = os.path.join(d, "killed.h5")
        make_run(killed, seed=3, time_short_by=7)
        png = os.path.join(d, "killed.png")
        check_png(run([killed, "-o", png]), png, "time 7 rows short of the other series")
        sys.path.insert(0, os.path.join(ROOT, "tools"))
        import plot_wrench
        with plot_wrench.open_run(killed) as f:
            got = plot_wrench.read_run(f, killed, "body", "")
        assert got["force"].shape == (793, 3) and got["pose"].shape == (793, 7), got["force"].shape
        png = os.path.join(d, "sub", "raw.png")
        check_png(run([b, "-o", png, "--smooth", "1"]), png, "no smoothing, new folder")

        # The trajectory's segments, from the poses; rho's axis ends at the data's (71 mm).
        path1 = os.path.join(d, "table1.h5")
        make_table1_run(path1)
        png = os.path.join(d, "segments.png")
        result = run([path1, "-o", png])
        check_png(result, png, "segments")
        assert ("segments: rotation 1 at rho 0 mm, push at rho 1 mm, rotation 2 at rho 51 mm"
                in result.stdout), result.stdout
        png = os.path.join(d, "paper_axis.png")
        check_png(run([path1, "-o", png, "--rho-max", "450"]), png, "rho axis to 450 mm")

        # A shape study: four runs from one file, |F| alone or the full layout.
        study = os.path.join(d, "study.h5")
        make_study(study)
        png = os.path.join(d, "study_force.png")
        result = run([study, "-o", png, "--force-only"])
        check_png(result, png, "shape study, |F| only")
        assert "4 lines" in result.stdout, result.stdout
        png = os.path.join(d, "study_all.png")
        check_png(run([study, "-o", png, "--labels", "a,b,c,d"]), png, "shape study, all panels")
        broken_study = os.path.join(d, "broken_study.h5")
        make_study(broken_study, drop_group="tetra8")

        # Bad input: one line on stderr, exit 2.
        broken = os.path.join(d, "broken.h5")
        make_run(broken, drop="torque_body")
        expect_refused(run, (([broken, "-o", os.path.join(d, "x.png")], "/scoop/torque_body"),
                             ([os.path.join(d, "none.h5"), "-o", os.path.join(d, "x.png")],
                              "no such file"),
                             ([a, "-o", os.path.join(d, "x.png"), "--pass", "7"], "--pass 7"),
                             ([a, b, "-o", os.path.join(d, "x.png"), "--labels", "one"],
                              "--labels"),
                             ([broken_study, "-o", os.path.join(d, "x.png")], "no group /tetra8"),
                             ([study, "-o", os.path.join(d, "x.png"), "--labels", "a,b"],
                              "expected 4 labels"),
                             ([a, "-o", os.path.join(d, "x.png"), "--rho-max", "-1"],
                              "--rho-max")))
        assert not os.path.exists(os.path.join(d, "x.png"))
    print("plot_wrench_test: 8 plots written (segments found from the poses), 7 bad inputs "
          "refused with exit 2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
