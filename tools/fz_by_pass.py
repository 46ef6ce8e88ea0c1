#!/usr/bin/env python3
"""Fz (l_scoop frame) pass by pass: where along a pass the vertical load on the scoop goes, and
where each pass first touches the bed (issue 39, item 4).

    tools/fz_by_pass.py CASE.h5 [CASE.h5 ...] -o DIR [--smooth W]

Each CASE.h5 is a dig's output (`scoopsim run` or a sweep's DIR/cases/<name>.h5) with the /scoop/
rows (time, pass, rho_path or rho, contacts, force_scoop, pose) and the root attribute surface.
l_scoop frame (assets/README.md): +x toward the blade, +z the scoop-bottom normal, pointing down
when the scoop is level; so Fz > 0 is the bed pressing the scoop's bottom down (the sample's
weight, the cut soil above the blade: Balovnev's F_v, FACTS section 7) and Fz < 0 the bed
holding the scoop up from below.

Writes:
  DIR/fz_by_pass.csv   case,pass,segment,rows,mean_Fz_N,mean_Fx_N,mean_abs_F_N: the mean over the
                       rows from first contact, per segment of the path (descent, rotation 1,
                       push, rotation 2: from /scoop/pose as tools/plot_wrench.py finds them) and
                       over the whole pass ("all")
  DIR/first_contact.csv  case,pass,time_s,pitch_deg,origin_depth_mm,com_depth_mm,segment: where
                       the scoop is at its first contact of each pass (depths below the bed's
                       original surface, of the l_scoop origin and of the CoM)
  DIR/fz_by_pass.png   Fz against rho per pass, one panel per case (smoothed over W rows)
"""
import argparse
import csv
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot_wrench  # noqa: E402

COM_SCOOP = np.array([0.001315, 0.0, 0.045328])  # the scoop's CoM in l_scoop [m] (FACTS 3)


def rotate(q, v):
    """Rotates v (3) by each unit quaternion q (n x 4, w first)."""
    w, x, y, z = q.T
    u = np.stack([x, y, z], axis=1)
    t = 2 * np.cross(u, np.broadcast_to(v, u.shape))
    return v + w[:, None] * t + np.cross(u, t)


def row_segments(pose):
    """The segment name of every row ("descent", "rotation 1", "push", "rotation 2", ...): that of
    the step into it (plot_wrench.segment_runs; row 0 that of the first step)."""
    names = np.full(len(pose), "", dtype=object)
    for name, first, steps in plot_wrench.segment_runs(pose):
        names[first + 1:first + 1 + steps] = name
        if first == 0:
            names[0] = name
    return names


def analyse(path):
    with h5py.File(path, "r") as f:
        s = f["scoop"]
        time = np.asarray(s["time"][()], dtype=float)
        n = len(time)  # time is written last in a flush: a killed file may hold more of the rest
        passes = np.rint(s["pass"][:n]).astype(int)
        rho_name = "rho_path" if "rho_path" in s else "rho"
        rho = np.asarray(s[rho_name][:n], dtype=float)
        contacts = np.asarray(s["contacts"][:n], dtype=float)
        force = np.asarray(s["force_scoop"][:n], dtype=float)
        pose = np.asarray(s["pose"][:n], dtype=float)
        surface = float(f.attrs["surface"]) if "surface" in f.attrs else np.nan
    name = os.path.splitext(os.path.basename(path))[0]
    means, firsts, curves = [], [], []
    for p in sorted(set(passes.tolist())):
        rows = np.flatnonzero(passes == p)
        seg = row_segments(pose[rows])
        touched = np.flatnonzero(contacts[rows] > 0)
        if touched.size == 0:
            continue
        k0 = touched[0]
        q = pose[rows[k0]:rows[k0] + 1, 3:7]
        com = pose[rows[k0], :3] + rotate(q / np.linalg.norm(q), COM_SCOOP)[0]
        theta, _ = plot_wrench.pitch(pose[rows[k0]:rows[k0] + 1])
        firsts.append([name, p, time[rows[k0]], np.degrees(theta[0]),
                       1e3 * (surface - pose[rows[k0], 2]), 1e3 * (surface - com[2]), seg[k0]])
        live = rows[k0:]
        live_seg = seg[k0:]
        for label in ["all"] + sorted(set(live_seg.tolist()), key=live_seg.tolist().index):
            sel = live if label == "all" else live[live_seg == label]
            fm = force[sel]
            means.append([name, p, label, len(sel), fm[:, 2].mean(), fm[:, 0].mean(),
                          np.linalg.norm(fm, axis=1).mean()])
        curves.append((p, 1e3 * rho[live], force[live, 2]))
    return name, rho_name, means, firsts, curves


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cases", nargs="+")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--smooth", type=int, default=25, help="rows in the moving mean")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    results = []
    for path in a.cases:
        try:
            results.append(analyse(path))
        except (OSError, KeyError) as e:
            sys.exit("fz_by_pass: %s: %s (expected a dig's output with /scoop/ rows)" % (path, e))
    with open(os.path.join(a.out, "fz_by_pass.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "pass", "segment", "rows", "mean_Fz_N", "mean_Fx_N", "mean_abs_F_N"])
        for _, _, means, _, _ in results:
            for m in means:
                w.writerow(m[:4] + ["%.5g" % v for v in m[4:]])
    with open(os.path.join(a.out, "first_contact.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "pass", "time_s", "pitch_deg", "origin_depth_mm", "com_depth_mm",
                    "segment"])
        for _, _, _, firsts, _ in results:
            for r in firsts:
                w.writerow(r[:2] + ["%.5g" % v for v in r[2:6]] + [r[6]])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(len(results), 1, figsize=(8, 2.6 * len(results)), squeeze=False)
    for ax, (name, rho_name, _, _, curves) in zip(axes[:, 0], results):
        for p, rho_mm, fz in curves:
            ax.plot(rho_mm, plot_wrench.smooth(fz, a.smooth), label="pass %d" % p, linewidth=1)
        ax.axhline(0, color="k", linewidth=0.5)
        ax.set_title(name, fontsize=9)
        ax.set_ylabel("Fz l_scoop [N]")
        ax.set_xlabel("%s [mm]" % rho_name)
        ax.legend(fontsize=7, ncol=5)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "fz_by_pass.png"), dpi=110)
    print("fz_by_pass: wrote %s/fz_by_pass.csv, first_contact.csv, fz_by_pass.png" % a.out)


if __name__ == "__main__":
    main()
