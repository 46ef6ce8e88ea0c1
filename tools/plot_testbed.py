#!/usr/bin/env python3
"""The sand testbed (paper Fig. 13): the three body-frame force components against the distance
pushed, over several beds, with their band.

    tools/plot_testbed.py RUN.h5 [RUN2.h5 ...] -o PLOT.png [--smooth 20] [--csv SUMMARY.csv]

Each RUN.h5 is a run of scenes/paper/testbed_sand.yaml on one bed (`scoopsim run`, `study
balovnev` or a case of scenes/sweeps/testbed_sand.yaml). The distance is the scoop's travel along
the trench since the push began (its l_scoop origin's, from /scoop/pose). Each bed's
/scoop/force_body is smoothed by a centred moving mean over --smooth rows, then put on a common
distance grid (linear); the plot shows, per component, each bed (thin), the mean over beds
(dashed) and its 95% confidence band (mean +- t(0.975, n-1) sd / sqrt(n)), as the study draws its
five trials. Body frame (paper Fig. 1): X across the trench (the scoop's rotation axis), Y
forward along the push, Z up; the force is the bed's on the scoop.

Prints, per component, over beds (mean +- sd): the force over the first 10% of the push, the
mean over the rest, and the slope of a straight-line fit over the rest (N/m; the trend), and
writes them to --csv when given. Exit 2 with one line on stderr for a missing or malformed file.
Needs python3-numpy, python3-h5py and python3-matplotlib.
"""
import argparse
import sys

import numpy as np

# Student's t at 0.975 for n - 1 = 1..10 degrees of freedom (two-sided 95%).
T975 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306,
        9: 2.262, 10: 2.228}
NAMES = ("X (across)", "Y (along the push)", "Z (up)")
COLOURS = ("tab:green", "tab:blue", "tab:red")


def read(path):
    import h5py
    try:
        with h5py.File(path, "r") as f:
            if "scoop/force_body" not in f or "scoop/pose" not in f:
                raise ValueError("%s: expected /scoop/force_body and /scoop/pose (a dig's run)" % path)
            force = np.asarray(f["scoop/force_body"][...], dtype=float)
            pose = np.asarray(f["scoop/pose"][...], dtype=float)
    except OSError as e:
        raise ValueError("%s: not a readable HDF5 file (%s)" % (path, e))
    if force.ndim != 2 or force.shape[1] != 3 or pose.shape[0] != force.shape[0] or len(force) < 3:
        raise ValueError("%s: expected /scoop/force_body (n x 3) and /scoop/pose (n x 7), n >= 3"
                         % path)
    travel = pose[:, :3] - pose[0, :3]
    # The push is along the trench (horizontal): its distance is the horizontal travel.
    distance = np.hypot(travel[:, 0], travel[:, 1])
    return distance, force


def smooth(y, n):
    if n <= 1:
        return y
    kernel = np.ones(n)
    return np.convolve(y, kernel, "same") / np.convolve(np.ones_like(y), kernel, "same")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--smooth", type=int, default=20, help="rows in the moving mean (default 20)")
    ap.add_argument("--csv", help="write the summary table here")
    ap.add_argument("--title", default="Sand testbed: scoop pushed at 0.01 m/s (paper Fig. 13)")
    args = ap.parse_args()
    try:
        if args.smooth < 1:
            raise ValueError("--smooth: expected >= 1, got %d" % args.smooth)
        beds = [read(p) for p in args.runs]
    except ValueError as e:
        print("plot_testbed: %s" % e, file=sys.stderr)
        return 2
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    end = min(d[-1] for d, _ in beds)
    grid = np.linspace(0.0, end, 400)
    curves = np.array([[np.interp(grid, d, smooth(f[:, c], args.smooth)) for c in range(3)]
                       for d, f in beds])  # beds x 3 x grid
    n = len(beds)
    mean = curves.mean(axis=0)
    half = (T975.get(n - 1, 1.96) * curves.std(axis=0, ddof=1) / np.sqrt(n)) if n > 1 else 0 * mean

    fig, ax = plt.subplots(figsize=(9, 5.5))
    for c in range(3):
        for b in range(n):
            ax.plot(1e3 * grid, curves[b, c], color=COLOURS[c], lw=0.6, alpha=0.35)
        ax.fill_between(1e3 * grid, mean[c] - half[c], mean[c] + half[c], color=COLOURS[c],
                        alpha=0.25, lw=0)
        ax.plot(1e3 * grid, mean[c], color=COLOURS[c], lw=1.8, ls="--", label="F" + NAMES[c])
    ax.axhline(0, color="0.5", lw=0.6)
    ax.set_xlabel("distance pushed along the rail [mm]")
    ax.set_ylabel("force on the scoop, body frame [N]")
    ax.set_title("%s\n%d beds: each thin, mean dashed, 95%% confidence band shaded; moving mean of "
                 "%d rows" % (args.title, n, args.smooth), fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(args.output, dpi=110)

    # The numbers: start (first 10%), mean and slope over the rest, per bed, then over beds.
    start = grid <= 0.1 * end
    rest = ~start
    rows = []
    for c in range(3):
        first = curves[:, c, start].mean(axis=1)
        level = curves[:, c, rest].mean(axis=1)
        slope = np.array([np.polyfit(grid[rest], curves[b, c, rest], 1)[0] for b in range(n)])
        rows.append((NAMES[c], first, level, slope))
    print("| component | first 10%% of the push [N] | mean over the rest [N] | slope over the rest "
          "[N/m] |  (%d beds: mean +- sd)" % n)
    print("| --- | --- | --- | --- |")
    sd = (lambda v: v.std(ddof=1)) if n > 1 else (lambda v: 0.0)
    for name, first, level, slope in rows:
        print("| F%s | %.3g +- %.2g | %.3g +- %.2g | %.3g +- %.2g |" % (
            name, first.mean(), sd(first), level.mean(), sd(level), slope.mean(), sd(slope)))
    if args.csv:
        with open(args.csv, "w") as f:
            f.write("component,beds,first10_mean_N,first10_sd_N,rest_mean_N,rest_sd_N,"
                    "slope_mean_N_per_m,slope_sd_N_per_m\n")
            for name, first, level, slope in rows:
                f.write("%s,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n" % (
                    "F" + name.split()[0], n, first.mean(), sd(first), level.mean(), sd(level),
                    slope.mean(), sd(slope)))
    print("plot_testbed: wrote %s (%d beds, %.1f mm)" % (args.output, n, 1e3 * end),
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
