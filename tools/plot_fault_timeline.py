#!/usr/bin/env python3
"""Plots an arm's joint torque against time with its effort limit and the fault flags raised.

    tools/plot_fault_timeline.py RUN.h5 [RUN2.h5 ...] -o PLOT.png [--joint NAME]
                                 [--labels A,B,...] [--title TEXT]

Reads the arm series of scoopsim runs of a scene with an `arm:` block (sim/loop/arm_driver.h; SI):
  /arm/time (n) [s], /arm/torque_demanded, /arm/torque_applied, /arm/effort_limit (n x joints)
  [N m: the URDF's], /arm/effort_derate (n x joints: arm.derate; the limit the arm saturated at is
  effort_limit x effort_derate; older files have no effort_derate and their effort_limit is that
  limit already), /arm/fault_latched (n, uint64); /arm/fault_events (e records: time, flag, flag_name,
  joint, joint_name, value, limit; older files: e x 5 float64 time, flag, joint, value, limit,
  present only when a fault was raised); root attributes arm_joints (names, comma-separated) and
  start_time (the dig's start).
One panel per run: the demanded torque (the PID's output) and the applied one (clamped at the
limit) of one joint against the run's time (one clock with the run's stderr and every dataset,
README "One clock"; the dig's start marked), its effort limit as dashed lines at
+-limit, the first time the demand reached the limit, and a vertical line at each fault event
with the flag's name. The joint: --joint NAME, else the joint of the run's first fault event, else
the joint that came closest to its limit. Flag names as arm/fault_monitor.h.

Exit status: 0 written; 2 bad input (a missing file or dataset, an unknown joint, a wrong number
of labels), one line on stderr. Needs python3-numpy, python3-h5py and python3-matplotlib.
"""

import argparse
import os
import sys

import h5py
import numpy as np

FLAGS = {1: "HARDWARE", 2: "TRAJECTORY_GENERATION", 4: "COLLISION", 8: "E_STOP",
         16: "POSITION_LIMIT", 32: "JOINT_TORQUE_LIMIT", 64: "VELOCITY_LIMIT",
         128: "NO_FORCE_DATA", 256: "FORCE_TORQUE_LIMIT"}
REQUIRED = ("time", "torque_demanded", "torque_applied", "effort_limit")


class InputError(Exception):
    """Bad input: the message is the one line to print."""


def read_events(f):
    """/arm/fault_events as rows (time, flag, joint index, value, limit): the table of records
    written since issue 40, or the e x 5 float64 array of older files (or none)."""
    if "arm/fault_events" not in f:
        return []
    data = f["arm/fault_events"][()]
    if data.dtype.names:
        return [(float(r["time"]), int(r["flag"]), int(r["joint"]), float(r["value"]),
                 float(r["limit"])) for r in data]
    return [(float(t), int(flag), int(k), float(v), float(lim)) for t, flag, k, v, lim in data]


def open_run(path):
    """A run file opened read-only; InputError for a missing file or one that is not HDF5."""
    if not os.path.isfile(path):
        raise InputError("%s: no such file (expected a scoopsim run file with /arm/, .h5)" % path)
    try:
        return h5py.File(path, "r")
    except OSError as e:
        raise InputError("%s: cannot open as HDF5 (%s)" % (path, e))


def read_run(path, joint):
    """The series of one joint of a run file, times on the run's clock."""
    with open_run(path) as f:
        for name in REQUIRED:
            if "arm/" + name not in f:
                raise InputError("%s: missing dataset /arm/%s (expected a run of a scene with an "
                                 "arm: block)" % (path, name))
        joints = str(f.attrs.get("arm_joints", "")).split(",")
        time = f["arm/time"][()]
        n = len(time)  # time is written last in a flush: a killed file may hold more of the rest
        demanded, applied, limit = (f["arm/" + name][:n] for name in REQUIRED[1:])
        if "arm/effort_derate" in f:  # the URDF's limit and the derate beside it
            limit = limit * f["arm/effort_derate"][:n]
        if demanded.shape != (len(time), len(joints)):
            raise InputError("%s: /arm/torque_demanded has shape %s, expected (%d, %d) (one "
                             "column per joint of arm_joints)"
                             % (path, demanded.shape, len(time), len(joints)))
        events = read_events(f)
        start = float(f.attrs["start_time"]) if "start_time" in f.attrs else None
    if joint is not None:
        if joint not in joints:
            raise InputError("--joint %s: %s has no such joint (it has %s)"
                             % (joint, path, ", ".join(joints)))
        j = joints.index(joint)
    elif len(events) > 0 and int(events[0][2]) >= 0:
        j = int(events[0][2])
    else:
        j = int(np.argmax(np.max(np.abs(demanded) / limit, axis=0)))
    saturated = np.nonzero(np.abs(demanded[:, j]) >= limit[:, j])[0]
    return {"joint": joints[j], "t": time, "start": start, "demanded": demanded[:, j],
            "applied": applied[:, j], "limit": limit[:, j],
            "first_saturation": time[saturated[0]] if len(saturated) else None,
            "events": [(t, FLAGS.get(int(flag), "flag %d" % int(flag)),
                        joints[int(k)] if 0 <= int(k) < len(joints) else "-", value, lim)
                       for t, flag, k, value, lim in events]}


def plot(runs, labels, title, output):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 3.2 * len(runs)), squeeze=False)
    for ax, run, label in zip(axes[:, 0], runs, labels):
        t = run["t"]
        ax.plot(t, run["demanded"], color="C0", lw=1.2, label="demanded (PID output)")
        ax.plot(t, run["applied"], color="C1", lw=1.0, ls="-", alpha=0.8,
                label="applied (clamped)")
        ax.plot(t, run["limit"], color="k", lw=1.0, ls="--", label="effort limit")
        ax.plot(t, -run["limit"], color="k", lw=1.0, ls="--")
        if run["start"] is not None:
            ax.axvline(run["start"], color="0.3", lw=1.0, ls="-.",
                       label="dig starts (%.3f s)" % run["start"])
        if run["first_saturation"] is not None:
            ax.axvline(run["first_saturation"], color="0.5", lw=1.0, ls=":",
                       label="demand reaches the limit (%.3f s)" % run["first_saturation"])
        for k, (te, flag, joint, value, lim) in enumerate(run["events"]):
            ax.axvline(te, color="C3", lw=1.5,
                       label="%s on %s at %.3f s" % (flag, joint, te) if k < 4 else None)
        ax.set_title("%s: %s" % (label, run["joint"]), fontsize=10)
        ax.set_ylabel("torque [N m]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    axes[-1, 0].set_xlabel("time t [s] (the run's clock, as on stderr and in /arm/time)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(output, dpi=120)


def main(argv=None):
    parser = argparse.ArgumentParser(description="Plot an arm joint's torque, its limit and the "
                                     "fault flags of scoopsim runs against time")
    parser.add_argument("runs", nargs="+", help="scoopsim run files (.h5) of scenes with an arm")
    parser.add_argument("-o", "--output", required=True, help="the PNG to write")
    parser.add_argument("--joint", help="the joint to plot (default: the first fault's, else the "
                        "one closest to its limit)")
    parser.add_argument("--labels", help="comma-separated panel titles (default: the file stems)")
    parser.add_argument("--title", help="figure title")
    args = parser.parse_args(argv)
    try:
        runs = [read_run(p, args.joint) for p in args.runs]
        labels = [os.path.splitext(os.path.basename(p))[0] for p in args.runs]
        if args.labels is not None:
            labels = args.labels.split(",")
            if len(labels) != len(runs):
                raise InputError("--labels: expected %d labels (one per run), got %d"
                                 % (len(runs), len(labels)))
        os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
        plot(runs, labels, args.title, args.output)
    except InputError as e:
        print("plot_fault_timeline: %s" % e, file=sys.stderr)
        return 2
    for label, run in zip(labels, runs):
        flags = "; ".join("%s on %s at %.3f s (|demanded| %.4g N m, limit %.4g N m)"
                          % (flag, joint, t, value, lim)
                          for t, flag, joint, value, lim in run["events"]) or "no fault"
        print("plot_fault_timeline: %s: %s; %s's limit %.4g N m"
              % (label, flags, run["joint"], run["limit"][-1]))
    print("plot_fault_timeline: wrote %s" % args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
