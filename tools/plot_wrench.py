#!/usr/bin/env python3
"""Plots the wrench on the scoop against rho, the way the paper's figures do.

    tools/plot_wrench.py RUN.h5 [RUN2.h5 ...] -o PLOT.png [--frame body|scoop|world]
                         [--pass N] [--smooth W] [--labels A,B,...] [--title TEXT] [--force-only]

Reads the scoop time series of scoopsim run files (SI units):
  /scoop/time (n) [s], /scoop/pass (n), /scoop/rho (n) [m],
  /scoop/force_<frame>, /scoop/torque_<frame> (n x 3) [N], [N m],
  /scoop/collected_mass (P) [kg] (optional: added to the legend),
  /scoop/pose (n x 7: position, quaternion w x y z of l_scoop in world; optional: the segments).
Draws |F| and |T| on the top row, Fx Fy Fz and Tx Ty Tz of the chosen frame (default body: the
paper's Fig. 1 frame) below, against rho in mm: the scoop CoM's horizontal travel along the
trench since the pass's first contact (the paper's rho), from 0 to the largest rho in the data
(--rho-max MM sets it, e.g. 450 for the paper's axis). Each series is drawn raw (thin, light) and
smoothed by a centred moving average over --smooth samples (odd; 1 = none). One line per run and
pass: all passes, or only pass N with --pass N. Legend: the file stem, or --labels.

The trajectory's segments (the paper's Fig. 9-11 mark them on the rho axis) are read from the
first line's poses: each row is a rotation when the scoop's pitch changes by more than 1e-6 rad
from the previous row, else a descent (vertical travel), a push (horizontal travel) or a hold; a
change of kind is a boundary, drawn as a dotted line at that row's rho with the segment's name
above the top panels (segments shorter than 3 rows are merged into the previous one).

A shape-study file (scoopsim study shape: one group per clump template, each with a run's /scoop
datasets) counts as one run per template, in the study's order, labelled with the template and
its sphere count. --force-only draws |F| alone against rho, one line per run (the paper's Fig. 8).

Exit status: 0 written; 2 bad input (a missing file or dataset, an empty selection), one line on
stderr. Needs python3-numpy, python3-h5py and python3-matplotlib (tools/install-deps.sh).
"""

import argparse
import os
import sys

import h5py
import numpy as np

FRAMES = ("body", "scoop", "world")
REQUIRED = ("time", "pass", "rho")


class InputError(Exception):
    """Bad input: the message is the one line to print."""


def open_run(path):
    if not os.path.isfile(path):
        raise InputError("%s: no such file (expected a scoopsim run file, .h5)" % path)
    try:
        return h5py.File(path, "r", swmr=True)  # readable while the run is still writing
    except (OSError, ValueError):
        pass
    try:
        return h5py.File(path, "r")
    except OSError as e:
        raise InputError("%s: cannot open as HDF5 (%s)" % (path, e))


def read_runs(path, frame):
    """[(label, run)]: the file's own run, or one per template group of a shape-study file."""
    with open_run(path) as f:
        if "scoop" in f or f.attrs.get("study") != "shape":
            return [(os.path.splitext(os.path.basename(path))[0], read_run(f, path, frame, ""))]
        groups = str(f.attrs.get("templates", "")).split(",")
        out = []
        for g in [g for g in groups if g]:
            if g not in f:
                raise InputError("%s: the study names template %s but has no group /%s"
                                 % (path, g, g))
            spheres = int(f[g].attrs.get("spheres_per_clump", 0))
            label = "%s (%d sphere%s)" % (g, spheres, "" if spheres == 1 else "s")
            out.append((label, read_run(f, path, frame, "/" + g)))
        return out


def read_run(f, path, frame, group):
    """Dict of numpy arrays: time, pass (int), rho, force, torque, collected_mass (or None), from
    the /scoop datasets under `group` ("" for a run file)."""
    scoop = group + "/scoop/"
    names = list(REQUIRED) + ["force_" + frame, "torque_" + frame]
    for name in names:
        if scoop + name not in f:
            raise InputError("%s: missing dataset %s%s (expected a scoopsim run file "
                             "with the scoop time series)" % (path, scoop, name))
    # A group's time is written last in each flush, so a file read while its run writes, or
    # killed in a flush, may hold more rows in the other series: its rows are time's.
    n = f[scoop + "time"].shape[0]
    run = {name: np.asarray(f[scoop + name][:n], dtype=float) for name in names}
    mass = f[scoop + "collected_mass"][()] if scoop + "collected_mass" in f else None
    pose = np.asarray(f[scoop + "pose"][:n], dtype=float) if scoop + "pose" in f else None
    for name in names:
        want = (n, 3) if name.startswith(("force", "torque")) else (n,)
        if run[name].shape != want:
            raise InputError("%s: %s%s has shape %s, expected %s"
                             % (path, scoop, name, run[name].shape, want))
    return {
        "time": run["time"],
        "pass": np.rint(run["pass"]).astype(int),
        "rho": run["rho"],
        "force": run["force_" + frame],
        "torque": run["torque_" + frame],
        "collected_mass": None if mass is None else np.atleast_1d(np.asarray(mass, dtype=float)),
        "pose": pose if pose is not None and pose.shape == (n, 7) else None,
    }


def smooth(y, window):
    """Centred moving average over `window` samples (odd), ignoring NaN; the ends average over
    the samples that exist, so they are not pulled toward zero."""
    window = min(window, y.size if y.size % 2 == 1 else y.size - 1)  # "same" needs <= n
    if window <= 1:
        return y
    kernel = np.ones(window)
    valid = np.isfinite(y)
    total = np.convolve(np.where(valid, y, 0.0), kernel, mode="same")
    count = np.convolve(valid.astype(float), kernel, mode="same")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def pitch(pose):
    """Pitch [rad] of the blade (l_scoop +x) from horizontal, per row of /scoop/pose."""
    q = pose[:, 3:7]
    norm = np.linalg.norm(q, axis=1)
    q = q / np.where(norm > 0, norm, 1.0)[:, None]
    w, x, y, z = q.T
    # l_scoop +x in world: the first column of the rotation matrix.
    ex = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)], axis=1)
    return np.arctan2(-ex[:, 2], np.hypot(ex[:, 0], ex[:, 1])), norm > 0


def segment_runs(pose):
    """[(name, first step, steps)] of the trajectory's segments (see the module's doc), step k
    going from row k to row k + 1, named "descent", "push", "hold", "rotation" or, when a kind
    comes more than once, "rotation 1", "rotation 2", ...; [] without valid poses."""
    if pose is None or len(pose) < 3:
        return []
    theta, valid = pitch(pose)
    if not valid.all():
        return []
    d_theta = np.abs(np.diff(theta))
    step = np.diff(pose[:, :3], axis=0)
    horizontal = np.hypot(step[:, 0], step[:, 1])
    vertical = np.abs(step[:, 2])
    kinds = np.where(d_theta > 1e-6, "rotation",
                     np.where(np.maximum(horizontal, vertical) < 1e-9, "hold",
                              np.where(vertical > horizontal, "descent", "push")))
    runs = []  # [kind, first row, rows]
    for k, kind in enumerate(kinds):
        if runs and runs[-1][0] == kind:
            runs[-1][2] += 1
        else:
            runs.append([kind, k, 1])
    merged = []  # a run of under 3 rows is a row across a boundary: part of the previous one
    for r in runs:
        if merged and (r[2] < 3 or merged[-1][0] == r[0]):
            merged[-1][2] += r[2]
        else:
            merged.append(r)
    totals = {}
    for kind, _, _ in merged:
        totals[kind] = totals.get(kind, 0) + 1
    seen = {}
    runs = []
    for kind, first, steps in merged:
        seen[kind] = seen.get(kind, 0) + 1
        runs.append((kind if totals[kind] == 1 else "%s %d" % (kind, seen[kind]), first, steps))
    return runs


def segments(pose, rho_mm):
    """[(name, rho_mm at its start)] of the trajectory's segments (see the module's doc), or []
    without poses."""
    named = [(name, float(rho_mm[first])) for name, first, _ in segment_runs(pose)]
    # Before first contact rho is 0: keep only the segment in force when contact begins; a
    # segment over which rho does not move (a hold at the push's end) gives way to the next.
    before = [m for m in named if m[1] <= 0]
    named = before[-1:] + [m for m in named if m[1] > 0]
    return [m for k, m in enumerate(named)
            if k + 1 == len(named) or named[k + 1][1] - m[1] > 0.5]


def series(runs, labels, pass_filter):
    """[(label, rho_mm, force (n x 3), torque (n x 3), segments)], one per run and pass."""
    out = []
    for run, label in zip(runs, labels):
        passes = sorted(set(run["pass"].tolist()))
        if pass_filter is not None:
            passes = [p for p in passes if p == pass_filter]
        for p in passes:
            rows = run["pass"] == p
            text = label if len(passes) == 1 and pass_filter is None else "%s pass %d" % (label, p)
            mass = run["collected_mass"]
            if mass is not None and 1 <= p <= mass.size:
                text += " (%.1f g)" % (1e3 * mass[p - 1])
            rho_mm = 1e3 * run["rho"][rows]
            pose = None if run["pose"] is None else run["pose"][rows]
            out.append((text, rho_mm, run["force"][rows], run["torque"][rows],
                        segments(pose, rho_mm)))
    return out


def plot(lines, frame, window, title, out_path, force_only=False, rho_max=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    magnitude = (lambda f, t: np.linalg.norm(f, axis=1))
    if force_only:  # the paper's Fig. 8: |F| of each run against rho
        fig = plt.figure(figsize=(9, 5.5), constrained_layout=True)
        panels = [(fig.add_subplot(1, 1, 1), "|F| [N]", magnitude)]
    else:
        fig = plt.figure(figsize=(13, 9), constrained_layout=True)
        grid = fig.add_gridspec(3, 6)
        panels = [
            (fig.add_subplot(grid[0, 0:3]), "|F| [N]", magnitude),
            (fig.add_subplot(grid[0, 3:6]), "|T| [N m]", lambda f, t: np.linalg.norm(t, axis=1)),
        ]
        for i, axis in enumerate("xyz"):
            panels.append((fig.add_subplot(grid[1, 2 * i:2 * i + 2]), "F%s [N]" % axis,
                           lambda f, t, i=i: f[:, i]))
        for i, axis in enumerate("xyz"):
            panels.append((fig.add_subplot(grid[2, 2 * i:2 * i + 2]), "T%s [N m]" % axis,
                           lambda f, t, i=i: t[:, i]))

    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    # The axis ends at the data's largest rho (a pass of the paper's 0.3 m push ends near 240 mm,
    # not at its 450 mm axis), or at --rho-max.
    rho_seen = max([0.0] + [float(np.nanmax(r)) for _, r, _, _, _ in lines if r.size])
    if rho_max is None:
        rho_max = max(1.02 * rho_seen, 1.0)
    marks = lines[0][4]
    for ax, ylabel, value in panels:
        for k, (label, rho, force, torque, _) in enumerate(lines):
            colour = colours[k % len(colours)]
            y = value(force, torque)
            ax.plot(rho, y, color=colour, linewidth=0.5, alpha=0.3)
            ax.plot(rho, smooth(y, window), color=colour, linewidth=1.5, label=label)
        ax.set_xlim(0, rho_max)
        ax.set_xlabel("rho [mm]")
        ax.set_ylabel(ylabel)
        ax.grid(True, linewidth=0.3)
        for name, at in marks:
            if 0 < at <= rho_max:
                ax.axvline(at, color="0.35", linestyle=":", linewidth=1.0)
    # The segments' names above the top panels, at their starts.
    top = [ax for ax, _, _ in panels[:1 if force_only else 2]]
    for ax in top:
        for name, at in marks:
            if 0 <= at <= rho_max:
                ax.text(at, 1.01, " " + name, transform=ax.get_xaxis_transform(), fontsize=7,
                        rotation=0, va="bottom", ha="left", color="0.25")
    panels[0][0].legend(fontsize="small")
    default = ("Force magnitude on the scoop (raw and %d-sample moving average)" % window
               if force_only else
               "Wrench on the scoop, %s frame (raw and %d-sample moving average)" % (frame, window))
    default += ("\nrho: the scoop CoM's horizontal travel along the trench since the pass's first "
                "contact")
    if marks:
        default += "\ndotted: the trajectory's segments (of %s), named at their start" % lines[0][0]
    fig.suptitle(title or default)
    fig.savefig(out_path, dpi=110)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description="Plot the scoop wrench of scoopsim runs "
                                     "against rho.")
    parser.add_argument("runs", nargs="+", metavar="RUN.h5", help="scoopsim run files")
    parser.add_argument("-o", "--output", required=True, metavar="PLOT.png", help="image to write")
    parser.add_argument("--frame", choices=FRAMES, default="body",
                        help="frame of the components (default body, paper Fig. 1)")
    parser.add_argument("--pass", dest="pass_", type=int, metavar="N",
                        help="plot only pass N (default: every pass)")
    parser.add_argument("--smooth", type=int, default=25, metavar="W",
                        help="moving-average window in samples, made odd (default 25; 1 = none)")
    parser.add_argument("--labels", help="comma-separated legend labels, one per run "
                        "(default: file stems)")
    parser.add_argument("--title", help="figure title")
    parser.add_argument("--rho-max", type=float, metavar="MM",
                        help="end of the rho axis in mm (default: the data's largest rho)")
    parser.add_argument("--force-only", action="store_true",
                        help="draw |F| alone, one line per run (a shape study: per template)")
    args = parser.parse_args(argv)

    try:
        if args.smooth < 1:
            raise InputError("--smooth: expected a window >= 1 sample, got %d" % args.smooth)
        if args.rho_max is not None and not (np.isfinite(args.rho_max) and args.rho_max > 0):
            raise InputError("--rho-max: expected a length > 0 in mm, got %s" % args.rho_max)
        window = args.smooth if args.smooth % 2 == 1 else args.smooth + 1
        named = [lr for p in args.runs for lr in read_runs(p, args.frame)]
        labels = [label for label, _ in named]
        if args.labels is not None:
            labels = args.labels.split(",")
            if len(labels) != len(named):
                raise InputError("--labels: expected %d labels (one per run), got %d"
                                 % (len(named), len(labels)))
        lines = series([run for _, run in named], labels, args.pass_)
        if not lines:
            raise InputError("--pass %s: no rows of that pass in %s"
                             % (args.pass_, ", ".join(args.runs)))
        out_dir = os.path.dirname(os.path.abspath(args.output))
        os.makedirs(out_dir, exist_ok=True)
        plot(lines, args.frame, window, args.title, args.output, args.force_only, args.rho_max)
    except InputError as e:
        print("plot_wrench: %s" % e, file=sys.stderr)
        return 2
    marks = lines[0][4]
    print("plot_wrench: wrote %s (%d lines, %s frame; segments: %s)" % (
        args.output, len(lines), args.frame,
        ", ".join("%s at rho %.0f mm" % m for m in marks) if marks else "none"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
