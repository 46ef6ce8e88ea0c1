#!/usr/bin/python3
"""tools/compare_tables.py on synthetic tables written here (the exporter's CSV columns, and a
table.h5 in the layout of sim/files/wrench_table.h), each ratio known in closed form:
  - scaled: cells snow 15 mm pass 1 and ice 15 mm pass 2 (rho 0..20 mm, 2 mm grid) where FINE is
    COARSE with force x 0.4 and torque x 0.5: every ratio is 1 / 0.4 = 2.5 (force) and
    1 / 0.5 = 2 (torque); tolerance relative 1e-12 (the CSVs hold repr() text, the output too);
  - common nodes: snow 5 mm pass 1, COARSE at rho 0, 2, 4, 6, 8, 10 mm with (Fx, Fy) = (1, 0),
    (2, 0), (3, 0), (3, 4), (50, 0), (100, 0) N, FINE at 0, 2, 4, 6 mm (its rho_end 6 mm) with
    |F| = 2 N and an off-grid node at 7 mm with 1000 N, both |T| constant (0.3, 0.4, 0) -> 0.5 and
    0.25 N m: over the common nodes 0..6 mm, by hand, mean |F| coarse (1 + 2 + 3 + 5) / 4 = 2.75,
    peak 5, fine 2 and 2 -> ratios 1.375 and 2.5; torque 2 and 2; nodes 4, rho_end 10 and 6 mm
    (counting COARSE's 50 and 100 or FINE's 1000 would change them);
  - cells in one table only: ice 3 mm pass 1 (COARSE only), snow 3 mm pass 2 (FINE only);
    status says so, no ratios;
  - the summary: snow's median peak |F| ratio over its two cells in both, 2.5 and 2.5 -> 2.5;
    its mean |F| ratio median (2.5 + 1.375) / 2 = 1.938 (1.375 .. 2.5);
  - the prediction from a synthetic size study (sizes 2, 4, 10 mm; peak |F| 1, 2, 5 N; peak |T|
    0.1, 0.3, 0.5 N m): at 3.5 mm, linear between 2 and 4 mm, |F| 1.75, |T| 0.25, so the
    predicted ratios 5 / 1.75 = 2.857142857... and 0.5 / 0.25 = 2; with --coarse-size-mm 7
    --fine-size-mm 3: |F| (2 + 3 x 3/6) / 1.5 = 3.5 / 1.5, |T| 0.4 / 0.2 = 2; prediction_applies 1
    for snow pass 1 only;
  - FINE as a table.h5 holding the same numbers (NaN past each cell's rho_end, the off-grid node
    left out, as a table's grid has none) gives the CSV's rows but the common-nodes cell, which
    loses nothing (the 7 mm node never was common): the same output CSV but for the file names;
  - the self-comparison of assets/lookup_coarse.csv: every ratio exactly 1, each (m, d, p) of
    its rows a cell in both (40 today);
  - bad input: a missing file, a CSV with the wrong header, a row that is not numbers, a size
    study without peak_torque_mean, a fine size outside the study's sizes: exit 2, one line on
    stderr naming the file (or the option) and what was expected."""

import csv
import os
import subprocess
import sys

import h5py
import numpy as np

from cli_check import expect_refused, test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "compare_tables.py")
HEADER = "m,d,p,rho,Fx,Fy,Fz,Tx,Ty,Tz"
REL = 1e-12


def scaled_cell(k):
    """The wrench at node k of the scaled cells (COARSE's): varied so |F| and |T| are not
    constant."""
    return [-(1 + k), 0.5 * k, 0.25, 0.01 * k, -0.02, 0.003 * (k + 1)]


def cells():
    """{(m, d [m], p): [(rho [m], wrench)]} of COARSE and of FINE."""
    coarse, fine = {}, {}
    for key in ((1, 0.015, 1), (2, 0.015, 2)):
        coarse[key] = [(2e-3 * k, scaled_cell(k)) for k in range(11)]
        fine[key] = [(r, [0.4 * v for v in w[:3]] + [0.5 * v for v in w[3:]])
                     for r, w in coarse[key]]
    fx = [(1, 0), (2, 0), (3, 0), (3, 4), (50, 0), (100, 0)]
    coarse[(1, 0.005, 1)] = [(2e-3 * k, [a, b, 0, 0.3, 0.4, 0]) for k, (a, b) in enumerate(fx)]
    fine[(1, 0.005, 1)] = [(2e-3 * k, [0, 2, 0, 0.25, 0, 0]) for k in range(4)] + \
        [(7e-3, [1000, 0, 0, 0.25, 0, 0])]
    coarse[(2, 0.003, 1)] = [(2e-3 * k, [1, 0, 0, 0, 0, 0.1]) for k in range(3)]
    fine[(1, 0.003, 2)] = [(2e-3 * k, [1, 0, 0, 0, 0, 0.1]) for k in range(3)]
    return coarse, fine


def write_csv(path, table):
    with open(path, "w") as f:
        f.write(HEADER + "\n")
        for (m, d, p), rows in sorted(table.items()):
            for rho, w in rows:
                f.write(",".join([str(m), repr(d), str(p), repr(rho)] + [repr(float(v))
                                                                         for v in w]) + "\n")


def write_h5(path, table):
    """A table.h5 of `table`'s grid nodes (2 mm; off-grid nodes left out), NaN elsewhere."""
    ids, depths, passes = (sorted({k[i] for k in table}) for i in range(3))
    rho = 2e-3 * np.arange(11)
    shape = (len(ids), len(depths), max(passes), rho.size, 3)
    force, torque = np.full(shape, np.nan), np.full(shape, np.nan)
    for (m, d, p), rows in table.items():
        for r, w in rows:
            k = int(round(r / 2e-3))
            if abs(k * 2e-3 - r) > 1e-12:
                continue
            at = (ids.index(m), depths.index(d), p - 1, k)
            force[at], torque[at] = w[:3], w[3:]
    with h5py.File(path, "w") as f:
        f.attrs["kind"] = "scoopsim wrench table"
        f["materials/name"] = np.array(["snow", "ice"][:len(ids)], dtype=h5py.string_dtype())
        f["materials/id"] = np.array(ids, dtype=np.int32)
        f["bite_depth"] = np.array(depths)
        f["pass"] = np.arange(1, max(passes) + 1, dtype=np.int32)
        f["rho"] = rho
        f["scoop/force_scoop"], f["scoop/torque_scoop"] = force, torque
        f["scoop/force_body"], f["scoop/torque_body"] = force, torque


def write_size_study(path, drop=None):
    columns = [c for c in ("size_mm", "beds", "peak_force_mean", "peak_torque_mean")
               if c != drop]
    values = {"size_mm": (10, 2, 4), "beds": (1, 1, 1), "peak_force_mean": (5, 1, 2),
              "peak_torque_mean": (0.5, 0.1, 0.3)}
    with open(path, "w") as f:
        f.write("# a synthetic size study\n" + ",".join(columns) + "\n")
        for k in range(3):  # out of order: the tool sorts by size
            f.write(",".join(str(values[c][k]) for c in columns) + "\n")


def run(args):
    return subprocess.run([sys.executable, SCRIPT] + args, capture_output=True, text=True)


def read_rows(path):
    with open(path) as f:
        body = [l for l in f.read().splitlines() if not l.startswith("#")]
    return {(r["material"], float(r["bite_depth_mm"]), int(r["pass"])): r
            for r in csv.DictReader(body)}


def close(got, want):
    return abs(float(got) - want) <= REL * abs(want)


def main():
    with test_dir("compare_tables") as tmp:
        p = lambda name: os.path.join(tmp, name)
        coarse, fine = cells()
        write_csv(p("coarse.csv"), coarse)
        write_csv(p("fine.csv"), fine)
        write_h5(p("fine.h5"), fine)
        write_size_study(p("size.csv"))

        r = run([p("coarse.csv"), p("fine.csv"), "--size-study", p("size.csv"), "--csv",
                 p("out.csv"), "--md", p("out.md")])
        assert r.returncode == 0, r.stderr
        rows = read_rows(p("out.csv"))
        assert len(rows) == 5, sorted(rows)
        for key in (("snow", 15.0, 1), ("ice", 15.0, 2)):
            row = rows[key]
            assert row["status"] == "both" and row["nodes"] == "11", row
            for c, want in (("mean_F_ratio", 2.5), ("peak_F_ratio", 2.5), ("mean_T_ratio", 2.0),
                            ("peak_T_ratio", 2.0)):
                assert close(row[c], want), (key, c, row[c])
            # The statistics themselves: peak |F| of COARSE at its last node, k = 10.
            assert close(row["peak_F_N_coarse"], float(np.linalg.norm(scaled_cell(10)[:3])))
        row = rows[("snow", 5.0, 1)]
        assert row["status"] == "both" and row["nodes"] == "4", row
        assert row["nodes_coarse"] == "6" and row["nodes_fine"] == "5", row
        assert float(row["rho_end_mm_coarse"]) == 10 and float(row["rho_end_mm_fine"]) == 7, row
        for c, want in (("mean_F_N_coarse", 2.75), ("peak_F_N_coarse", 5.0),
                        ("mean_F_N_fine", 2.0), ("peak_F_N_fine", 2.0),
                        ("mean_F_ratio", 1.375), ("peak_F_ratio", 2.5),
                        ("mean_T_ratio", 2.0), ("peak_T_ratio", 2.0)):
            assert close(row[c], want), (c, row[c], want)
        assert rows[("ice", 3.0, 1)]["status"] == "coarse_only", rows[("ice", 3.0, 1)]
        assert rows[("snow", 3.0, 2)]["status"] == "fine_only", rows[("snow", 3.0, 2)]
        for key in (("ice", 3.0, 1), ("snow", 3.0, 2)):
            assert rows[key]["peak_F_ratio"] == "" and rows[key]["nodes"] == "0", rows[key]
        for key, row in rows.items():
            assert close(row["predicted_peak_F_ratio"], 5 / 1.75), row
            assert close(row["predicted_peak_T_ratio"], 2.0), row
            assert row["prediction_applies"] == ("1" if key[0] == "snow" and key[2] == 1
                                                 else "0"), (key, row)
        with open(p("out.md")) as f:
            md = f.read()
        assert md.strip() == r.stdout.strip(), "stdout is the markdown"
        assert "| snow | 2 | 1.938 (1.375 .. 2.5) | 2.5 (2.5 .. 2.5) | 2 (2 .. 2) |" in md, md
        assert "Only in the coarse table: ice 3 mm pass 1." in md, md
        assert "Only in the fine table: snow 3 mm pass 2." in md, md
        assert "snow pass-1 peak" in md and "only a reference" in md, md
        assert "| snow | 5 | 1 | both | 4 | 2.5 | 2.857 | 2 | 2 | 1.375 | 2 |" in md, md
        assert "| ice | 15 | 2 | both | 11 | 2.5 | 2.857 (ref.) | 2 | 2 (ref.) | 2.5 | 2 |" in md

        # Other sizes: linear between the bracketing rows at both ends.
        r = run([p("coarse.csv"), p("fine.csv"), "--size-study", p("size.csv"),
                 "--coarse-size-mm", "7", "--fine-size-mm", "3", "--csv", p("sizes.csv")])
        assert r.returncode == 0, r.stderr
        row = read_rows(p("sizes.csv"))[("snow", 5.0, 1)]
        assert close(row["predicted_peak_F_ratio"], 3.5 / 1.5), row
        assert close(row["predicted_peak_T_ratio"], 2.0), row

        # FINE as a table.h5: the same rows, but the off-grid node it cannot hold.
        r = run([p("coarse.csv"), p("fine.h5"), "--size-study", p("size.csv"), "--csv",
                 p("out_h5.csv")])
        assert r.returncode == 0, r.stderr
        rows_h5 = read_rows(p("out_h5.csv"))
        assert sorted(rows_h5) == sorted(rows)
        for key, row in rows.items():
            other = dict(rows_h5[key])
            if key == ("snow", 5.0, 1):
                assert other["nodes_fine"] == "4" and float(other["rho_end_mm_fine"]) == 6, other
                other["nodes_fine"], other["rho_end_mm_fine"] = "5", row["rho_end_mm_fine"]
            assert other == row, (key, other, row)

        # The shipped coarse table against itself: every ratio 1.
        asset = os.path.join(ROOT, "assets", "lookup_coarse.csv")
        r = run([asset, asset, "--csv", p("self.csv")])
        assert r.returncode == 0, r.stderr
        rows = read_rows(p("self.csv"))
        with open(asset) as f:
            asset_cells = {tuple(l.split(",")[:3]) for l in f.read().splitlines()[1:] if l}
        assert len(rows) == len(asset_cells) and all(v["status"] == "both"
                                                     for v in rows.values()), len(rows)
        assert all(float(v[c]) == 1.0 for v in rows.values() for c in (
            "mean_F_ratio", "peak_F_ratio", "mean_T_ratio", "peak_T_ratio")), "not all 1"
        assert "No size study given" in r.stdout

        # Bad input.
        with open(p("bad_header.csv"), "w") as f:
            f.write("m,d,p,rho,Fx,Fy,Fz\n1,0.01,1,0,1,2,3\n")
        with open(p("bad_row.csv"), "w") as f:
            f.write(HEADER + "\n1,0.01,1,0,1,2,3,4,5,x\n")
        write_size_study(p("size_no_torque.csv"), drop="peak_torque_mean")
        expect_refused(run, (
            ([p("none.csv"), p("fine.csv")], "none.csv: no such file (expected a wrench table"),
            ([p("coarse.csv"), p("bad_header.csv")],
             "bad_header.csv:1: expected the header " + HEADER),
            ([p("bad_row.csv"), p("fine.csv")], "bad_row.csv:2: expected 10 numbers"),
            ([p("coarse.csv"), p("fine.csv"), "--size-study", p("none_size.csv")],
             "none_size.csv: cannot read"),
            ([p("coarse.csv"), p("fine.csv"), "--size-study", p("size_no_torque.csv")],
             "size_no_torque.csv:2: missing column peak_torque_mean"),
            ([p("coarse.csv"), p("fine.csv"), "--size-study", p("size.csv"), "--fine-size-mm",
              "1"], "--fine-size-mm 1: outside the size study's sizes 2 .. 10 mm")))
    print("compare_tables_test: closed-form ratios (2.5, 2; common nodes 1.375, 2.5), one-table "
          "cells, the interpolated prediction, CSV = table.h5, the asset against itself all 1, "
          "6 bad inputs refused")
    return 0


if __name__ == "__main__":
    sys.exit(main())
