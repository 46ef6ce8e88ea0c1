#!/usr/bin/python3
"""tools/plot_bonds.py on synthetic run files written as sim/loop/world.cpp writes a dig's (the
/scoop/ rows, /bonds/ rows with them, one /bonds/broken/ record per break, dtypes and shapes of
docs/outputs.md): a step of DT = 1 ms, a row at the end of a pass's first step and then every
5 steps (World::Record's next_row), pass 1 = steps 1..98 (rows at steps 1, 5, 10, ..., 95), pass 2
= steps 99..196 (rows at 99, 103, 108, ..., 193), 20 rows each; a break's time is the end of its
step. Per pass, |F| = 0 before the contact row c (3 in pass 1, 4 in pass 2), then F = s (3, 0, -4)
N up to row 9 and s (0, 12, 5) N from row 10 (s = 1 in pass 1, 100 in pass 2); rho_path = 2 mm x
(row - c) from contact. 1000 bonds made; breaks (step, mode): pass 1 (1, 1) (40, 2) (41, 2)
(97, 1: after the pass's last row) (98, 2: the pass's last step, exactly at the boundary); pass 2
(99, 1: its first step) (150, 1) (196, 2: after its last row).
Closed forms checked, from the CSV:
  mean |F| after first contact: (7 x 5 + 10 x 13) / 17 = 165/17 N; 100 (6 x 5 + 10 x 13) / 16 N;
  peak |F|: 13 N; 1300 N; mean Fz: (7 x -4 + 10 x 5) / 17 = 22/17 N; 100 (6 x -4 + 50) / 16 N;
  broken tension/shear: 2/3 in pass 1 (97 and 98 are pass 1's, 99 pass 2's), 2/1 in pass 2;
  intact at the pass's end: 1000 - 5 = 995; 1000 - 8 = 992 (the breaks after the last row count);
  rho_end_m: 2 mm x (19 - 3) = 0.032 m; 2 mm x (19 - 4) = 0.030 m; complete 1 and 1;
  collected_kg 0.01 and 0.02 (/scoop/collected_mass, one row per ended pass).
A run cut short in pass 2 (rows up to its 13th, step 158, breaks up to step 158, one
collected_mass row; /scoop/pass one row ahead of the others, as a file killed between two series'
flushes): pass 2 has rho_end_m 2 mm x (12 - 4) = 0.016 m, complete 0, tension 2, shear 0, intact
1000 - 7 = 993 (as far as the file goes); pass 1 as above. The same file read while a process
still holds it open for writing in SWMR mode (as a run writes its file): the same two rows. An
unbonded run (no /bonds/, |F| 0.5 N): no breaks, intact empty. A run that has written no row yet
(empty series): no CSV row, and alone a CSV of the header. Tolerance: relative 1e-12 (the CSV
keeps Python's repr of each float).
The figure (plot_bonds.draw, smoothing off): each break drawn at the rho of the row at or after
it, the pass's last row for one after it: pass 1 at 0, 10, 12, 32, 32 mm (steps 1, 40 -> row 40,
41 -> row 45, 97 and 98 -> row 95), pass 2 at 0, 14, 30 mm (steps 99, 150 -> row 153, 196 -> row
193), to 1e-9 mm; |F| drawn from 0 to 1300 N on a linear axis, and with --log on a log axis from
1e-3 N (the rows before contact, floored) to 1300 N, exactly.
Defect this pins: the tool took a pass's breaks from one row spacing before its first row to its
last row, so the breaks of a pass's last steps (97, 98) went to the next pass, those after the
last pass's last row (196) to none, and the intact count at a pass's end was that of its last row
(997, not 995); a file whose series differ in length (the cut one) raised IndexError, and so did
--csv of a run with no row yet.
Also: the PNG is written and non-empty, with and without --log (the two differ); bad input (a
missing file, a file without /scoop/time, an even or non-integer --smooth, a wrong --labels count,
no -o) gives exit 2 and exactly one line on stderr."""

import csv
import importlib.util
import os
import subprocess
import sys

import h5py
import numpy as np

from cli_check import expect_refused, test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "plot_bonds.py")
DT = 1e-3          # step [s]
INTERVAL = 5       # steps between rows (dig.interval / DT)
PASS_STEPS = 98    # steps per pass
MADE = 1000        # bonds made
CONTACT = {1: 3, 2: 4}
SCALE = {1: 1.0, 2: 100.0}
BREAKS = [(1, 1), (40, 2), (41, 2), (97, 1), (98, 2), (99, 1), (150, 1), (196, 2)]
COLUMNS = ["run", "pass", "mean_F_N", "peak_F_N", "mean_Fz_scoop_N", "broken_tension",
           "broken_shear", "intact_at_end", "collected_kg", "rho_end_m", "complete"]
F_A, F_B = np.array([3.0, 0.0, -4.0]), np.array([0.0, 12.0, 5.0])  # |F| 5 and 13 N


def row_steps(first_step):
    """The steps that end with a row in a pass whose first step is first_step (World::Record:
    next_row starts at the pass's start and goes up by the interval at each row)."""
    steps, next_row = [], first_step - 1
    for s in range(first_step, first_step + PASS_STEPS):
        if s >= next_row:
            steps.append(s)
            next_row += INTERVAL
    return steps


def write_run(path, cut_step=None, bonded=True):
    """A two-pass bonded dig (or, cut_step given, one whose file ends at that step)."""
    scoop = {k: [] for k in ("time", "pass", "rho", "rho_path", "force_scoop", "contacts")}
    bond_time, intact = [], []
    for p in (1, 2):
        for j, s in enumerate(row_steps(1 + (p - 1) * PASS_STEPS)):
            if cut_step is not None and s > cut_step:
                break
            c = CONTACT[p]
            force = 0 * F_A if j < c else SCALE[p] * (F_A if j < 10 else F_B)
            scoop["time"].append(s * DT)
            scoop["pass"].append(float(p))
            scoop["rho"].append(0.0015 * max(0, j - c))
            scoop["rho_path"].append(0.002 * max(0, j - c))
            scoop["force_scoop"].append(force)
            scoop["contacts"].append(0.0 if j < c else 3.0)
            bond_time.append(s * DT)
            intact.append(float(MADE - sum(1 for b, _ in BREAKS if b <= s)))
    breaks = [(b, m) for b, m in BREAKS if cut_step is None or b <= cut_step]
    ended = 2 if cut_step is None else sum(1 for p in (1, 2) if p * PASS_STEPS <= cut_step)
    with h5py.File(path, "w") as f:
        for k, v in scoop.items():
            f["scoop/" + k] = np.array(v, dtype=float)
        f["scoop/collected_mass"] = 0.01 * np.arange(1, ended + 1, dtype=float)
        if cut_step is not None:  # /scoop/pass flushed one row further than the others
            del f["scoop/pass"]
            f["scoop/pass"] = np.array(scoop["pass"] + [2.0])
        if not bonded:
            return
        f["bonds/time"] = np.array(bond_time, dtype=float)
        f["bonds/intact"] = np.array(intact, dtype=float)
        m = len(breaks)
        f["bonds/broken/time"] = np.array([b * DT for b, _ in breaks], dtype=float)
        f["bonds/broken/pair"] = np.arange(2 * m, dtype=np.uint64).reshape(m, 2)
        f["bonds/broken/position"] = np.zeros((m, 3))
        f["bonds/broken/mode"] = np.array([md for _, md in breaks], dtype=np.uint64)
        f["bonds/broken/stress"] = np.full(m, 1e6)


def write_unbonded(path):
    n = 30
    with h5py.File(path, "w") as f:
        f["scoop/time"] = DT * np.arange(1, n + 1, dtype=float)
        f["scoop/pass"] = np.ones(n)
        f["scoop/rho_path"] = 0.001 * np.arange(n, dtype=float)
        f["scoop/force_scoop"] = np.tile([0.3, 0.0, 0.4], (n, 1))  # |F| 0.5 N
        f["scoop/collected_mass"] = np.array([0.005])


# A writer that holds a copy of a file open in SWMR mode (as a run holds its output) until its
# stdin closes: argv[1] the file, argv[2] the copy.
SWMR_WRITER = """
import sys, h5py
with h5py.File(sys.argv[1], "r") as src, h5py.File(sys.argv[2], "w", libver="latest") as dst:
    names = []
    src.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
    for n in names:
        v = src[n][()]
        dst.create_dataset(n, data=v, maxshape=(None,) + v.shape[1:], chunks=True)
    dst.swmr_mode = True
    dst.flush()
    print("ready", flush=True)
    sys.stdin.read()
"""


def run(args):
    return subprocess.run([sys.executable, SCRIPT] + args, capture_output=True, text=True)


def close(got, want):
    return abs(float(got) - want) <= 1e-12 * max(abs(want), 1e-300)


def check_pass(r, want):
    """r: a CSV row; want: column -> value (floats compared at 1e-12, the rest as text)."""
    for k, v in want.items():
        if isinstance(v, float):
            assert close(r[k], v), (k, v, r)
        else:
            assert r[k] == str(v), (k, v, r)


def main():
    with test_dir("plot_bonds") as tmp:
        full, cut, loose = (os.path.join(tmp, n + ".h5") for n in ("full", "cut", "loose"))
        write_run(full)
        write_run(cut, cut_step=158)
        write_unbonded(loose)
        empty = os.path.join(tmp, "empty.h5")  # a run with no row yet
        with h5py.File(empty, "w") as f:
            for k in ("time", "pass", "rho_path"):
                f["scoop/" + k] = np.zeros(0)
            f["scoop/force_scoop"] = np.zeros((0, 3))
        png, png_log, table = (os.path.join(tmp, n) for n in ("f.png", "f_log.png", "s.csv"))
        r = run([full, cut, loose, empty, "-o", png, "--csv", table, "--smooth", "3"])
        assert r.returncode == 0, r.stderr
        with open(png, "rb") as f:
            linear = f.read()
        with open(table) as f:
            got = {(row["run"], row["pass"]): row for row in csv.DictReader(f)}
        assert sorted(got) == [("cut", "1"), ("cut", "2"), ("full", "1"), ("full", "2"),
                               ("loose", "1")], sorted(got)
        pass1 = {"mean_F_N": 165 / 17, "peak_F_N": 13.0, "mean_Fz_scoop_N": 22 / 17,
                 "broken_tension": 2, "broken_shear": 3, "intact_at_end": 995,
                 "collected_kg": 0.01, "rho_end_m": 0.032, "complete": 1}
        check_pass(got[("full", "1")], pass1)
        check_pass(got[("full", "2")], {
            "mean_F_N": 100 * 160 / 16, "peak_F_N": 1300.0, "mean_Fz_scoop_N": 100 * 26 / 16,
            "broken_tension": 2, "broken_shear": 1, "intact_at_end": 992, "collected_kg": 0.02,
            "rho_end_m": 0.030, "complete": 1})
        check_pass(got[("cut", "1")], pass1)
        check_pass(got[("cut", "2")], {
            "broken_tension": 2, "broken_shear": 0, "intact_at_end": 993, "collected_kg": "",
            "rho_end_m": 0.016, "complete": 0})
        # The cut run read while a writer holds it (SWMR), as a run in progress.
        live = os.path.join(tmp, "live.h5")
        writer = subprocess.Popen([sys.executable, "-c", SWMR_WRITER, cut, live],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            assert writer.stdout.readline().strip() == "ready"
            r = run([live, "-o", png, "--csv", table, "--smooth", "3"])
        finally:
            writer.stdin.close()
            writer.wait()
        assert r.returncode == 0, r.stderr
        with open(table) as f:
            live_rows = {row["pass"]: row for row in csv.DictReader(f)}
        assert sorted(live_rows) == ["1", "2"], live_rows
        for p in ("1", "2"):
            assert {k: v for k, v in live_rows[p].items() if k != "run"} == {
                k: v for k, v in got[("cut", p)].items() if k != "run"}, (live_rows[p],
                                                                           got[("cut", p)])
        check_pass(got[("loose", "1")], {
            "mean_F_N": 0.5, "peak_F_N": 0.5, "mean_Fz_scoop_N": 0.4, "broken_tension": 0,
            "broken_shear": 0, "intact_at_end": "", "collected_kg": 0.005, "complete": 1})

        # A run with no row yet, alone: the CSV's header.
        r = run([empty, "-o", png_log, "--csv", table])
        assert r.returncode == 0, r.stderr
        with open(table) as f:
            assert f.read().strip() == ",".join(COLUMNS), "expected the header alone"

        # The PNG, linear and log: written, non-empty, and not the same picture.
        r = run([full, cut, loose, "-o", png_log, "--smooth", "3", "--log"])
        assert r.returncode == 0, r.stderr
        with open(png_log, "rb") as f:
            logged = f.read()
        for data in (linear, logged):
            assert data.startswith(b"\x89PNG") and len(data) > 1000, len(data)
        assert linear != logged, "--log drew the same picture as the linear axis"

        # The figure's lines: the breaks' rho and the |F| axis, linear and log.
        spec = importlib.util.spec_from_file_location("plot_bonds", SCRIPT)
        tool = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(tool)
        runs = [tool.read_run(full)]
        for log, floor in ((False, 0.0), (True, 1e-3)):
            fig = tool.draw(runs, ["full"], 1, log)
            ax_f, ax_b = fig.axes
            assert ax_f.get_yscale() == ("log" if log else "linear"), (log, ax_f.get_yscale())
            values = np.concatenate([line.get_ydata() for line in ax_f.get_lines()])
            assert values.min() == floor and values.max() == 1300.0, (log, values.min(),
                                                                      values.max())
            drawn = [list(line.get_xdata()) for line in ax_b.get_lines()]
            for got_x, want_x in zip(drawn, ([0, 10, 12, 32, 32], [0, 14, 30])):
                assert len(got_x) == len(want_x) and all(
                    abs(g - w) <= 1e-9 for g, w in zip(got_x, want_x)), (drawn, want_x)
            assert len(drawn) == 2, drawn

        # Bad input: exit 2, one line naming what is wrong.
        no_time = os.path.join(tmp, "no_time.h5")
        with h5py.File(no_time, "w") as f:
            f["scoop/pass"] = np.ones(3)
        missing = os.path.join(tmp, "missing.h5")
        expect_refused(run, [
            ([missing, "-o", png], missing),
            ([no_time, "-o", png], "/scoop/time"),
            ([full, "-o", png, "--csv", os.path.join(tmp, "no", "s.csv")], "--csv"),
            ([empty, "-o", os.path.join(tmp, "no", "f.png")], "-o"),
            ([full, "-o", png, "--smooth", "4"], "--smooth"),
            ([full, "-o", png, "--smooth", "abc"], "--smooth"),
            ([full, loose, "-o", png, "--labels", "a"], "--labels"),
            ([full], "-o"),
        ])
    print("plot_bonds_test: passed")


if __name__ == "__main__":
    main()
