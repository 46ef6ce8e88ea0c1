#!/usr/bin/env python3
"""Coarse against fine: two wrench tables of the lookup set compared cell by cell (issue 39).

    tools/compare_tables.py COARSE FINE [--size-study CSV] [--coarse-size-mm 10]
                            [--fine-size-mm 3.5] [--csv OUT.csv] [--md OUT.md]

COARSE and FINE are wrench tables, each either the lander simulator's CSV that `scoopsim table
export-csv` writes (columns m,d,p,rho,Fx,Fy,Fz,Tx,Ty,Tz: material id, bite depth [m], pass, rho
[m], force [N] and torque [N m] in the l_scoop frame; assets/lookup_coarse.csv) or the table.h5
that `scoopsim table build` writes (its /scoop/force_scoop and /scoop/torque_scoop, the same
numbers; read as HDF5 when the file starts with HDF5's signature).

A cell is (material id, bite depth, pass). Where a table holds data: the exporter
(sim/files/wrench_table.cpp, WrenchTable::ExportCsv) writes a row for a rho node exactly where
the table's sample is not NaN, i.e. from rho 0 to the pass's rho_end (its last row since first
contact); past rho_end, and in a pass without contact, there is no row (not a zero row: a row
of zeros is data, the scoop touching nothing there). So a CSV holds data at the nodes it has a
row for, a table.h5 at the nodes whose six components are finite. Nodes of the two tables are
matched by rho to 1 um (and bite depths to 1 um), so two grids of different steps meet at the
nodes they share.

For each cell in both tables, over the rho nodes where BOTH hold data (the common nodes): mean
|F|, peak |F|, mean |T|, peak |T| of each table (|F|, |T| the magnitudes of the node's force and
torque; the mean over the common nodes, on a uniform grid the average over rho) and the ratios
coarse / fine (inf where only fine's value is 0, nan where both are). A cell in one table only
is listed as such (status coarse_only or fine_only), a cell in both without a common node as
no_common_nodes; neither has statistics.

The prediction (--size-study, the CSV of `scoopsim study particle-size`, e.g.
bench/results/vm/size_study_20_2026-12-05.csv: '#' note lines, then columns size_mm,
peak_force_mean, peak_torque_mean, ...): peak |F| and peak |T| against particle size, each
linear in size between the two rows that bracket a size; the predicted coarse / fine ratio is
value(--coarse-size-mm) / value(--fine-size-mm) (default 10 mm and 3.5 mm: the coarse table's
snow spheres and the study's). It is the study's snow, pass 1 peak, of its own scene (Table 1
dig): it predicts the snow pass-1 cells (prediction_applies 1); for ice and later passes it is
only a reference (prediction_applies 0).

Output: a table of cells and a short summary (markdown) on stdout; --csv OUT.csv writes one row
per cell ('#' note lines first: the command, the inputs, the rule, the prediction):
  material, material_id, bite_depth_mm, pass, status, nodes (common), nodes_coarse, nodes_fine,
  rho_end_mm_coarse, rho_end_mm_fine (each table's own last node with data), mean_F_N_coarse,
  peak_F_N_coarse, mean_T_Nm_coarse, peak_T_Nm_coarse, the same four _fine, mean_F_ratio,
  peak_F_ratio, mean_T_ratio, peak_T_ratio (coarse / fine), predicted_peak_F_ratio,
  predicted_peak_T_ratio (the same on every row; empty without --size-study), prediction_applies;
--md OUT.md writes the summary and the table (what tools/report.py's section shows from the CSV).
Exit status: 0 written; 2 bad input (a missing or unreadable file, wrong columns, a size outside
the size study's), one line on stderr naming the file and what was expected. Needs python3-numpy
(and python3-h5py for a table.h5).
"""

import argparse
import csv
import math
import os
import sys

import numpy as np

CSV_HEADER = ("m", "d", "p", "rho", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz")
SIZE_COLUMNS = ("size_mm", "peak_force_mean", "peak_torque_mean")
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
MATERIAL_NAMES = {1: "snow", 2: "ice", 3: "sand"}  # the lander's ids (sim::LanderMaterialId)
STATS = ("mean_F_N", "peak_F_N", "mean_T_Nm", "peak_T_Nm")
RATIOS = ("mean_F_ratio", "peak_F_ratio", "mean_T_ratio", "peak_T_ratio")
OUT_COLUMNS = (("material", "material_id", "bite_depth_mm", "pass", "status", "nodes",
                "nodes_coarse", "nodes_fine", "rho_end_mm_coarse", "rho_end_mm_fine")
               + tuple(s + "_coarse" for s in STATS) + tuple(s + "_fine" for s in STATS)
               + RATIOS + ("predicted_peak_F_ratio", "predicted_peak_T_ratio",
                           "prediction_applies"))


class InputError(Exception):
    """Bad input: the message is the one line to print."""


def material_name(m):
    return MATERIAL_NAMES.get(m, "id %d" % m)


def um(metres):
    """A length [m] as whole micrometres: the key rho nodes and bite depths are matched by."""
    return int(round(metres * 1e6))


# ---- Reading a table: {(material id, bite depth [um], pass): {rho [um]: (|F| [N], |T| [N m])}}

def read_csv_table(path):
    try:
        with open(path, newline="") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise InputError("%s: cannot read (%s)" % (path, e.strerror))
    if not lines or tuple(h.strip() for h in lines[0].split(",")) != CSV_HEADER:
        raise InputError("%s:1: expected the header %s (`scoopsim table export-csv`), got %r"
                         % (path, ",".join(CSV_HEADER), lines[0] if lines else ""))
    cells = {}
    for k, line in enumerate(lines[1:], 2):
        if not line.strip():
            continue
        fields = line.split(",")
        try:
            if len(fields) != len(CSV_HEADER):
                raise ValueError
            v = [float(x) for x in fields]
            m, p = int(v[0]), int(v[2])
            if m != v[0] or p != v[2]:
                raise ValueError
        except ValueError:
            raise InputError("%s:%d: expected %d numbers (m and p whole), got %r"
                             % (path, k, len(CSV_HEADER), line))
        if not all(math.isfinite(x) for x in v):
            raise InputError("%s:%d: expected finite numbers (the exporter writes no row where "
                             "the table has none), got %r" % (path, k, line))
        node = cells.setdefault((m, um(v[1]), p), {})
        rho = um(v[3])
        if rho in node:
            raise InputError("%s:%d: a second row of m %d, d %g, p %d at rho %g" %
                             (path, k, m, v[1], p, v[3]))
        node[rho] = (math.sqrt(v[4] ** 2 + v[5] ** 2 + v[6] ** 2),
                     math.sqrt(v[7] ** 2 + v[8] ** 2 + v[9] ** 2))
    if not cells:
        raise InputError("%s: no rows (expected a table's rows under the header %s)"
                         % (path, ",".join(CSV_HEADER)))
    return cells


def read_h5_table(path):
    try:
        import h5py
    except ImportError:
        raise InputError("%s: an HDF5 file, and this Python has no h5py (python3-h5py)" % path)
    needed = ("materials/id", "bite_depth", "pass", "rho", "scoop/force_scoop",
              "scoop/torque_scoop")
    try:
        with h5py.File(path, "r") as f:
            for name in needed:
                if name not in f:
                    raise InputError("%s: missing dataset /%s (expected a wrench table from "
                                     "`scoopsim table build`)" % (path, name))
            ids = [int(v) for v in f["materials/id"][()]]
            depths = np.asarray(f["bite_depth"][()], dtype=float)
            passes = [int(v) for v in f["pass"][()]]
            rho = np.asarray(f["rho"][()], dtype=float)
            force = np.asarray(f["scoop/force_scoop"][()], dtype=float)
            torque = np.asarray(f["scoop/torque_scoop"][()], dtype=float)
    except OSError as e:
        raise InputError("%s: cannot open as HDF5 (%s)" % (path, e))
    want = (len(ids), depths.size, len(passes), rho.size, 3)
    for name, a in (("force_scoop", force), ("torque_scoop", torque)):
        if a.shape != want:
            raise InputError("%s: /scoop/%s has shape %s, expected %s (materials x bite depths "
                             "x passes x rho x 3)" % (path, name, a.shape, want))
    cells = {}
    for m, mid in enumerate(ids):
        for b, d in enumerate(depths):
            for p, pass_ in enumerate(passes):
                f, t = force[m, b, p], torque[m, b, p]
                has = np.isfinite(f).all(axis=1) & np.isfinite(t).all(axis=1)
                if not has.any():
                    continue  # no contact in that pass: the exporter writes no row
                fn, tn = np.linalg.norm(f, axis=1), np.linalg.norm(t, axis=1)
                cells[(mid, um(d), pass_)] = {um(rho[k]): (float(fn[k]), float(tn[k]))
                                              for k in np.flatnonzero(has)}
    if not cells:
        raise InputError("%s: no cell holds data (expected a wrench table with rows)" % path)
    return cells


def read_table(path):
    if not os.path.isfile(path):
        raise InputError("%s: no such file (expected a wrench table: `scoopsim table "
                         "export-csv`'s CSV or `table build`'s table.h5)" % path)
    try:
        with open(path, "rb") as f:
            head = f.read(len(HDF5_SIGNATURE))
    except OSError as e:
        raise InputError("%s: cannot read (%s)" % (path, e.strerror))
    return read_h5_table(path) if head == HDF5_SIGNATURE else read_csv_table(path)


# ---- The size study's prediction

def read_size_study(path):
    """{column: numpy array} of the size study's CSV, sorted by size_mm."""
    try:
        with open(path, newline="") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise InputError("%s: cannot read (%s; expected `scoopsim study particle-size`'s CSV)"
                         % (path, e.strerror))
    body = [(k, l) for k, l in enumerate(lines, 1) if l.strip() and not l.startswith("#")]
    if not body:
        raise InputError("%s: no header line (expected the columns %s)"
                         % (path, ", ".join(SIZE_COLUMNS)))
    header = [h.strip() for h in body[0][1].split(",")]
    missing = [c for c in SIZE_COLUMNS if c not in header]
    if missing:
        raise InputError("%s:%d: missing column %s (expected a size study's CSV with %s)"
                         % (path, body[0][0], ", ".join(missing), ", ".join(SIZE_COLUMNS)))
    rows = []
    for k, line in body[1:]:
        fields = line.split(",")
        try:
            if len(fields) != len(header):
                raise ValueError
            rows.append([float(fields[header.index(c)]) for c in SIZE_COLUMNS])
        except ValueError:
            raise InputError("%s:%d: expected %d fields, %s numbers, got %r"
                             % (path, k, len(header), ", ".join(SIZE_COLUMNS), line))
    if len(rows) < 2:
        raise InputError("%s: expected at least 2 sizes to interpolate between, got %d"
                         % (path, len(rows)))
    data = np.array(sorted(rows))
    if np.any(np.diff(data[:, 0]) <= 0):
        raise InputError("%s: expected each size_mm once" % path)
    return {c: data[:, k] for k, c in enumerate(SIZE_COLUMNS)}


def at_size(study, column, size_mm, path, option):
    """The column at size_mm, linear between the two rows that bracket it: (value, how)."""
    sizes, values = study["size_mm"], study[column]
    if not (sizes[0] - 1e-9 <= size_mm <= sizes[-1] + 1e-9):
        raise InputError("%s %g: outside the size study's sizes %g .. %g mm (%s)"
                         % (option, size_mm, sizes[0], sizes[-1], path))
    k = int(np.argmin(np.abs(sizes - size_mm)))
    if abs(sizes[k] - size_mm) <= 1e-9:
        return float(values[k]), "the %g mm row" % sizes[k]
    hi = int(np.searchsorted(sizes, size_mm))
    lo = hi - 1
    t = (size_mm - sizes[lo]) / (sizes[hi] - sizes[lo])
    return (float((1 - t) * values[lo] + t * values[hi]),
            "linear between the %g and %g mm rows" % (sizes[lo], sizes[hi]))


def prediction(path, coarse_mm, fine_mm):
    """{peak_F, peak_T: predicted coarse / fine ratio, notes: [lines]}."""
    study = read_size_study(path)
    out = {"notes": []}
    for key, column, unit in (("peak_F", "peak_force_mean", "N"),
                              ("peak_T", "peak_torque_mean", "N m")):
        c, c_how = at_size(study, column, coarse_mm, path, "--coarse-size-mm")
        f, f_how = at_size(study, column, fine_mm, path, "--fine-size-mm")
        out[key] = c / f if f != 0 else float("inf")
        out["notes"].append("predicted %s ratio %.6g = %s(%g mm) %.6g %s (%s) / %s(%g mm) %.6g %s "
                            "(%s)" % (key, out[key], column, coarse_mm, c, unit, c_how, column,
                                      fine_mm, f, unit, f_how))
    return out


# ---- The comparison

def stats(nodes, keys):
    """mean and peak of |F| and |T| over the nodes `keys` of one table's cell."""
    f = np.array([nodes[k][0] for k in keys])
    t = np.array([nodes[k][1] for k in keys])
    return {"mean_F_N": float(f.mean()), "peak_F_N": float(f.max()),
            "mean_T_Nm": float(t.mean()), "peak_T_Nm": float(t.max())}


def ratio(a, b):
    if b != 0:
        return a / b
    return float("nan") if a == 0 else float("inf")


def compare(coarse, fine, predicted):
    """One dict per cell of either table, in (material id, bite depth, pass) order."""
    rows = []
    for key in sorted(set(coarse) | set(fine)):
        m, d_um, p = key
        c, f = coarse.get(key), fine.get(key)
        row = {"material": material_name(m), "material_id": m, "bite_depth_mm": d_um / 1e3,
               "pass": p, "nodes_coarse": len(c) if c else 0, "nodes_fine": len(f) if f else 0,
               "rho_end_mm_coarse": max(c) / 1e3 if c else None,
               "rho_end_mm_fine": max(f) / 1e3 if f else None,
               "prediction_applies": int(m == 1 and p == 1)}
        if predicted:
            row["predicted_peak_F_ratio"] = predicted["peak_F"]
            row["predicted_peak_T_ratio"] = predicted["peak_T"]
        common = sorted(set(c) & set(f)) if c and f else []
        row["nodes"] = len(common)
        if not c or not f:
            row["status"] = "coarse_only" if c else "fine_only"
        elif not common:
            row["status"] = "no_common_nodes"
        else:
            row["status"] = "both"
            sc, sf = stats(c, common), stats(f, common)
            for s in STATS:
                row[s + "_coarse"], row[s + "_fine"] = sc[s], sf[s]
            for r, s in zip(RATIOS, STATS):
                row[r] = ratio(sc[s], sf[s])
        rows.append(row)
    return rows


def fmt(v, digits=4):
    if v is None:
        return "-"
    if isinstance(v, float):
        return "%.*g" % (digits, v)
    return str(v)


def median_range(values):
    v = [x for x in values if math.isfinite(x)]
    if not v:
        return "-"
    return "%s (%s .. %s)" % (fmt(float(np.median(v))), fmt(min(v)), fmt(max(v)))


def summary(rows, coarse_path, fine_path, predicted, size_path, coarse_mm, fine_mm):
    """The markdown summary and the table of cells, as lines."""
    both = [r for r in rows if r["status"] == "both"]
    out = ["## Coarse against fine (issue 39)", "",
           "Coarse: %s (%d cells); fine: %s (%d cells); %d cells in both, each compared over the "
           "rho nodes where both tables hold data (rows the exporter writes: rho 0 to the pass's "
           "rho_end). Ratios are coarse / fine." % (
               coarse_path, sum(r["nodes_coarse"] > 0 for r in rows), fine_path,
               sum(r["nodes_fine"] > 0 for r in rows), len(both)), ""]
    if predicted:
        out += ["Prediction from the size study %s: peak \\|F\\| ratio %s, peak \\|T\\| ratio %s "
                "(its value at %g mm over its value at %g mm, linear in size between its rows). "
                "It is the snow pass-1 peak of the size study's own scene: it predicts the snow "
                "pass-1 cells; for ice and later passes it is only a reference."
                % (size_path, fmt(predicted["peak_F"]), fmt(predicted["peak_T"]), coarse_mm,
                   fine_mm), ""]
    else:
        out += ["No size study given (--size-study): no prediction.", ""]
    out += ["| material | cells | mean \\|F\\| ratio | peak \\|F\\| ratio | mean \\|T\\| ratio | "
            "peak \\|T\\| ratio |", "|---|---:|---:|---:|---:|---:|"]
    for m in sorted({r["material_id"] for r in both}):
        sel = [r for r in both if r["material_id"] == m]
        out.append("| %s | %d | %s |" % (material_name(m), len(sel), " | ".join(
            median_range([r[k] for r in sel]) for k in RATIOS)))
    if not both:
        out.append("| (no cell in both tables) | 0 | - | - | - | - |")
    out += ["", "Each ratio: the median over the material's cells (min .. max)."]
    for status, what in (("coarse_only", "Only in the coarse table"),
                         ("fine_only", "Only in the fine table"),
                         ("no_common_nodes", "In both without a common rho node")):
        sel = [r for r in rows if r["status"] == status]
        if sel:
            out.append("%s: %s." % (what, ", ".join("%s %g mm pass %d" % (
                r["material"], r["bite_depth_mm"], r["pass"]) for r in sel)))
    out += ["", "| material | bite depth [mm] | pass | status | nodes | peak \\|F\\| ratio | "
                "predicted | peak \\|T\\| ratio | predicted | mean \\|F\\| ratio | "
                "mean \\|T\\| ratio |", "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        pred = lambda k: "-" if k not in r else (fmt(r[k]) + ("" if r["prediction_applies"]
                                                                else " (ref.)"))
        out.append("| %s | %g | %d | %s | %d | %s | %s | %s | %s | %s | %s |" % (
            r["material"], r["bite_depth_mm"], r["pass"], r["status"], r["nodes"],
            fmt(r.get("peak_F_ratio")), pred("predicted_peak_F_ratio"),
            fmt(r.get("peak_T_ratio")), pred("predicted_peak_T_ratio"),
            fmt(r.get("mean_F_ratio")), fmt(r.get("mean_T_ratio"))))
    if predicted:
        out += ["", "predicted: the size study's snow pass-1 ratio; (ref.): a cell it does not "
                    "predict (ice, or a pass after the first), shown as a reference."]
    return out


def csv_text(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    return str(v)


def write_csv(path, rows, notes):
    tmp = path + ".tmp"
    try:
        if os.path.dirname(path):
            os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(tmp, "w", newline="") as f:
            for n in notes:
                f.write("# %s\n" % n)
            w = csv.writer(f, lineterminator="\n")
            w.writerow(OUT_COLUMNS)
            for r in rows:
                w.writerow([csv_text(r.get(c)) for c in OUT_COLUMNS])
        os.replace(tmp, path)
    except OSError as e:
        raise InputError("%s: cannot write (%s)" % (path, e.strerror))


def write_text(path, lines):
    try:
        if os.path.dirname(path):
            os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w", encoding="utf-8") as f:
            f.write("\n".join(lines) + "\n")
    except OSError as e:
        raise InputError("%s: cannot write (%s)" % (path, e.strerror))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("coarse", metavar="COARSE", help="the coarse table (CSV or table.h5)")
    parser.add_argument("fine", metavar="FINE", help="the fine table (CSV or table.h5)")
    parser.add_argument("--size-study", metavar="CSV",
                        help="a particle-size study's CSV: the predicted peak ratios")
    parser.add_argument("--coarse-size-mm", type=float, default=10.0,
                        help="the coarse table's particle size [mm] (default 10)")
    parser.add_argument("--fine-size-mm", type=float, default=3.5,
                        help="the fine table's particle size [mm] (default 3.5, the study's)")
    parser.add_argument("--csv", metavar="OUT.csv", help="one row per cell")
    parser.add_argument("--md", metavar="OUT.md", help="the summary and the table, markdown")
    args = parser.parse_args(argv)
    try:
        coarse = read_table(args.coarse)
        fine = read_table(args.fine)
        predicted = (prediction(args.size_study, args.coarse_size_mm, args.fine_size_mm)
                     if args.size_study else None)
        rows = compare(coarse, fine, predicted)
        lines = summary(rows, args.coarse, args.fine, predicted, args.size_study,
                        args.coarse_size_mm, args.fine_size_mm)
        notes = ["tools/compare_tables.py %s %s%s --coarse-size-mm %g --fine-size-mm %g%s%s" % (
                     args.coarse, args.fine,
                     " --size-study " + args.size_study if args.size_study else "",
                     args.coarse_size_mm, args.fine_size_mm,
                     " --csv " + args.csv if args.csv else "",
                     " --md " + args.md if args.md else ""),
                 "coarse: %s; fine: %s" % (args.coarse, args.fine),
                 "nodes: the rho nodes where both tables hold data (a CSV row; a table.h5 sample "
                 "not NaN), matched to 1 um; statistics over those; ratios coarse / fine",
                 "prediction: the size study's snow pass-1 peak, value(coarse size) / value(fine "
                 "size); prediction_applies 1 for snow pass 1, else 0 (only a reference)"]
        notes += predicted["notes"] if predicted else ["prediction: none (no --size-study)"]
        if args.csv:
            write_csv(args.csv, rows, notes)
        if args.md:
            write_text(args.md, lines)
    except InputError as e:
        print("compare_tables: %s" % e, file=sys.stderr)
        return 2
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
