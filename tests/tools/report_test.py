#!/usr/bin/python3
"""tools/report.sh and tools/report.py on a results folder of small fixtures written here (no
DEM): a shape study's HDF5 (two templates, their /table and /scoop rows; report.sh draws its
Fig. 8 PNG), a size study's CSV with `# verdict: largest_within_20pct_mm=4` and three PNGs, a
Balovnev CSV and PNG, a testbed summary and PNG, a synthetic wrench table (plot_lookup_test's;
report.sh draws the lookup figures and trends) and lookup/coarse_vs_fine.csv
(tools/compare_tables.py on compare_tables_test's synthetic tables and size study). Checks:
  - the page lists 9 figures and embeds each as a data URI whose bytes are the file's; every src
    is a data URI (nothing fetched);
  - the shape table's numbers, the size verdicts against the study's 3.5 mm (4 mm: coarser; with
    the spread 2 mm: finer; the 20% crossing, 4 + (20 - 10) / (50 - 10) x 6 = 5.5 mm: coarser)
    and the command the CSV records (its scene), the
    Balovnev table's last row (the mean over the rows that cut: dem_horizontal = time, cut for
    time in [0.2, 0.8) at 0.02 s -> mean 0.49 exactly) and 10 span rows, the lookup ratio (10);
  - the coarse-against-fine section: the prediction (5 / 1.75 = 2.857, 0.5 / 0.25 = 2), the
    per-material medians (snow mean |F| 1.938 (1.375 .. 2.5)), the cell rows (snow 5 mm pass 1:
    4 nodes, peak |F| 2.5 against 2.857, mean |F| 1.375; ice 15 mm pass 2's prediction marked a
    reference; ice 3 mm pass 1 coarse_only) and the command its CSV records;
  - headless Chromium loads the page and every <img> has naturalWidth > 0 (an inline script added
    to a copy of the page marks each image); skipped (exit 77) when chromium is not installed
    (tools/install-deps.sh --test installs it);
  - report.sh run again redraws nothing and writes the same page;
  - a folder with nothing: every section (6) "Not run: <its command>", exit 0; with the lookup
    sweep's table alone, only tools/plot_lookup.py is "not run";
  - the command shown: DIR/commands.txt's (shape), the one the files record (size), else the
    layout's (lookup), each said;
  - an input that exists but is unreadable (shape.h5 not HDF5, a PNG that is not one, a CSV
    without its columns, coarse_vs_fine.csv without its columns, a commands.txt line without a
    known key): one line on stderr naming it, exit 2."""

import base64
import os
import re
import shutil
import struct
import subprocess
import sys
import zlib

import h5py
import numpy as np

from cli_check import expect_refused, test_dir
import compare_tables_test
import plot_lookup_test

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
REPORT = os.path.join(ROOT, "tools", "report.py")
COMPARE = os.path.join(ROOT, "tools", "compare_tables.py")
WRAPPER = os.path.join(ROOT, "tools", "report.sh")
# report.sh runs the scripts under $SCOOPSIM_PYTHON, else python3 on PATH: this Python, which has
# numpy, h5py and matplotlib (a python3 first on PATH may lack them).
WRAPPER_ENV = dict(os.environ, SCOOPSIM_PYTHON=sys.executable)
BALOVNEV_COLUMNS = ("time", "pass", "rho", "tip_x", "tip_y", "tip_z", "surface", "depth",
                    "dem_horizontal", "dem_down", "balovnev_horizontal", "balovnev_vertical",
                    "plugin_horizontal", "plugin_vertical")
FIGURES = ("shape/shape_force.png", "size/size_force.png", "size/size_stack.png",
           "size/size_mpe.png", "balovnev/dig.balovnev.png", "testbed/testbed_sand.png",
           "lookup/lookup_fig9.png", "lookup/lookup_fig10.png", "lookup/lookup_fig11.png")


def write_png(path, w=6, h=4):
    """A small valid RGB PNG."""
    raw = b"".join(b"\x00" + b"\x80\x40\x20" * w for _ in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def write_shape(path):
    with h5py.File(path, "w") as f:
        f.attrs["study"] = "shape"
        f.attrs["templates"] = "tetra1,tetra4"
        # A level push with the scoop buried, as scenes/shape_study_small.yaml: no preset.
        f.attrs["scene_yaml"] = ("dig:\n  trajectory:\n    preset: none\n"
                                 "  start_buried: true\n")
        n = 50
        for k, t in enumerate(("tetra1", "tetra4")):
            g = f.create_group(t)
            g.attrs["spheres_per_clump"] = 1 + 3 * k
            g["scoop/time"] = np.arange(n) * 0.01
            g["scoop/pass"] = np.ones(n)
            g["scoop/rho"] = np.arange(n) * 1e-3
            g["scoop/force_body"] = np.tile([0.0, -1.0 - k, 0.5], (n, 1))
            g["scoop/torque_body"] = np.tile([0.1, 0.0, 0.0], (n, 1))
        f["table/spheres_per_clump"] = np.array([1, 4], dtype=np.int32)
        f["table/clumps"] = np.array([1000, 1000], dtype=np.int64)
        f["table/dig_cpu_s"] = np.array([12.5, 40.5])
        f["table/peak_force"] = np.array([1.118, 2.062])


def write_size(d):
    with open(os.path.join(d, "size_study.csv"), "w") as f:
        f.write("# scoopsim study particle-size scenes/paper/size_S2.yaml (scoopsim 0.1.0): paper "
                "section 4, eq. 5-7\n# verdict: largest_within_20pct_mm=4\n"
                "# verdict_spread: largest_within_20pct_all_beds_mm=2\n"
                "# crossing: mpe_20pct_mm=5.5 (force 5.5, torque 5.5): where |mpe| reaches 20\n"
                "# prior: sizes_mm=10 from old/size_study.csv (its rows: peaks, beds, cost)\n"
                "size_mm,beds,peak_force_mean,peak_force_min,peak_force_max,mpe_force_pct,"
                "mpe_force_min_pct,mpe_force_max_pct,peak_torque_mean,peak_torque_min,"
                "peak_torque_max,mpe_torque_pct,mpe_torque_min_pct,mpe_torque_max_pct,within_20,"
                "cpu_s_mean\n"
                "2,2,10,9,11,0,-5,5,1,0.9,1.1,0,-4,4,1,100\n"
                "4,2,11,10,12,10,0,20,1.1,1,1.2,10,0,20,1,50\n"
                "10,2,15,14,16,50,40,60,1.5,1.4,1.6,50,40,60,0,10\n")
    for name in ("size_force.png", "size_stack.png", "size_mpe.png"):
        write_png(os.path.join(d, name))


def write_balovnev(d):
    t = np.arange(50) * 0.02
    depth = np.where((t >= 0.2 - 1e-12) & (t < 0.8 - 1e-12), 0.01, 0.0)
    cols = {c: np.zeros_like(t) for c in BALOVNEV_COLUMNS}
    cols.update(time=t, depth=depth, dem_horizontal=t, rho=t * 0.1)
    cols["pass"] = np.ones_like(t)
    with open(os.path.join(d, "dig.balovnev.csv"), "w") as f:
        f.write("# rho_bulk 500 kg/m^3\n" + ",".join(BALOVNEV_COLUMNS) + "\n")
        for k in range(t.size):
            f.write(",".join(repr(float(cols[c][k])) for c in BALOVNEV_COLUMNS) + "\n")
    write_png(os.path.join(d, "dig.balovnev.png"))


def write_testbed(d):
    with open(os.path.join(d, "summary.csv"), "w") as f:
        f.write("component,beds,first10_mean_N,first10_sd_N,rest_mean_N,rest_sd_N,"
                "slope_mean_N_per_m,slope_sd_N_per_m\nFX,5,0.1,0.01,0.2,0.02,1,0.1\n"
                "FY,5,-3,0.3,-4.2,0.5,-100,10\nFZ,5,-2,0.1,-2,0.1,0,1\n")
    with open(os.path.join(d, "times.txt"), "w") as f:
        f.write("seed1 cpu_s 90.0 wall_s 95.0\n")
    write_png(os.path.join(d, "testbed_sand.png"))


def write_coarse_vs_fine(d, tmp):
    """DIR/lookup/coarse_vs_fine.csv: compare_tables.py on compare_tables_test's tables."""
    coarse, fine = compare_tables_test.cells()
    paths = [os.path.join(tmp, n) for n in ("coarse.csv", "fine.csv", "size.csv")]
    compare_tables_test.write_csv(paths[0], coarse)
    compare_tables_test.write_csv(paths[1], fine)
    compare_tables_test.write_size_study(paths[2])
    r = subprocess.run([sys.executable, COMPARE, paths[0], paths[1], "--size-study", paths[2],
                        "--csv", os.path.join(d, "coarse_vs_fine.csv")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def make_results(root):
    for sub in ("shape", "size", "balovnev", "testbed", "lookup"):
        os.makedirs(os.path.join(root, sub))
    write_shape(os.path.join(root, "shape", "shape.h5"))
    write_size(os.path.join(root, "size"))
    write_balovnev(os.path.join(root, "balovnev"))
    write_testbed(os.path.join(root, "testbed"))
    plot_lookup_test.write_table(os.path.join(root, "lookup", "table.h5"))
    write_coarse_vs_fine(os.path.join(root, "lookup"), os.path.dirname(root))
    with open(os.path.join(root, "commands.txt"), "w") as f:
        f.write("# what was run\nshape: build/scoopsim study shape scenes/shape_study_small.yaml "
                "-o results/shape/shape.h5\n")


def check_embedded(page, root):
    listed = re.findall(r"<li>\w+: ([^<]+)</li>", page)
    assert sorted(listed) == sorted(FIGURES), listed
    for rel in FIGURES:
        m = re.search(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)" alt="[^"]*" '
                      r'data-file="%s">' % re.escape(rel), page)
        assert m, rel
        with open(os.path.join(root, rel), "rb") as f:
            assert base64.b64decode(m.group(1)) == f.read(), rel
    srcs = re.findall(r'src="([^"]{0,12})', page)
    assert srcs and all(s.startswith("data:") for s in srcs), srcs
    assert "http:" not in page and "https:" not in page and "<link" not in page


def check_chromium(page_path, tmp):
    """Loads the page in headless Chromium: each image's naturalWidth, or None without it."""
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if not browser:
        return None
    probe = os.path.join(tmp, "probe.html")
    script = ("<script>window.addEventListener('load', () => { for (const i of document.images) "
              "i.setAttribute('data-natural-width', i.naturalWidth); "
              "document.body.setAttribute('data-probed', document.images.length); });</script>")
    with open(page_path, encoding="utf-8") as f:
        page = f.read()
    with open(probe, "w", encoding="utf-8") as f:
        f.write(page.replace("</body>", script + "</body>"))
    r = subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu",
                        "--user-data-dir=" + os.path.join(tmp, "chromium-profile"),
                        "--virtual-time-budget=5000", "--dump-dom", "file://" + probe],
                       capture_output=True, text=True, timeout=90)
    assert r.returncode == 0, r.stderr[-2000:]
    assert re.search(r'data-probed="%d"' % len(FIGURES), r.stdout), "the probe did not run"
    widths = {}  # data-file -> naturalWidth (-1: not marked)
    for tag in re.findall(r"<img [^>]*>", r.stdout):
        rel = re.search(r'data-file="([^"]+)"', tag).group(1)
        width = re.search(r'data-natural-width="(\d+)"', tag)
        widths[rel] = int(width.group(1)) if width else -1
    return widths


def main():
    with test_dir("report") as tmp:
        root = os.path.join(tmp, "results")
        make_results(root)
        page_path = os.path.join(tmp, "report.html")
        r = subprocess.run(["bash", WRAPPER, root, page_path], capture_output=True, text=True,
                           env=WRAPPER_ENV)
        assert r.returncode == 0, r.stdout + r.stderr
        assert "9 figures" in r.stdout and "not run: none" in r.stdout, r.stdout
        with open(page_path, encoding="utf-8") as f:
            page = f.read()
        check_embedded(page, root)
        shape_row = ("<tr><td>tetra4</td><td>4</td><td>1000</td><td>40.5</td><td>2.062</td>"
                     "<td>2.3</td>")
        assert shape_row in page.replace(' class="l"', ""), "the shape table"
        shape = page[page.index('id="shape"'):page.index('id="size"')]
        # The section names the scene's own dig, not the Table 1 dig it did not run.
        assert "The scene&#x27;s dig (the scoop starts buried, no preset trajectory)" in shape \
            and "Table 1" not in shape, shape
        assert ("Made by (commands.txt):</p><pre>build/scoopsim study shape "
                "scenes/shape_study_small.yaml -o results/shape/shape.h5</pre>") in shape, shape
        lookup = page[page.index('id="lookup"'):page.index('id="coarse_vs_fine"')]
        assert "Made by (the layout&#x27;s command: " in lookup, lookup[:400]
        size = page[page.index('id="size"'):page.index('id="balovnev"')]
        assert "largest_within_20pct_mm=4 &mdash; 4 mm, coarser than the study" in size, size
        assert "all_beds_mm=2 &mdash; 2 mm, finer than the study" in size, size
        assert "mpe_20pct_mm=5.5 (force 5.5" in size and "5.5 mm, coarser than the study" in \
            size, size
        assert "<pre>build/scoopsim study particle-size scenes/paper/size_S2.yaml -o " + \
            os.path.join(root, "size") + " --prior old/size_study.csv</pre>" in size, \
            "the recorded command, with the earlier run's rows it took"
        assert "Made by (as its files record)" in size
        bal = page[page.index('id="balovnev"'):page.index('id="testbed"')]
        rows = re.findall(r"<tr>(.*?)</tr>", bal)
        assert len(rows) == 1 + 10 + 1, len(rows)
        cells = re.findall(r"<td[^>]*>([^<]*)</td>", rows[-1])
        assert cells[0] == "mean, rows cut" and cells[3] == "0.49", cells
        assert "mean_F_ratio_geomean" in page
        assert "The table (lookup/table.h5): snow; ice; bite depths 3, 5, 9, 15 mm; passes 1, 2, " \
            "3." in page
        cvf = page[page.index('id="coarse_vs_fine"'):].replace(' class="l"', "")
        assert "Made by (as its files record):</p><pre>tools/compare_tables.py %s " % \
            os.path.join(tmp, "coarse.csv") in cvf, cvf[:600]
        assert "peak |F| ratio 2.857, peak |T| ratio 2</div>" in cvf, cvf
        assert "<tr><td>snow</td><td>2</td><td>1.938 (1.375 .. 2.5)</td><td>2.5 (2.5 .. 2.5)" \
            "</td><td>2 (2 .. 2)</td><td>2 (2 .. 2)</td></tr>" in cvf, cvf
        assert ("<tr><td>snow</td><td>5</td><td>1</td><td>both</td><td>4</td><td>10</td>"
                "<td>7</td><td>2.5</td><td>2.857</td><td>2</td><td>2</td><td>1.375</td>"
                "<td>2</td></tr>") in cvf, cvf
        assert "<td>ice</td><td>15</td><td>2</td><td>both</td><td>11</td><td>20</td><td>20</td>" \
            "<td>2.5</td><td>2.857 (ref.)</td>" in cvf, cvf
        assert "<td>ice</td><td>3</td><td>1</td><td>coarse_only</td><td>0</td><td>4</td>" \
            "<td>-</td><td>-</td>" in cvf, cvf

        # Again: nothing is redrawn (the figures are newer than their inputs), the same page.
        mtime = os.path.getmtime(os.path.join(root, "lookup", "lookup_fig9.png"))
        r = subprocess.run(["bash", WRAPPER, root, page_path], capture_output=True, text=True,
                           env=WRAPPER_ENV)
        assert r.returncode == 0 and "plot_lookup" not in r.stdout + r.stderr, r.stdout + r.stderr
        assert os.path.getmtime(os.path.join(root, "lookup", "lookup_fig9.png")) == mtime
        with open(page_path, encoding="utf-8") as f:
            check_embedded(f.read(), root)

        widths = check_chromium(page_path, tmp)
        if widths is not None:
            assert sorted(widths) == sorted(FIGURES), widths
            assert all(w > 0 for w in widths.values()), widths

        # Nothing run: every section says how to make it.
        empty = os.path.join(tmp, "empty")
        os.makedirs(empty)
        r = subprocess.run([sys.executable, REPORT, empty], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        with open(os.path.join(empty, "report.html"), encoding="utf-8") as f:
            blank = f.read()
        assert blank.count('class="notrun">Not run: ') == 6, blank
        assert ("Not run: build/scoopsim sweep scenes/sweeps/lookup.yaml -o %s/lookup_fine "
                "&amp;&amp; tools/compare_tables.py assets/lookup_coarse.csv "
                "%s/lookup_fine/table.h5 "
                % (empty, empty)) in blank, blank
        assert "Not run: build/scoopsim study shape scenes/paper/shape_study.yaml -o " + empty + \
            "/shape/shape.h5" in blank
        # The lookup sweep done but not drawn: only the drawing is not run.
        os.makedirs(os.path.join(empty, "lookup"))
        shutil.copy(os.path.join(root, "lookup", "table.h5"), os.path.join(empty, "lookup"))
        r = subprocess.run([sys.executable, REPORT, empty], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        with open(os.path.join(empty, "report.html"), encoding="utf-8") as f:
            blank = f.read()
        assert ('class="notrun">Not run: tools/plot_lookup.py %s/lookup/table.h5 -o %s/lookup<'
                % (empty, empty)) in blank, blank

        # Unreadable inputs.
        run = lambda args: subprocess.run([sys.executable, REPORT] + args, capture_output=True,
                                          text=True)
        bad_h5 = os.path.join(tmp, "bad_h5")
        os.makedirs(os.path.join(bad_h5, "shape"))
        with open(os.path.join(bad_h5, "shape", "shape.h5"), "w") as f:
            f.write("not hdf5\n")
        bad_png = os.path.join(tmp, "bad_png")
        os.makedirs(os.path.join(bad_png, "testbed"))
        shutil.copy(os.path.join(root, "testbed", "summary.csv"), os.path.join(bad_png, "testbed"))
        with open(os.path.join(bad_png, "testbed", "testbed_sand.png"), "w") as f:
            f.write("not a png\n")
        bad_csv = os.path.join(tmp, "bad_csv")
        os.makedirs(os.path.join(bad_csv, "size"))
        with open(os.path.join(bad_csv, "size", "size_study.csv"), "w") as f:
            f.write("size_mm,beds\n2,1\n")
        bad_cvf = os.path.join(tmp, "bad_cvf")
        os.makedirs(os.path.join(bad_cvf, "lookup"))
        with open(os.path.join(bad_cvf, "lookup", "coarse_vs_fine.csv"), "w") as f:
            f.write("# tools/compare_tables.py a b\nmaterial,bite_depth_mm,pass\nsnow,5,1\n")
        bad_commands = os.path.join(tmp, "bad_commands")
        os.makedirs(bad_commands)
        with open(os.path.join(bad_commands, "commands.txt"), "w") as f:
            f.write("shape: ok\nshpae: a typo\n")
        expect_refused(run, (([bad_commands], "commands.txt:2: expected `KEY: COMMAND`"),
                             ([bad_h5], "shape.h5"), ([bad_png], "testbed_sand.png"),
                             ([bad_csv], "missing column peak_force_mean"),
                             ([bad_cvf], "coarse_vs_fine.csv: missing column material_id"),
                             ([os.path.join(tmp, "none")], "none: no such folder")))
    if widths is None:
        print("report_test: SKIPPED the Chromium check (no chromium: tools/install-deps.sh --test "
              "installs it); every other check passed")
        return 77
    print("report_test: 9 figures embedded and rendered by headless Chromium, empty folder -> 6 "
          "'not run' sections, 6 bad inputs refused")
    return 0


if __name__ == "__main__":
    sys.exit(main())
