#!/usr/bin/env python3
"""Plots a dig against Balovnev's model: the CSV of `scoopsim study balovnev` -> one PNG.

    tools/plot_balovnev.py OUT.balovnev.csv -o OUT.balovnev.png [--smooth 25]
                           [--model textbook|lander|both]

Three panels against the time since the dig began: the horizontal force against the motion, the
vertical force (downward on the scoop, Balovnev's sense), the DEM's raw (light) and its moving
mean over --smooth rows (dark); the textbook model (--model textbook or both: A split at x*,
FACTS.md section 7, the bed's gamma; dashed: the same with the plugin's A_II everywhere) and the
OceanWATERS lander plugin's variant (--model lander or both: its own rho_bulk 1700, g 1.315, q,
b = 0, A_II and its 40 N / 30 N caps; CSVs written before it have no such columns); and the
blade tip's depth below the bed's surface before the dig (the depth the model is evaluated at). The '#' lines of the CSV (rho_bulk, g, gamma, q,
phi, delta, beta) go under the title. Exit 2 with one line on stderr for a missing or malformed
CSV. Needs python3-numpy and python3-matplotlib.
"""
import argparse
import re
import sys

import numpy as np

import study_csv

OLD_COLUMNS = ("time", "pass", "rho", "tip_x", "tip_y", "tip_z", "surface", "depth",
               "dem_horizontal", "dem_down", "balovnev_horizontal", "balovnev_vertical",
               "plugin_horizontal", "plugin_vertical")
COLUMNS = OLD_COLUMNS + ("lander_horizontal", "lander_vertical")


def read(path):
    try:
        notes, data = study_csv.read(path, COLUMNS, min_rows=2)
    except ValueError as e:
        if "expected the header" not in str(e):
            raise
        notes, data = study_csv.read(path, OLD_COLUMNS, min_rows=2)  # before the lander variant
    # The CSV keeps every digit; the figure's notes four significant ones.
    short = lambda m: "%.4g" % float(m.group())
    return data, [re.sub(r"\d+\.\d{5,}(e[-+]?\d+)?", short, n) for n in notes]


def smooth(y, n):
    """Centred moving mean over n rows (shorter at the ends)."""
    if n <= 1 or len(y) < 2:
        return y
    kernel = np.ones(n)
    return np.convolve(y, kernel, "same") / np.convolve(np.ones_like(y), kernel, "same")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--smooth", type=int, default=25, help="rows in the moving mean (default 25)")
    ap.add_argument("--model", choices=("textbook", "lander", "both"), default="both",
                    help="which Balovnev to draw (default both)")
    args = ap.parse_args()
    try:
        d, notes = read(args.csv)
        if args.smooth < 1:
            raise ValueError("--smooth: expected >= 1, got %d" % args.smooth)
    except ValueError as e:
        print("plot_balovnev: %s" % e, file=sys.stderr)
        return 2
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = d["time"] - d["time"][0]
    fig, axes = plt.subplots(3, 1, figsize=(9, 9), sharex=True,
                             gridspec_kw={"height_ratios": [3, 3, 1.6]})
    for ax, dem, bal, plug, lander, what in (
            (axes[0], "dem_horizontal", "balovnev_horizontal", "plugin_horizontal",
             "lander_horizontal", "horizontal force\nagainst the motion [N]"),
            (axes[1], "dem_down", "balovnev_vertical", "plugin_vertical", "lander_vertical",
             "vertical force\ndownward on the scoop [N]")):
        ax.plot(t, d[dem], color="tab:blue", alpha=0.25, lw=0.8, label="DEM, raw")
        ax.plot(t, smooth(d[dem], args.smooth), color="tab:blue", lw=1.8,
                label="DEM, mean of %d rows" % args.smooth)
        if args.model != "lander":
            ax.plot(t, d[bal], color="tab:red", lw=1.8, label="Balovnev, textbook (A split at x*)")
            ax.plot(t, d[plug], color="tab:red", lw=1.2, ls="--",
                    label="Balovnev, textbook with the plugin's A")
        if args.model != "textbook" and lander in d:
            ax.plot(t, d[lander], color="tab:green", lw=1.6,
                    label="Balovnev, lander plugin's variant")
        ax.axhline(0, color="0.6", lw=0.6)
        ax.set_ylabel(what)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=8)
    axes[2].plot(t, 1e3 * d["depth"], color="k")
    axes[2].set_ylabel("blade tip depth\nbelow surface [mm]")
    axes[2].set_xlabel("time since the dig began [s]")
    axes[2].grid(alpha=0.3)
    title = "DEM against Balovnev's model along the same dig"
    if notes:
        title += "\n" + notes[0]
    fig.suptitle(title, fontsize=10)
    caption = "\n".join(notes[1:2] + ([n for n in notes if n.startswith("lander_*")][:1]
                                       if args.model != "textbook" else []))
    if caption:
        fig.text(0.01, 0.005, caption, fontsize=7, va="bottom", wrap=True)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(args.output, dpi=110)
    print("plot_balovnev: wrote %s" % args.output, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
