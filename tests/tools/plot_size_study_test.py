#!/usr/bin/python3
"""tools/plot_size_study.py on synthetic files of `scoopsim study particle-size`'s layout (three
sizes, two beds each, a '# crossing:' line): writes the three PNGs, also when a '# prior:' line
names a size that has no curves (an earlier run's row); a folder without the files, a CSV with
another header, rows that are not numbers, no verdict line, or a size with neither curves nor a
prior line: one line, exit 2."""

import os
import subprocess
import sys

from cli_check import expect_refused, test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "plot_size_study.py")
STUDY = ("size_mm,beds,peak_force_mean,peak_force_min,peak_force_max,mpe_force_pct,"
         "mpe_force_min_pct,mpe_force_max_pct,peak_torque_mean,peak_torque_min,peak_torque_max,"
         "mpe_torque_pct,mpe_torque_min_pct,mpe_torque_max_pct,within_20,cpu_s_mean")
CURVES = "size_mm,bed,time,rho,force,torque,force_smooth,torque_smooth"
PNGS = ("size_force.png", "size_stack.png", "size_mpe.png")


def write_study(d, header=STUDY, verdict=True, rows=None, prior=None):
    with open(os.path.join(d, "size_study.csv"), "w") as f:
        f.write("# scoopsim study particle-size x.yaml\n# smoothing: centred moving mean over 0.05 s\n")
        if prior:
            f.write("# prior: sizes_mm=%s from old/size_study.csv (its rows: ...)\n" % prior)
        if verdict:
            f.write("# verdict: largest_within_20pct_mm=4\n")
            # where |MPE| reaches 20 between 4 and 6 mm: 4 + (20 - 15) / (40 - 15) x 2 = 4.4 mm
            # (force), 4 + 5 / 35 x 2 = 4.29 mm (torque); drawn where the line is given
            f.write("# crossing: mpe_20pct_mm=4.28571 (force 4.4, torque 4.28571): where ...\n")
        f.write(header + "\n")
        for row in rows or (
                "2,2,10,9,11,0,-10,10,1,0.9,1.1,0,-10,10,1,60",
                "4,2,11.5,11,12,15,10,20,1.15,1.1,1.2,15,10,20,1,20",
                "6,2,14,13,15,40,30,50,1.5,1.4,1.6,50,40,60,0,8"):
            f.write(row + "\n")


def write_curves(d, sizes=((2, 10), (4, 11.5), (6, 14))):
    with open(os.path.join(d, "size_curves.csv"), "w") as f:
        f.write("# curves\n" + CURVES + "\n")
        for size, peak in sizes:
            for bed in (1, 2):
                for k in range(300 + 7 * bed):
                    t = 1e-3 * k
                    shape = min(1.0, t / 0.1)
                    f.write("%g,%d,%g,%g,%g,%g,%g,%g\n" % (size, bed, t, 0.3 * t, peak * shape + bed,
                                                          0.1 * peak * shape, peak * shape,
                                                          0.1 * peak * shape))


def main():
    run = lambda args: subprocess.run([sys.executable, SCRIPT] + args, capture_output=True,
                                      text=True)
    with test_dir("plot_size_study") as d:
        write_study(d)
        write_curves(d)
        r = run([d])
        assert r.returncode == 0, r.stderr
        for png in PNGS:
            with open(os.path.join(d, png), "rb") as f:
                assert f.read(8) == b"\x89PNG\r\n\x1a\n", png
        # 6 mm from an earlier run: no curves, in the MPE figure only.
        prior = os.path.join(d, "prior")
        os.mkdir(prior)
        write_study(prior, prior="6")
        write_curves(prior, sizes=((2, 10), (4, 11.5)))
        r = run([prior])
        assert r.returncode == 0, r.stderr
        for png in PNGS:
            assert os.path.getsize(os.path.join(prior, png)) > 0, png
        no_prior = os.path.join(d, "no_prior")
        os.mkdir(no_prior)
        write_study(no_prior)
        write_curves(no_prior, sizes=((2, 10), (4, 11.5)))
        empty = os.path.join(d, "empty")
        os.mkdir(empty)
        other = os.path.join(d, "other")
        os.mkdir(other)
        write_study(other, header="size_mm,force")
        write_curves(other)
        words = os.path.join(d, "words")
        os.mkdir(words)
        write_study(words, rows=["x," * 15 + "x"])
        write_curves(words)
        no_verdict = os.path.join(d, "no_verdict")
        os.mkdir(no_verdict)
        write_study(no_verdict, verdict=False)
        write_curves(no_verdict)
        expect_refused(run, (([empty], "cannot read"),
                             ([other], "expected the header"),
                             ([words], "expected numbers"),
                             ([no_verdict], "expected a line '# verdict"),
                             ([no_prior], "no curve of the size 6 mm")))
    print("plot_size_study_test: 3 plots written twice (once with a prior row), 5 bad inputs "
          "refused with exit 2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
