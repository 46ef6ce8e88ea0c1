#!/usr/bin/python3
"""tools/plot_balovnev.py on a synthetic CSV of `scoopsim study balovnev`'s layout: writes a PNG;
a CSV with another header, a row that is not numbers, or no file: one line, exit 2."""

import os
import subprocess
import sys
import tempfile

from cli_check import expect_refused

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "plot_balovnev.py")
OLD_HEADER = ("time,pass,rho,tip_x,tip_y,tip_z,surface,depth,dem_horizontal,dem_down,"
              "balovnev_horizontal,balovnev_vertical,plugin_horizontal,plugin_vertical")
HEADER = OLD_HEADER + ",lander_horizontal,lander_vertical"


def main():
    run = lambda args: subprocess.run([sys.executable, SCRIPT] + args, capture_output=True,
                                      text=True)
    with tempfile.TemporaryDirectory() as d:
        good = os.path.join(d, "a.balovnev.csv")
        with open(good, "w") as f:
            f.write("# scoopsim study balovnev: x.yaml\n# rho_bulk 1326.6484923188793 kg/m^3\n")
            f.write(HEADER + "\n")
            for k in range(200):
                depth = 0.0003 * min(k, 100)
                f.write(",".join(str(v) for v in (
                    0.005 * k, 1, 0.0001 * k, 0.1, 0.08, 0.05 - depth, 0.05, depth, 0.1 * k,
                    0.01 * k, 600 * depth, 770 * depth, 590 * depth, 755 * depth,
                    min(650 * depth, 40), min(830 * depth, 30))) + "\n")
        png = os.path.join(d, "a.png")
        r = run([good, "-o", png])
        assert r.returncode == 0, r.stderr
        for model in ("textbook", "lander"):
            r = run([good, "-o", os.path.join(d, model + ".png"), "--model", model])
            assert r.returncode == 0, r.stderr
        # A CSV written before the lander variant (14 columns) still plots.
        old = os.path.join(d, "old.balovnev.csv")
        with open(good) as f, open(old, "w") as g:
            for line in f:
                g.write(line if line.startswith("#") else ",".join(line.split(",")[:14]).rstrip()
                        + "\n")
        r = run([old, "-o", os.path.join(d, "old.png")])
        assert r.returncode == 0, r.stderr
        with open(png, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n"
        other = os.path.join(d, "other.csv")
        with open(other, "w") as f:
            f.write("time,force\n0,1\n1,2\n")
        words = os.path.join(d, "words.csv")
        with open(words, "w") as f:
            f.write(HEADER + "\n" + ",".join(["x"] * 16) + "\n" + ",".join(["1"] * 16) + "\n")
        expect_refused(run, (([other, "-o", png], "expected the header"),
                             ([words, "-o", png], "expected numbers"),
                             ([os.path.join(d, "none.csv"), "-o", png], "cannot read")))
    print("plot_balovnev_test: 4 plots written (both, textbook, lander, an old CSV), 3 bad inputs "
          "refused with exit 2")
    return 0


if __name__ == "__main__":
    sys.exit(main())
