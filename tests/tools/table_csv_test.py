#!/usr/bin/python3
"""`scoopsim table export-csv` against the lander simulator's format (FACTS.md section 6): the CSV
parses with Python's csv module into exactly the columns m,d,p,rho,Fx,Fy,Fz,Tx,Ty,Tz, and every
row reads back to the table's own values bit for bit (material id, bite depth [m], pass, rho [m],
the l_scoop wrench [N, N m]); rows exist exactly where the table has data. The table is built by
`scoopsim table build` from synthetic case files (no DEM), and `table query` at a grid node gives
the CSV's row; tools/compare_tables.py finds the CSV and the table.h5 the same table (every
ratio 1, the same nodes).

    table_csv_test.py SCOOPSIM
"""

import csv
import json
import os
import subprocess
import sys

import h5py
import numpy as np

from cli_check import test_dir

LANDER_COLUMNS = ["m", "d", "p", "rho", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]


def write_case(path, material, bite, passes=2, rows=60, seed=0):
    """A sweep case file: the scene text and the /scoop/ rows of `passes` passes (rho from 0 to
    about 0.18 m after a few rows without contact), with a random wrench."""
    rng = np.random.default_rng(seed)
    pass_col, rho, contacts = [], [], []
    for p in range(1, passes + 1):
        n0 = 3  # before first contact
        pass_col += [p] * (n0 + rows)
        contacts += [0] * n0 + [2] * rows
        rho += [0.0] * n0 + list(np.cumsum(rng.uniform(0, 0.006, rows)))
    n = len(rho)
    with h5py.File(path, "w") as f:
        f.attrs["scene_yaml"] = (
            f"bed: {{material: {material}, radius: 0.008, count: 10}}\n"
            f"dig: {{bite_depth: {bite}, passes: {passes}}}\n")
        f["scoop/time"] = np.arange(n) * 1e-3
        f["scoop/pass"] = np.array(pass_col, float)
        f["scoop/rho"] = np.array(rho)
        f["scoop/rho_path"] = np.array(rho)
        f["scoop/contacts"] = np.array(contacts, float)
        for name in ("force_body", "torque_body", "force_scoop", "torque_scoop"):
            f["scoop/" + name] = rng.normal(size=(n, 3))


def main():
    scoopsim = sys.argv[1]
    with test_dir("table_csv") as tmp:
        os.makedirs(os.path.join(tmp, "cases"))
        for k, (material, bite) in enumerate(
                [("snow", 0.015), ("snow", 0.003), ("ice", 0.009), ("ice", 0.015)]):
            write_case(os.path.join(tmp, "cases", f"{material}_{bite}.h5"), material, bite, seed=k)
        table = os.path.join(tmp, "table.h5")
        out_csv = os.path.join(tmp, "table.csv")
        subprocess.run([scoopsim, "table", "build", tmp, "-o", table], check=True)
        subprocess.run([scoopsim, "table", "export-csv", table, "-o", out_csv], check=True)

        with open(out_csv, newline="") as f:
            reader = csv.reader(f)
            header = next(reader)
            rows = list(reader)
        assert header == LANDER_COLUMNS, header
        assert all(len(r) == len(LANDER_COLUMNS) for r in rows)

        with h5py.File(table, "r") as t:
            ids = list(t["materials/id"][:])
            depths = t["bite_depth"][:]
            passes = list(t["pass"][:])
            grid = t["rho"][:]
            force = t["scoop/force_scoop"][:]
            torque = t["scoop/torque_scoop"][:]
        assert ids == [1, 2], ids  # snow 1, ice 2 (docs/outputs.md)
        assert list(depths) == [0.003, 0.009, 0.015], depths
        expected = []
        for m, mid in enumerate(ids):
            for b, d in enumerate(depths):
                for p, pn in enumerate(passes):
                    for r, rho in enumerate(grid):
                        w = np.concatenate([force[m, b, p, r], torque[m, b, p, r]])
                        if not np.isnan(w[0]):
                            expected.append((mid, d, pn, rho, w))
        assert len(rows) == len(expected), (len(rows), len(expected))
        for row, (mid, d, pn, rho, w) in zip(rows, expected):
            assert int(row[0]) == mid and float(row[1]) == d, row
            assert int(row[2]) == pn and float(row[3]) == rho, row
            got = np.array([float(x) for x in row[4:]])
            assert np.array_equal(got, w), (row, w)  # bit for bit: shortest round-trip text
        # Cells without a case (snow 9 mm, ice 3 mm) have no rows.
        assert not any(int(r[0]) == 1 and float(r[1]) == 0.009 for r in rows)

        # --digits 6: the same rows and keys, each wrench value within half a unit of its sixth
        # significant digit (relative 5e-6), and --digits outside 1-17 refused with exit 2.
        short_csv = os.path.join(tmp, "table6.csv")
        subprocess.run([scoopsim, "table", "export-csv", table, "-o", short_csv, "--digits", "6"],
                       check=True)
        with open(short_csv, newline="") as f:
            short = list(csv.reader(f))[1:]
        assert len(short) == len(rows)
        for row, full in zip(short, rows):
            assert row[:4] == full[:4], (row, full)
            got = np.array([float(x) for x in row[4:]])
            want = np.array([float(x) for x in full[4:]])
            assert np.all(np.abs(got - want) <= 5e-6 * np.abs(want)), (row, full)
            assert all(len(x.lstrip("-").replace(".", "").split("e")[0].lstrip("0")) <= 6
                       for x in row[4:]), row
        bad = subprocess.run([scoopsim, "table", "export-csv", table, "-o", short_csv,
                              "--digits", "18"], capture_output=True, text=True)
        assert bad.returncode == 2 and "--digits" in bad.stderr, (bad.returncode, bad.stderr)

        # `table query` at a grid node: the CSV's row.
        mid, d, pn, rho, w = expected[len(expected) // 2]
        material = "snow" if mid == 1 else "ice"
        out = subprocess.run([scoopsim, "table", "query", table, "--material", material,
                              "--bite-depth-mm", repr(d * 1e3), "--pass", str(pn),
                              "--rho-mm", repr(rho * 1e3)],
                             check=True, capture_output=True, text=True).stdout
        q = json.loads(out)
        assert np.array_equal(np.array(q["F"] + q["T"]), w), (q, w)

        # tools/compare_tables.py reads the exported CSV and the table.h5 as the same table:
        # each cell in both, the same nodes and rho_end, every ratio exactly 1 (the CSV's text
        # reads back bit for bit, above), so its rule for where a table.h5 holds data is the
        # exporter's.
        compare = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools",
                               "compare_tables.py")
        cmp_csv = os.path.join(tmp, "csv_vs_h5.csv")
        subprocess.run([sys.executable, compare, out_csv, table, "--csv", cmp_csv], check=True,
                       capture_output=True)
        with open(cmp_csv, newline="") as f:
            cells = list(csv.DictReader(l for l in f if not l.startswith("#")))
        assert len(cells) == len({(r[0], r[1], r[2]) for r in rows}), len(cells)
        for c in cells:
            assert c["status"] == "both" and c["nodes"] == c["nodes_coarse"] == c["nodes_fine"], c
            assert c["rho_end_mm_coarse"] == c["rho_end_mm_fine"], c
            assert all(float(c[k]) == 1.0 for k in ("mean_F_ratio", "peak_F_ratio",
                                                    "mean_T_ratio", "peak_T_ratio")), c
    print("table_csv_test: ok")


if __name__ == "__main__":
    main()
