#!/usr/bin/env python3
"""Digs in sintered ground side by side: the wrench along rho and the bonds broken, per pass.

    tools/plot_bonds.py RUN.h5 [RUN2.h5 ...] -o PLOT.png [--csv SUMMARY.csv] [--labels A,B,...]
                        [--smooth W]

Reads scoopsim run files (SI units):
  /scoop/time (n) [s], /scoop/pass (n), /scoop/rho_path (or /scoop/rho) (n) [m],
  /scoop/force_scoop (n x 3) [N] (l_scoop frame), /scoop/collected_mass (P) [kg] (optional);
  /bonds/time (k) [s], /bonds/intact (k), /bonds/broken/time (b) [s] and /bonds/broken/mode (b:
  1 tension, 2 shear) (docs/outputs.md); an unbonded run has no /bonds/ and counts zero.
Draws, one colour per run and one line style per pass: |F| against rho (smoothed by a centred
moving average over --smooth samples, odd), and the bonds broken so far in the pass against rho
(each break placed at the rho of the scoop row at or after its time). --csv writes one row per
run and pass: mean and peak |F| after first contact, mean Fz (l_scoop), the bonds broken in the
pass in tension and in shear, the bonds intact at the pass's end, the mass collected.

Exit status: 0 written; 2 bad input (a missing file or dataset), one line on stderr. Needs
python3-numpy, python3-h5py and python3-matplotlib (tools/install-deps.sh).
"""

import argparse
import csv
import os
import sys

import h5py
import numpy as np


class InputError(Exception):
    """Bad input: the message is the one line to print."""


def need(f, path, name):
    if name not in f:
        raise InputError("%s: missing dataset %s (expected a scoopsim run file of a dig)"
                         % (path, name))
    return f[name][()]


def read_run(path):
    """The run's scoop rows and its bond records, as numpy arrays."""
    if not os.path.isfile(path):
        raise InputError("%s: no such file (expected a scoopsim run file, .h5)" % path)
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise InputError("%s: not an HDF5 file (%s)" % (path, e))
    with f:
        run = {"time": need(f, path, "/scoop/time"), "pass": need(f, path, "/scoop/pass")}
        run["rho"] = f["/scoop/rho_path"][()] if "/scoop/rho_path" in f else need(
            f, path, "/scoop/rho")
        run["force"] = need(f, path, "/scoop/force_scoop")
        run["collected"] = (f["/scoop/collected_mass"][()] if "/scoop/collected_mass" in f
                            else None)
        run["bond_time"] = f["/bonds/time"][()] if "/bonds/time" in f else np.zeros(0)
        run["intact"] = f["/bonds/intact"][()] if "/bonds/intact" in f else np.zeros(0)
        if "/bonds/broken/time" in f:
            run["break_time"] = np.asarray(f["/bonds/broken/time"][()], dtype=float)
            run["break_mode"] = np.asarray(need(f, path, "/bonds/broken/mode"), dtype=int)
        else:
            run["break_time"] = np.zeros(0)
            run["break_mode"] = np.zeros(0, dtype=int)
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


def breaks_in_pass(run, rows):
    """The breaks within the pass's time span: their rho (the row at or after each) and mode."""
    t = run["time"][rows]
    start = t[0] - (t[1] - t[0] if t.size > 1 else 0.0)
    inside = (run["break_time"] > start) & (run["break_time"] <= t[-1])
    at = np.searchsorted(t, run["break_time"][inside], side="left")
    at = np.clip(at, 0, t.size - 1)
    return run["rho"][rows][at], run["break_mode"][inside]


def summary(run, label):
    rows_out = []
    for k, p in enumerate(passes(run)):
        rows = pass_rows(run, p)
        force = run["force"][rows]
        mag = np.linalg.norm(force, axis=1)
        touched = np.nonzero(mag > 0)[0]
        after = touched[0] if touched.size else rows.size
        _, modes = breaks_in_pass(run, rows)
        intact = ""
        if run["intact"].size:
            end = run["time"][rows][-1]
            i = np.searchsorted(run["bond_time"], end, side="right") - 1
            intact = int(run["intact"][max(i, 0)])
        collected = run["collected"]
        rows_out.append({
            "run": label, "pass": p,
            "mean_F_N": float(mag[after:].mean()) if after < mag.size else 0.0,
            "peak_F_N": float(mag.max()) if mag.size else 0.0,
            "mean_Fz_scoop_N": float(force[after:, 2].mean()) if after < mag.size else 0.0,
            "broken_tension": int((modes == 1).sum()), "broken_shear": int((modes == 2).sum()),
            "intact_at_end": intact,
            "collected_kg": float(collected[k]) if collected is not None and k < collected.size
            else ""})
    return rows_out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--csv")
    ap.add_argument("--labels")
    ap.add_argument("--smooth", type=int, default=51)
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
            mag = np.linalg.norm(run["force"][rows], axis=1)
            style = styles[k % len(styles)]
            ax_f.plot(rho_mm, smooth(mag, args.smooth), color=color, linestyle=style,
                      label="%s, pass %d" % (label, p))
            where, _ = breaks_in_pass(run, rows)
            order = np.sort(where)
            ax_b.step(1e3 * order, np.arange(1, order.size + 1), where="post", color=color,
                      linestyle=style, label="%s, pass %d" % (label, p))
    ax_f.set_ylabel("|F| on the scoop [N] (moving average)")
    ax_b.set_ylabel("bonds broken in the pass")
    ax_b.set_xlabel("rho: the scoop CoM's path since first contact [mm]")
    ax_f.legend(fontsize=7, ncol=2)
    ax_b.legend(fontsize=7, ncol=2)
    ax_f.grid(alpha=0.3)
    ax_b.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.output, dpi=110)
    if args.csv:
        rows = [r for run, label in zip(runs, labels) for r in summary(run, label)]
        with open(args.csv, "w", newline="") as out:
            w = csv.DictWriter(out, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    print("plot_bonds: wrote %s%s" % (args.output, " and " + args.csv if args.csv else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
