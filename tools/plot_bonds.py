#!/usr/bin/env python3
"""Digs in sintered ground side by side: the wrench along rho and the bonds broken, per pass.

    tools/plot_bonds.py RUN.h5 [RUN2.h5 ...] -o PLOT.png [--csv SUMMARY.csv] [--labels A,B,...]
                        [--smooth W] [--log]

Reads scoopsim run files (SI units; docs/outputs.md), also one a run is still writing:
  /scoop/time (n) [s], /scoop/pass (n), /scoop/rho_path (or /scoop/rho) (n) [m],
  /scoop/force_scoop (n x 3) [N] (l_scoop frame), /scoop/collected_mass (one row per pass that has
  ended) [kg] (optional); /bonds/time (k) [s], /bonds/intact (k), /bonds/broken/time (b) [s] and
  /bonds/broken/mode (b: 1 tension, 2 shear); an unbonded run has no /bonds/ and counts zero.
Draws, one colour per run and one line style per pass: |F| against rho (smoothed by a centred
moving average over --smooth samples, odd; --log: on a log axis, values below 1e-3 N drawn at
1e-3 N, so that an unbonded run's ~0.5 N and a sintered one's ~600 N both read), and the bonds
broken so far in the pass against rho (each break placed at the rho of the scoop row at or after
its time, the pass's last row for a break after it).

A break belongs to the pass whose steps it broke in (its time is the end of that step): pass p's
steps end from its first row's time (a pass's first row is written at the end of its first step,
sim/loop/world.cpp) up to, not including, the first row of the next pass in the file; so a break
at the very end of a pass, after the pass's last row, is that pass's. A break before the file's
first row is in no pass.

--csv writes one row per run and pass: mean and peak |F| after first contact (the first row with
|F| > 0), mean Fz (l_scoop) after it, the bonds broken in the pass in tension and in shear, the
bonds intact at the pass's end (the intact count of the last /bonds/ row at or before the pass's
last row, less the pass's breaks after that row; empty for an unbonded run), the mass collected,
rho_end_m: the rho of the pass's last row [m] (how far a pass that is cut short got), and
complete: 1 if the pass has ended (the run writes a pass's /scoop/collected_mass row when its
driver ends the pass, World::EndPass, flushed with the pass's last rows), else 0 (a run still
writing, or stopped, in that pass). A pass cut short counts what the file holds so far.

Exit status: 0 written; 2 bad input (a missing file or dataset, a bad option, an output that
cannot be written), one line on stderr.
Needs python3-numpy, python3-h5py and python3-matplotlib (tools/install-deps.sh).
"""

import argparse
import csv
import os
import sys

import h5py
import numpy as np

LOG_FLOOR_N = 1e-3  # --log: |F| at or below this is drawn at it [N]
FIELDS = ["run", "pass", "mean_F_N", "peak_F_N", "mean_Fz_scoop_N", "broken_tension",
          "broken_shear", "intact_at_end", "collected_kg", "rho_end_m", "complete"]


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot_wrench  # noqa: E402  (a run file's opening, live or not, and its bad-input error)

InputError = plot_wrench.InputError
open_run = plot_wrench.open_run


class Parser(argparse.ArgumentParser):
    """argparse, but a bad option is one line on stderr (argparse adds the usage), exit 2."""

    def error(self, message):
        print("plot_bonds: %s (see --help)" % message, file=sys.stderr)
        sys.exit(2)


def need(f, path, name):
    if name not in f:
        raise InputError("%s: missing dataset %s (expected a scoopsim run file of a dig)"
                         % (path, name))
    return f[name][()]


def read_run(path):
    """The run's scoop rows and its bond records, as numpy arrays. A file read while its run
    writes, or killed in a flush, may hold more rows in one series than in another: each group's
    series are cut to their common length."""
    with open_run(path) as f:
        run = {"time": np.asarray(need(f, path, "/scoop/time"), dtype=float),
               "pass": np.asarray(need(f, path, "/scoop/pass"), dtype=float)}
        if "/scoop/rho_path" not in f and "/scoop/rho" not in f:
            raise InputError("%s: missing dataset /scoop/rho_path (or /scoop/rho) (expected a "
                             "scoopsim run file of a dig)" % path)
        rho = "/scoop/rho_path" if "/scoop/rho_path" in f else "/scoop/rho"
        run["rho"] = np.asarray(f[rho][()], dtype=float)
        run["force"] = np.asarray(need(f, path, "/scoop/force_scoop"), dtype=float).reshape(-1, 3)
        run["collected"] = (np.atleast_1d(np.asarray(f["/scoop/collected_mass"][()], dtype=float))
                            if "/scoop/collected_mass" in f else np.zeros(0))
        run["bond_time"] = f["/bonds/time"][()] if "/bonds/time" in f else np.zeros(0)
        run["intact"] = f["/bonds/intact"][()] if "/bonds/intact" in f else np.zeros(0)
        if "/bonds/broken/time" in f:
            run["break_time"] = np.asarray(f["/bonds/broken/time"][()], dtype=float)
            run["break_mode"] = np.asarray(need(f, path, "/bonds/broken/mode"), dtype=int)
        else:
            run["break_time"] = np.zeros(0)
            run["break_mode"] = np.zeros(0, dtype=int)
    for group in (("time", "pass", "rho", "force"), ("bond_time", "intact"),
                  ("break_time", "break_mode")):
        n = min(len(run[k]) for k in group)
        for k in group:
            run[k] = run[k][:n]
    return run


def smooth(y, window):
    if window <= 1 or y.size < window:
        return y
    kernel = np.ones(window) / window
    pad = window // 2
    return np.convolve(np.pad(y, pad, mode="edge"), kernel, mode="valid")


def passes(run):
    return [int(p) for p in np.unique(run["pass"])]


def pass_rows(run, p):
    return np.nonzero(run["pass"] == p)[0]


def pass_span(run, p):
    """[start, end) of the times of pass p's steps' ends: its first row's time to the next pass's
    first row's (inf for the file's last pass)."""
    firsts = sorted(run["time"][pass_rows(run, q)][0] for q in passes(run))
    start = run["time"][pass_rows(run, p)][0]
    later = [t for t in firsts if t > start]
    return start, (later[0] if later else np.inf)


def breaks_in_pass(run, p):
    """The breaks of pass p (pass_span): their rho (the row at or after each, else the pass's last)
    and mode."""
    rows = pass_rows(run, p)
    start, end = pass_span(run, p)
    inside = (run["break_time"] >= start) & (run["break_time"] < end)
    at = np.searchsorted(run["time"][rows], run["break_time"][inside], side="left")
    at = np.clip(at, 0, rows.size - 1)
    return run["rho"][rows][at], run["break_mode"][inside]


def intact_at_end(run, p):
    """The bonds intact at pass p's end: the last /bonds/ row at or before the pass's last row,
    less the pass's breaks after it ('' without bonds, or without a row yet)."""
    if not run["intact"].size:
        return ""
    rows = pass_rows(run, p)
    i = np.searchsorted(run["bond_time"], run["time"][rows][-1], side="right") - 1
    if i < 0:
        return ""
    _, end = pass_span(run, p)
    t = run["break_time"]
    after = int(((t > run["bond_time"][i]) & (t < end)).sum())
    return int(run["intact"][i]) - after


def summary(run, label):
    rows_out = []
    for k, p in enumerate(passes(run)):
        rows = pass_rows(run, p)
        force = run["force"][rows]
        mag = np.linalg.norm(force, axis=1)
        touched = np.nonzero(mag > 0)[0]
        after = touched[0] if touched.size else rows.size
        _, modes = breaks_in_pass(run, p)
        collected = run["collected"]
        rows_out.append({
            "run": label, "pass": p,
            "mean_F_N": float(mag[after:].mean()) if after < mag.size else 0.0,
            "peak_F_N": float(mag.max()) if mag.size else 0.0,
            "mean_Fz_scoop_N": float(force[after:, 2].mean()) if after < mag.size else 0.0,
            "broken_tension": int((modes == 1).sum()), "broken_shear": int((modes == 2).sum()),
            "intact_at_end": intact_at_end(run, p),
            "collected_kg": float(collected[k]) if k < collected.size else "",
            "rho_end_m": float(run["rho"][rows][-1]),
            "complete": 1 if k < collected.size else 0})
    return rows_out


def draw(runs, labels, window, log):
    """The figure: |F| (moving average over `window` rows; log: on a log axis, floored at
    LOG_FLOOR_N) and the bonds broken so far, against rho, a line per run and pass."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_f, ax_b) = plt.subplots(2, 1, figsize=(10, 8), sharex=True)
    styles = ["-", "--", ":", "-.", (0, (1, 3))]
    for n, (run, label) in enumerate(zip(runs, labels)):
        color = "C%d" % (n % 10)
        for k, p in enumerate(passes(run)):
            rows = pass_rows(run, p)
            rho_mm = 1e3 * run["rho"][rows]
            mag = smooth(np.linalg.norm(run["force"][rows], axis=1), window)
            if log:
                mag = np.maximum(mag, LOG_FLOOR_N)
            style = styles[k % len(styles)]
            ax_f.plot(rho_mm, mag, color=color, linestyle=style, label="%s, pass %d" % (label, p))
            where, _ = breaks_in_pass(run, p)
            order = np.sort(where)
            ax_b.step(1e3 * order, np.arange(1, order.size + 1), where="post", color=color,
                      linestyle=style, label="%s, pass %d" % (label, p))
    if log:
        ax_f.set_yscale("log")
        ax_f.set_ylabel("|F| on the scoop [N] (moving average, log)")
    else:
        ax_f.set_ylabel("|F| on the scoop [N] (moving average)")
    ax_b.set_ylabel("bonds broken in the pass")
    ax_b.set_xlabel("rho: the scoop CoM's path since first contact [mm]")
    for ax in (ax_f, ax_b):
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, ncol=2)
        ax.grid(alpha=0.3, which="both" if ax is ax_f and log else "major")
    fig.tight_layout()
    return fig


def main(argv=None):
    ap = Parser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--csv")
    ap.add_argument("--labels")
    ap.add_argument("--smooth", type=int, default=51)
    ap.add_argument("--log", action="store_true",
                    help="|F| on a log axis (values below %g N drawn at it)" % LOG_FLOOR_N)
    args = ap.parse_args(argv)
    try:
        labels = args.labels.split(",") if args.labels else [
            os.path.splitext(os.path.basename(r))[0] for r in args.runs]
        if len(labels) != len(args.runs):
            raise InputError("--labels: expected %d labels, got %d" % (len(args.runs),
                                                                      len(labels)))
        if args.smooth < 1 or args.smooth % 2 == 0:
            raise InputError("--smooth: expected an odd window >= 1, got %d" % args.smooth)
        runs = [read_run(r) for r in args.runs]
    except InputError as e:
        print("plot_bonds: %s" % e, file=sys.stderr)
        return 2

    fig = draw(runs, labels, args.smooth, args.log)
    option = "-o"
    try:
        fig.savefig(args.output, dpi=110)
        if args.csv:
            option = "--csv"
            rows = [r for run, label in zip(runs, labels) for r in summary(run, label)]
            with open(args.csv, "w", newline="") as out:
                w = csv.DictWriter(out, fieldnames=FIELDS)
                w.writeheader()
                w.writerows(rows)
    except OSError as e:
        print("plot_bonds: %s %s: cannot write (%s)" % (option, e.filename or "", e.strerror or e),
              file=sys.stderr)
        return 2
    print("plot_bonds: wrote %s%s" % (args.output, " and " + args.csv if args.csv else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
