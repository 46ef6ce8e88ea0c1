#!/usr/bin/env python3
"""The lookup set's figures (the study's Fig. 9-11) and its trends as numbers, from a wrench table.

    tools/plot_lookup.py TABLE.h5 -o DIR [--cases SWEEP_DIR] [--frame body|scoop] [--smooth W]

TABLE.h5 is `scoopsim table build`'s (sim/files/wrench_table.h: material x bite depth x pass x rho).
Writes, each panel against rho in mm (as the table measures it, its rho_definition: the length
of the scoop CoM's path since the pass's first contact, or its travel along the trench), drawn by tools/plot_wrench.py's plot (|F| and |T| on top, the force and torque
components of --frame below, raw thin and smoothed thick over --smooth grid nodes):
  DIR/lookup_fig9.png    ice, bite depth 15 mm, passes 1-5 (the study's Fig. 9)
  DIR/lookup_fig10.png   ice and snow, 15 mm, passes 1 and 5 (Fig. 10)
  DIR/lookup_fig11.png   snow, pass 1, every bite depth held (the study's 15, 9, 5, 3 mm; Fig. 11)
  DIR/lookup_trends.csv  the numbers below, also printed on stdout as tables
What the table lacks is said on stderr and in the figure's title, and what it holds is drawn: a
bite depth of 15 mm missing -> the deepest held; pass 5 missing -> the last pass held; a missing
pass or material -> left out (a figure with nothing to draw says so in its one panel).

The trajectory's segments (rotation, push, ...) are marked on the rho axis as the study marks
them, found by plot_wrench.segments from /scoop/pose of the first line's case file: the table's
/cases/file, relative to the sweep folder (--cases; default the table's own folder, where
`scoopsim sweep` puts it; through a link, the folder of the file linked to). Without the case
file the figures have no marks (said on stderr).

The numbers (lookup_trends.csv: trend,material,bite_depth_mm,pass,statistic,value,detail), all
from the table's raw samples (not smoothed; |F| is the same in either frame):
  cell            per material, bite depth and pass with data: mean_F_N, the mean of |F| over the
                  rho grid nodes where the table has data (0 .. rho_end: on the uniform grid, the
                  average over rho of |F|); peak_F_N, its largest value there; mean_T_Nm,
                  peak_T_Nm the same for |T|; nodes, how many grid nodes that is.
  ice_over_snow   per bite depth and pass both materials hold: mean_F_ratio = ice's mean_F_N /
                  snow's, peak_F_ratio the same for peak_F_N; and over all of them (bite depth and
                  pass "all") their geometric means (the study: about an order of magnitude).
  vs_bite_depth   per material and pass held at >= 2 bite depths: mean_F_grows and peak_F_grows,
                  1 when the value rises strictly from each bite depth to the next deeper one,
                  else 0; bite_depth_mm lists the depths, detail the values in that order.
  vs_pass         per material and bite depth held at >= 2 passes: the same against the pass.
Exit status: 0 written; 2 bad input (a missing file or dataset), one line on stderr. Needs
python3-numpy, python3-h5py and python3-matplotlib (tools/install-deps.sh).
"""

import argparse
import csv
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot_wrench  # noqa: E402  (the figure, its smoothing and the trajectory's segments)

STUDY_DEPTHS_MM = (15.0, 9.0, 5.0, 3.0)
FIG_DEPTH_MM = 15.0  # Fig. 9 and 10
CSV_COLUMNS = ("trend", "material", "bite_depth_mm", "pass", "statistic", "value", "detail")


class InputError(Exception):
    """Bad input: the message is the one line to print."""


def read_table(path, frame):
    """The table as numpy arrays: materials, depth_mm (B), passes (P), rho_mm (R), force and
    torque (M x B x P x R x 3) in `frame`, cell_case (M x B) case names, case_file {name: file}."""
    if not os.path.isfile(path):
        raise InputError("%s: no such file (expected a wrench table from `scoopsim table build`)"
                         % path)
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise InputError("%s: cannot open as HDF5 (%s)" % (path, e))
    with f:
        needed = ("materials/name", "bite_depth", "pass", "rho", "scoop/force_" + frame,
                  "scoop/torque_" + frame)
        for name in needed:
            if name not in f:
                raise InputError("%s: missing dataset /%s (expected a wrench table from "
                                 "`scoopsim table build`)" % (path, name))
        text = lambda v: v.decode() if isinstance(v, bytes) else str(v)
        t = {
            "path": path,
            "materials": [text(v) for v in f["materials/name"][()]],
            "depth_mm": 1e3 * np.asarray(f["bite_depth"][()], dtype=float),
            "passes": [int(v) for v in f["pass"][()]],
            "rho_mm": 1e3 * np.asarray(f["rho"][()], dtype=float),
            "force": np.asarray(f["scoop/force_" + frame][()], dtype=float),
            "torque": np.asarray(f["scoop/torque_" + frame][()], dtype=float),
            "cell_case": [text(v) for v in f["cells/case"][()]] if "cells/case" in f else [],
            "case_file": {},
            # What rho measures (sim/files/wrench_table.h): path (the CoM's path length, the
            # default since 2026-12-06) or along (its travel along the trench; older tables).
            "rho_dataset": ("scoop/rho_path" if text(f.attrs.get("rho_definition", "along"))
                            == "path" else "scoop/rho"),
        }
        if "cases/name" in f and "cases/file" in f:
            t["case_file"] = {text(n): text(p) for n, p in zip(f["cases/name"][()],
                                                                f["cases/file"][()])}
    want = (len(t["materials"]), len(t["depth_mm"]), len(t["passes"]), len(t["rho_mm"]), 3)
    for name in ("force", "torque"):
        if t[name].shape != want:
            raise InputError("%s: /scoop/%s_%s has shape %s, expected %s"
                             % (path, name, frame, t[name].shape, want))
    return t


def cell_valid(t, m, b, p):
    """The grid nodes of cell (m, b, p) where the table has data (all six components finite)."""
    return np.isfinite(t["force"][m, b, p]).all(axis=1) & np.isfinite(t["torque"][m, b, p]).all(
        axis=1)


def cell_stats(t):
    """{(material, depth_mm, pass): {mean_F_N, peak_F_N, mean_T_Nm, peak_T_Nm, nodes}} for every
    cell with data (see the module's doc)."""
    out = {}
    for m, material in enumerate(t["materials"]):
        for b, depth in enumerate(t["depth_mm"]):
            for p, pass_ in enumerate(t["passes"]):
                valid = cell_valid(t, m, b, p)
                if not valid.any():
                    continue
                f = np.linalg.norm(t["force"][m, b, p][valid], axis=1)
                tq = np.linalg.norm(t["torque"][m, b, p][valid], axis=1)
                out[(material, float(depth), pass_)] = {
                    "mean_F_N": float(f.mean()), "peak_F_N": float(f.max()),
                    "mean_T_Nm": float(tq.mean()), "peak_T_Nm": float(tq.max()),
                    "nodes": int(valid.sum())}
    return out


def fmt(v):
    return "%.9g" % v  # the CSV's numbers: 9 significant digits


def grows(values):
    """1 when every value is larger than the one before, else 0."""
    return int(all(b > a for a, b in zip(values, values[1:])))


def chain(values, unit):
    """'0.1 < 0.3 >= 0.2 N': the values in order, each step's sense."""
    s = "%.3g" % values[0]
    for a, b in zip(values, values[1:]):
        s += " %s %.3g" % ("<" if b > a else ">=", b)
    return s + " " + unit


def trends(stats):
    """The rows of lookup_trends.csv (dicts keyed by CSV_COLUMNS), from cell_stats."""
    rows = []
    add = lambda trend, material, depth, pass_, statistic, value, detail="": rows.append(dict(
        zip(CSV_COLUMNS, (trend, material, depth, pass_, statistic, value, detail))))
    for (material, depth, pass_), s in sorted(stats.items()):
        for key in ("mean_F_N", "peak_F_N", "mean_T_Nm", "peak_T_Nm"):
            add("cell", material, fmt(depth), pass_, key, fmt(s[key]))
        add("cell", material, fmt(depth), pass_, "nodes", s["nodes"])

    # Ice against snow, cell by cell.
    ratios = {"mean_F": [], "peak_F": []}
    pairs = sorted({(d, p) for (m, d, p) in stats if m == "ice"} &
                   {(d, p) for (m, d, p) in stats if m == "snow"})
    for depth, pass_ in pairs:
        ice, snow = stats[("ice", depth, pass_)], stats[("snow", depth, pass_)]
        for key in ("mean_F", "peak_F"):
            r = ice[key + "_N"] / snow[key + "_N"] if snow[key + "_N"] > 0 else float("inf")
            ratios[key].append(r)
            add("ice_over_snow", "ice/snow", fmt(depth), pass_, key + "_ratio", fmt(r),
                "ice %.3g N / snow %.3g N" % (ice[key + "_N"], snow[key + "_N"]))
    for key, rs in ratios.items():
        finite = [r for r in rs if 0 < r < float("inf")]
        if finite:
            g = math.exp(sum(math.log(r) for r in finite) / len(finite))
            add("ice_over_snow", "ice/snow", "all", "all", key + "_ratio_geomean", fmt(g),
                "geometric mean of %d cells (%.3g .. %.3g); the study: about 10"
                % (len(finite), min(finite), max(finite)))

    # Against bite depth (per material and pass) and against pass (per material and depth).
    for material in sorted({m for m, _, _ in stats}):
        mine = {(d, p): s for (m, d, p), s in stats.items() if m == material}
        for trend, axis in (("vs_bite_depth", 0), ("vs_pass", 1)):  # axis: what varies
            for fixed in sorted({k[1 - axis] for k in mine}):
                keys = sorted(k for k in mine if k[1 - axis] == fixed)
                if len(keys) < 2:
                    continue
                free = ";".join(fmt(k[0]) if axis == 0 else str(k[1]) for k in keys)
                depth, pass_ = (free, fixed) if axis == 0 else (fmt(fixed), free)
                for key in ("mean_F_N", "peak_F_N"):
                    v = [mine[k][key] for k in keys]
                    add(trend, material, depth, pass_, key[:-2] + "_grows", grows(v),
                        chain(v, "N"))
    return rows


def print_trends(rows, out):
    """The trend rows as markdown tables."""
    def table(title, header, lines):
        if not lines:
            return
        out.write("\n%s\n| %s |\n|%s\n" % (title, " | ".join(header), " --- |" * len(header)))
        for line in lines:
            out.write("| %s |\n" % " | ".join(short(v) for v in line))

    def short(v):  # 4 significant digits on screen (the CSV keeps 9)
        try:
            return "%.4g" % float(v) if "." in str(v) or "e" in str(v) else str(v)
        except ValueError:
            return str(v)

    by = lambda trend: [r for r in rows if r["trend"] == trend]
    cells = {}
    for r in by("cell"):
        cells.setdefault((r["material"], r["bite_depth_mm"], r["pass"]), {})[r["statistic"]] = \
            r["value"]
    table("Per cell (raw table samples over the grid nodes with data)",
          ("material", "bite depth [mm]", "pass", "mean norm F [N]", "peak norm F [N]",
           "mean norm T [N m]", "peak norm T [N m]", "nodes"),
          [k + (v["mean_F_N"], v["peak_F_N"], v["mean_T_Nm"], v["peak_T_Nm"], v["nodes"])
           for k, v in cells.items()])
    table("Ice against snow (the study: about an order of magnitude)",
          ("bite depth [mm]", "pass", "statistic", "ice / snow", "detail"),
          [(r["bite_depth_mm"], r["pass"], r["statistic"], r["value"], r["detail"])
           for r in by("ice_over_snow")])
    for trend, what in (("vs_bite_depth", "bite depth"), ("vs_pass", "pass")):
        table("Force against %s (1: grows at every step)" % what,
              ("material", "bite depth [mm]", "pass", "statistic", "grows", "values"),
              [(r["material"], r["bite_depth_mm"], r["pass"], r["statistic"], r["value"],
                r["detail"]) for r in by(trend)])


def pick_depth(t, want_mm, notes, what):
    """Index of the bite depth want_mm, else of the deepest held (noted)."""
    d = t["depth_mm"]
    if d.size == 0:
        return None
    hit = np.flatnonzero(np.abs(d - want_mm) < 1e-6)
    if hit.size:
        return int(hit[0])
    b = int(np.argmax(d))
    notes.append("%s: no bite depth %g mm in the table, drawn at its deepest, %g mm"
                 % (what, want_mm, d[b]))
    return b


def case_segments(t, cases_dir, m, b, pass_, notes, what):
    """The segments of the case of cell (m, b) in pass `pass_`, from its file's /scoop/pose."""
    k = m * len(t["depth_mm"]) + b
    name = t["cell_case"][k] if k < len(t["cell_case"]) else ""
    rel = t["case_file"].get(name)
    if not rel:
        notes.append("%s: no segment marks (the table names no case file for %s %g mm)"
                     % (what, t["materials"][m], t["depth_mm"][b]))
        return []
    path = os.path.join(cases_dir, rel)
    try:
        with h5py.File(path, "r") as f:
            # A group's time is written last in a flush: a killed file may hold more of the rest.
            n = f["scoop/time"].shape[0] if "scoop/time" in f else None
            rows = np.rint(f["scoop/pass"][:n]).astype(int) == pass_
            rho_mm = 1e3 * np.asarray(f[t["rho_dataset"]][:n], dtype=float)[rows]
            pose = np.asarray(f["scoop/pose"][:n], dtype=float)[rows]
    except (OSError, KeyError) as e:
        notes.append("%s: no segment marks (%s: %s; --cases names the sweep folder)"
                     % (what, path, e))
        return []
    return plot_wrench.segments(pose, rho_mm)


def figure(t, cases_dir, spec, window, frame, out_path, notes):
    """Draws one figure: spec = (title, [(label, m, b, p)]) of cells; the lines without data are
    left out (noted). Returns the number of lines drawn."""
    title, cells = spec
    lines = []
    for label, m, b, p in cells:
        valid = cell_valid(t, m, b, p)
        if not valid.any():
            notes.append("%s: %s has no data in the table" % (os.path.basename(out_path), label))
            continue
        rho = t["rho_mm"][valid]
        marks = [] if lines else case_segments(t, cases_dir, m, b, t["passes"][p], notes,
                                                os.path.basename(out_path))
        lines.append((label, rho, t["force"][m, b, p][valid], t["torque"][m, b, p][valid], marks))
    mine = [n for n in notes if n.startswith(os.path.basename(out_path))]
    full = "%s\n(table %s; raw thin, %d-node moving average thick; %s frame components)" % (
        title, os.path.basename(t["path"]), window, frame)
    full += ("\nrho: the scoop CoM's horizontal travel along the trench since the pass's first "
             "contact")
    if lines and lines[0][4]:
        full += "\ndotted: the trajectory's segments (of %s), named at their start" % lines[0][0]
    if mine:
        full += "\n" + "; ".join(n.split(": ", 1)[1] for n in mine)
    if lines:
        plot_wrench.plot(lines, frame, window, full, out_path)
    else:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(9, 4))
        ax.axis("off")
        ax.text(0.5, 0.5, full + "\n\nnothing of this figure is in the table", ha="center",
                va="center", fontsize=9)
        fig.savefig(out_path, dpi=110)
        plt.close(fig)
    return len(lines)


def specs(t, notes):
    """{file name: (title, [(label, m, b, p)])} of the three figures."""
    mat = {name: k for k, name in enumerate(t["materials"])}
    pidx = {p: k for k, p in enumerate(t["passes"])}
    out = {}

    def need_material(name, what):
        if name not in mat:
            notes.append("%s: no material %s in the table (it holds %s)"
                         % (what, name, ", ".join(t["materials"]) or "none"))
            return False
        return True

    def need_passes(wanted, what):
        missing = [p for p in wanted if p not in pidx]
        if missing:
            notes.append("%s: no pass %s in the table (it holds %s)" % (
                what, ", ".join(map(str, missing)), ", ".join(map(str, t["passes"])) or "none"))
        return [p for p in wanted if p in pidx]

    # Fig. 9: ice, 15 mm, passes 1-5.
    what = "lookup_fig9.png"
    cells = []
    if need_material("ice", what):
        b = pick_depth(t, FIG_DEPTH_MM, notes, what)
        for p in need_passes([1, 2, 3, 4, 5], what):
            cells.append(("ice pass %d" % p, mat["ice"], b, pidx[p]))
        depth = "%g mm" % t["depth_mm"][b] if b is not None else "-"
    else:
        depth = "15 mm"
    out[what] = ("Fig. 9 analogue: ice, bite depth %s, passes 1-5" % depth, cells)

    # Fig. 10: ice and snow, 15 mm, passes 1 and 5 (or the last held).
    what = "lookup_fig10.png"
    cells = []
    b = pick_depth(t, FIG_DEPTH_MM, notes, what)
    last = 5
    if 5 not in pidx and t["passes"]:
        last = max(t["passes"])
        notes.append("%s: no pass 5 in the table, its last pass %d drawn instead" % (what, last))
    for name in ("ice", "snow"):
        if need_material(name, what):
            for p in sorted({1, last}):
                if p in pidx:
                    cells.append(("%s pass %d" % (name, p), mat[name], b, pidx[p]))
    depth = "%g mm" % t["depth_mm"][b] if b is not None else "15 mm"
    out[what] = ("Fig. 10 analogue: ice against snow, bite depth %s, passes 1 and %d"
                 % (depth, last), cells)

    # Fig. 11: snow, pass 1, every bite depth held (the study's 15, 9, 5, 3 mm).
    what = "lookup_fig11.png"
    cells = []
    held = list(t["depth_mm"])
    missing = [d for d in STUDY_DEPTHS_MM if not any(abs(d - h) < 1e-6 for h in held)]
    if missing:
        notes.append("%s: no bite depth %s mm in the table (it holds %s mm)" % (
            what, ", ".join("%g" % d for d in missing), ", ".join("%g" % d for d in held)))
    if need_material("snow", what) and need_passes([1], what):
        for b in np.argsort(-t["depth_mm"]):
            cells.append(("snow %g mm" % t["depth_mm"][b], mat["snow"], int(b), pidx[1]))
    out[what] = ("Fig. 11 analogue: snow, pass 1, bite depths %s mm"
                 % ", ".join("%g" % d for d in sorted(held, reverse=True)), cells)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description="The lookup set's figures (the study's Fig. "
                                     "9-11) and trends from a wrench table.")
    parser.add_argument("table", metavar="TABLE.h5", help="a wrench table (scoopsim table build)")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write")
    parser.add_argument("--cases", metavar="SWEEP_DIR",
                        help="the sweep folder of the table's case files (default: the table's)")
    parser.add_argument("--frame", choices=("body", "scoop"), default="body",
                        help="frame of the components (default body, the study's)")
    parser.add_argument("--smooth", type=int, default=15, metavar="W",
                        help="moving average over W grid nodes, made odd (default 15; 1 = none)")
    args = parser.parse_args(argv)
    notes = []
    try:
        if args.smooth < 1:
            raise InputError("--smooth: expected a window >= 1 node, got %d" % args.smooth)
        window = args.smooth if args.smooth % 2 == 1 else args.smooth + 1
        t = read_table(args.table, args.frame)
        # The table's own folder, through a link: the report's DIR/lookup/table.h5 may link
        # to the sweep's.
        cases_dir = args.cases or os.path.dirname(os.path.realpath(args.table))
        os.makedirs(args.output, exist_ok=True)
        rows = trends(cell_stats(t))
        drawn = {}
        for name, spec in specs(t, notes).items():
            drawn[name] = figure(t, cases_dir, spec, window, args.frame,
                                 os.path.join(args.output, name), notes)
        with open(os.path.join(args.output, "lookup_trends.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
            w.writeheader()
            w.writerows(rows)
    except InputError as e:
        print("plot_lookup: %s" % e, file=sys.stderr)
        return 2
    for n in notes:
        print("plot_lookup: %s" % n, file=sys.stderr)
    print_trends(rows, sys.stdout)
    print("plot_lookup: wrote %s (%s) and lookup_trends.csv (%d rows)" % (
        args.output, ", ".join("%s: %d lines" % kv for kv in drawn.items()), len(rows)),
        file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
