#!/usr/bin/env python3
"""Draws the particle-size study's figures from the files of `scoopsim study particle-size`.

    tools/plot_size_study.py DIR

Reads DIR/size_study.csv (one row per size: peaks, MPE and spread, eq. 6-7; its '#' lines hold the
smoothing rule, the reference and the verdict) and DIR/size_curves.csv (every case's |F| and |T|,
raw and smoothed, against time since first contact and rho), and writes (the sizes a '# prior:'
line names came from an earlier run's size_study.csv, rows without curves: they are in the MPE
figure only, drawn open):
  DIR/size_force.png  Fig. 3 analogue: smoothed |F| (top) and |T| (bottom) against rho, one
                      colour per size: the mean over its beds (line) and their min-max (band),
                      the raw rows of its first bed (faint);
                      the beds are put on a common grid of time since first contact, and the
                      line's rho is the beds' mean rho there
  DIR/size_stack.png  Fig. 4 analogue: the same bed-mean curves in 3-D, over rho and diameter
  DIR/size_mpe.png    Fig. 6 analogue: MPE of the peak |F| (top) and |T| (bottom) against the
                      diameter, bed mean (dots) with the beds' min-max (error bars), the +-20%
                      lines, the eq. 7 verdict marked (red ring and dotted line), where
                      |MPE| reaches 20% between the sizes (orange cross, from the CSV's
                      '# crossing:' line where it has one) and the study's 3.5 mm (dash-dot)
Exit 2 with one line on stderr for a missing or malformed file. Needs python3-numpy and
python3-matplotlib.
"""
import os
import re
import sys
import textwrap

import numpy as np

import study_csv

STUDY_COLUMNS = ("size_mm", "beds", "peak_force_mean", "peak_force_min", "peak_force_max",
                 "mpe_force_pct", "mpe_force_min_pct", "mpe_force_max_pct", "peak_torque_mean",
                 "peak_torque_min", "peak_torque_max", "mpe_torque_pct", "mpe_torque_min_pct",
                 "mpe_torque_max_pct", "within_20", "cpu_s_mean")
CURVE_COLUMNS = ("size_mm", "bed", "time", "rho", "force", "torque", "force_smooth",
                 "torque_smooth")


def note(notes, key):
    """The text after `key` in the first '#' line that starts with it ("" when none)."""
    for n in notes:
        if n.startswith(key):
            return n[len(key):].strip()
    return ""


def bed_means(curves, size):
    """One size's beds on a common grid of time since first contact (the first bed's rows, up to
    the shortest bed's end): grid, mean rho, and mean / min / max of the smoothed |F| and |T|."""
    at = curves["size_mm"] == size
    beds = sorted(set(curves["bed"][at]))
    rows = [at & (curves["bed"] == b) for b in beds]
    end = min(curves["time"][r][-1] for r in rows)
    grid = curves["time"][rows[0]]
    grid = grid[grid <= end]
    on = lambda r, c: np.interp(grid, curves["time"][r], curves[c][r])
    out = {"time": grid, "rho": np.mean([on(r, "rho") for r in rows], axis=0)}
    for c in ("force_smooth", "torque_smooth"):
        stack = np.array([on(r, c) for r in rows])
        out[c] = (stack.mean(axis=0), stack.min(axis=0), stack.max(axis=0))
    return out


def main():
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        print("usage: plot_size_study.py DIR (the output folder of scoopsim study particle-size)",
              file=sys.stderr)
        return 2
    d = sys.argv[1]
    try:
        notes, study = study_csv.read(os.path.join(d, "size_study.csv"), STUDY_COLUMNS)
        _, curves = study_csv.read(os.path.join(d, "size_curves.csv"), CURVE_COLUMNS)
        verdict = re.search(r"largest_within_20pct_mm=([0-9.eE+-]+)", note(notes, "verdict:"))
        if not verdict:
            raise ValueError("%s: expected a line '# verdict: largest_within_20pct_mm=D'"
                             % os.path.join(d, "size_study.csv"))
        verdict = float(verdict.group(1))
        # `# crossing: mpe_20pct_mm=D (force F, torque T)`: where |MPE| reaches 20% between the
        # sizes (none: within at every size); optional (earlier studies' CSVs lack it).
        crossing = {}
        for n in notes:
            for key in ("force", "torque"):
                m = re.match(r"crossing: .*\b%s ([0-9.eE+-]+)" % key, n)
                if m:
                    crossing[key] = float(m.group(1))
        prior = set()
        for n in notes:
            m = re.match(r"prior: sizes_mm=([0-9.eE+,-]+)", n)
            if m:
                prior |= {float(x) for x in m.group(1).split(",")}
        missing = [s for s in study["size_mm"]
                   if not np.any(curves["size_mm"] == s) and s not in prior]
        if missing:
            raise ValueError("%s: no curve of the size %g mm" % (os.path.join(d, "size_curves.csv"),
                                                               missing[0]))
    except ValueError as e:
        print("plot_size_study: %s" % e, file=sys.stderr)
        return 2
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d import Axes3D  # noqa: F401 (registers the 3-D projection)

    sizes = study["size_mm"]
    curved = np.array([s not in prior for s in sizes])
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(sizes)))
    means = {s: bed_means(curves, s) for s in sizes[curved]}
    smoothing = note(notes, "smoothing:")
    written = []

    # Fig. 3: smoothed |F| and |T| against rho, bed mean and band.
    fig, axes = plt.subplots(2, 1, figsize=(9, 8), sharex=True)
    for ax, c, what in ((axes[0], "force_smooth", "|F| on the scoop [N]"),
                        (axes[1], "torque_smooth", "|T| about the scoop CoM [N m]")):
        for s, colour, beds in zip(sizes[curved], colours[curved], study["beds"][curved]):
            m = means[s]
            mean, lo, hi = m[c]
            ax.plot(1e3 * m["rho"], mean, color=colour, lw=1.4,
                    label="%g mm (%d bed%s)" % (s, beds, "" if beds == 1 else "s"))
            if beds > 1:
                ax.fill_between(1e3 * m["rho"], lo, hi, color=colour, alpha=0.2, lw=0)
            raw = (curves["size_mm"] == s) & (curves["bed"] == min(curves["bed"]))
            ax.plot(1e3 * curves["rho"][raw], curves[c[:-len("_smooth")]][raw], color=colour,
                    lw=0.5, alpha=0.3)
        ax.set_ylabel(what)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="best", fontsize=8, title="diameter")
    axes[1].set_xlabel("rho: the scoop CoM's travel along the trench since first contact [mm]")
    fig.suptitle("Particle size: force and torque (smoothed bed mean; band: min-max over beds; "
                 "faint: raw, first bed)\n"
                 + textwrap.fill("smoothing: %s" % smoothing, 120), fontsize=9)
    fig.tight_layout()
    written.append(os.path.join(d, "size_force.png"))
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)

    # Fig. 4: the bed-mean curves in 3-D over rho and diameter.
    fig = plt.figure(figsize=(12, 5.5))
    for k, (c, what) in enumerate((("force_smooth", "|F| [N]"), ("torque_smooth", "|T| [N m]"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        for s, colour in zip(sizes[curved], colours[curved]):
            m = means[s]
            ax.plot(1e3 * m["rho"], np.full(m["rho"].shape, s), m[c][0], color=colour, lw=1.3)
        ax.set_xlabel("rho [mm]")
        ax.set_ylabel("diameter [mm]")
        ax.set_yticks(sizes[curved])
        ax.set_zlabel(what)
        ax.view_init(elev=25, azim=-60)
    fig.suptitle("Particle size: smoothed force and torque against rho and diameter (bed means)",
                 fontsize=10)
    fig.tight_layout()
    written.append(os.path.join(d, "size_stack.png"))
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)

    # Fig. 6: MPE against diameter, the spread, the 20% lines, the verdict.
    fig, axes = plt.subplots(2, 1, figsize=(8, 7.5), sharex=True)
    chosen = sizes == verdict
    for ax, key, what in ((axes[0], "force", "MPE of peak |F| [%]"),
                          (axes[1], "torque", "MPE of peak |T| [%]")):
        mpe = study["mpe_%s_pct" % key]
        err = np.array([mpe - study["mpe_%s_min_pct" % key], study["mpe_%s_max_pct" % key] - mpe])
        for here, style, label in ((curved, "o", "bed mean; bars: min-max over beds"),
                                   (~curved, "s", "an earlier run's row (--prior)")):
            if np.any(here):
                ax.errorbar(sizes[here], mpe[here], yerr=err[:, here], fmt=style,
                            color="tab:purple", mfc="tab:purple" if style == "o" else "none",
                            ecolor="0.4", capsize=4, label=label)
        ax.plot(sizes[chosen], mpe[chosen], "o", ms=14, mfc="none", mec="red", mew=2,
                label="eq. 7: %g mm" % verdict)
        for y in (20, -20):
            ax.axhline(y, color="red", ls="--", lw=1)
        ax.axhline(0, color="0.6", lw=0.6)
        ax.axvline(verdict, color="red", ls=":", lw=1)
        if key in crossing:
            ax.plot([crossing[key]], [20], "x", ms=10, mew=2, color="darkorange",
                    label="|MPE| = 20%% (linear in d): %.3g mm" % crossing[key])
        ax.axvline(study_csv.STUDY_SIZE_MM, color="0.3", ls="-.", lw=1,
                   label="the study's verdict: %g mm" % study_csv.STUDY_SIZE_MM)
        ax.legend(loc="best", fontsize=8)
        ax.set_ylabel(what)
        ax.grid(alpha=0.3)
    axes[1].set_xlabel("particle diameter [mm]")
    axes[1].set_xticks(sizes)
    fig.suptitle("Particle size: maximum percent error against %g mm (eq. 6), 20%% tolerance "
                 "(eq. 7)" % sizes[0], fontsize=10)
    fig.tight_layout()
    written.append(os.path.join(d, "size_mpe.png"))
    fig.savefig(written[-1], dpi=110)
    plt.close(fig)
    print("plot_size_study: wrote %s" % ", ".join(written), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
