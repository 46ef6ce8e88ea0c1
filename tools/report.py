#!/usr/bin/env python3
"""One self-contained HTML page of the study's analyses (paper section 4) from a results folder.

    tools/report.py DIR [-o REPORT.html]        (default DIR/report.html)

The page has no outside references: the figures are embedded (base64 data URIs), the style is
inline, nothing is fetched. Each section shows the command that makes its files; a section whose
files are missing says "not run" with that command; a file that exists but cannot be read (not
HDF5, not the expected CSV, not a PNG) stops the report: one line on stderr, exit 2.

DIR's layout (tools/report.sh makes the figures that come from other files, then the page):
  DIR/shape/shape.h5         scoopsim study shape (its /table: one row per clump template)
  DIR/shape/shape_force.png  tools/plot_wrench.py DIR/shape/shape.h5 --force-only (Fig. 8)
  DIR/size/                  scoopsim study particle-size SCENE -o DIR/size: size_study.csv
                             ('#' lines, `# verdict: largest_within_20pct_mm=<d>`, one row a
                             size), size_force.png, size_stack.png, size_mpe.png (Fig. 3, 4, 6)
  DIR/balovnev/dig.h5        scoopsim study balovnev SCENE -o DIR/balovnev/dig.h5: its
                             dig.balovnev.csv (the table: ten spans of the rows that cut, as the
                             study prints it) and dig.balovnev.png
  DIR/testbed/               tools/testbed_sand.sh DIR/testbed: testbed_sand.png (Fig. 13),
                             summary.csv, times.txt, seed1.balovnev.png (shown when there)
  DIR/lookup/                the lookup set's sweep folder (scoopsim sweep ... -o DIR/lookup:
                             table.h5, cases/), and tools/plot_lookup.py's lookup_fig9.png,
                             lookup_fig10.png, lookup_fig11.png, lookup_trends.csv
  DIR/lookup/coarse_vs_fine.csv  tools/compare_tables.py COARSE FINE --csv ...: the coarse
                             lookup table against the paper-resolution one, one row a cell
                             (issue 39; its first '#' line records the command)
  DIR/commands.txt           optional: lines `KEY: COMMAND` (KEY shape, size, balovnev, testbed,
                             lookup or coarse_vs_fine; several lines a key allowed) shown as
                             the section's command, e.g. the scene actually used
A section's command: DIR/commands.txt's, else the one its files record (size_study.csv's and
the Balovnev CSV's first '#' line name the scene), else the layout's default above.
Exit status: 0 written (sections not run included); 2 bad input. Needs python3-numpy and
python3-h5py.
"""

import argparse
import base64
import csv
import datetime
import html
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from study_csv import STUDY_SIZE_MM  # noqa: E402  (after the path it is found on)

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
STUDY_SHAPE_HOURS = {"tetra1": 2.25, "tetra4": 2.3, "tetra8": 5, "tetra12": 33}  # its Table 3

# The default command of each section (DIR stands for the results folder).
COMMANDS = {
    "shape": ["build/scoopsim study shape scenes/paper/shape_study.yaml -o DIR/shape/shape.h5 "
              "--beds DIR/shape/beds",
              "tools/plot_wrench.py DIR/shape/shape.h5 --force-only -o DIR/shape/shape_force.png"],
    "size": ["build/scoopsim study particle-size scenes/paper/size_S10.yaml -o DIR/size"],
    "balovnev": ["build/scoopsim study balovnev scenes/tiny_dig.yaml -o DIR/balovnev/dig.h5"],
    "testbed": ["tools/testbed_sand.sh DIR/testbed"],
    "lookup": ["build/scoopsim sweep scenes/sweeps/lookup_coarse.yaml -o DIR/lookup",
               "tools/plot_lookup.py DIR/lookup/table.h5 -o DIR/lookup"],
    # The paper-resolution table (scenes/sweeps/lookup.yaml: its beds first, docs/studies.md)
    # against the coarse one shipped in assets/.
    "coarse_vs_fine": ["build/scoopsim sweep scenes/sweeps/lookup.yaml -o DIR/lookup_fine",
                       "tools/compare_tables.py assets/lookup_coarse.csv DIR/lookup_fine/table.h5 "
                       "--size-study bench/results/vm/size_study_20_2026-12-05.csv "
                       "--csv DIR/lookup/coarse_vs_fine.csv --md DIR/lookup/coarse_vs_fine.md"],
}

STYLE = """
body { font-family: sans-serif; max-width: 1200px; margin: 1em auto; padding: 0 1em; color: #222; }
h1 { font-size: 1.6em; }
h2 { border-bottom: 1px solid #bbb; padding-bottom: .2em; margin-top: 2em; }
table { border-collapse: collapse; margin: .6em 0; font-size: .9em; }
th, td { border: 1px solid #ccc; padding: .25em .5em; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
pre { background: #f6f6f6; padding: .5em; overflow-x: auto; font-size: .85em; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .85em; color: #555; }
.notrun { background: #fff4e0; border-left: 4px solid #e0a030; padding: .5em 1em; }
.verdict { background: #eef6ee; border-left: 4px solid #4a4; padding: .5em 1em; }
.missing { color: #a40; }
"""


class InputError(Exception):
    """Bad input: the message is the one line to print."""


def esc(v):
    return html.escape(str(v))


def table(header, rows, left=(0,)):
    """An HTML table; the columns in `left` (indices) aligned left, the others right."""
    cls = lambda k: ' class="l"' if k in left else ""
    out = ["<table><tr>" + "".join("<th%s>%s</th>" % (cls(k), esc(h))
                                   for k, h in enumerate(header)) + "</tr>"]
    for row in rows:
        out.append("<tr>" + "".join("<td%s>%s</td>" % (cls(k), esc(v))
                                    for k, v in enumerate(row)) + "</tr>")
    return "\n".join(out) + "</table>"


def num(v, digits=4):
    """A number in `digits` significant digits; anything else as it is."""
    try:
        f = float(v)
    except (TypeError, ValueError):
        return str(v)
    return "%.*g" % (digits, f) if np.isfinite(f) else str(v)


class Report:
    """The page being built: its sections and the figures embedded in them."""

    def __init__(self, root, commands):
        self.root = root
        self.commands = commands
        self.recorded = {}  # {key: [command]}: what the section's own files say made them
        self.sections = []  # (key, title, status, html)
        self.figures = []   # (section key, file path relative to root, caption)

    def path(self, *parts):
        return os.path.join(self.root, *parts)

    def command_lines(self, key):
        """(lines, where from): DIR/commands.txt's lines for `key`, else what its files record,
        else the layout's default."""
        if key in self.commands:
            return self.commands[key], "commands.txt"
        if key in self.recorded:
            return self.recorded[key], "as its files record"
        return ([c.replace("DIR", self.root) for c in COMMANDS[key]],
                "the layout's command: the files do not say which scene, commands.txt can")

    def figure(self, key, rel, caption):
        """An embedded PNG, or a visible note when the file is missing."""
        path = self.path(rel)
        if not os.path.isfile(path):
            return '<p class="missing">Figure missing: %s</p>' % esc(rel)
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError as e:
            raise InputError("%s: cannot read (%s)" % (path, e.strerror))
        if not data.startswith(PNG_MAGIC):
            raise InputError("%s: not a PNG file" % path)
        self.figures.append((key, rel, caption))
        return ('<figure><img src="data:image/png;base64,%s" alt="%s" data-file="%s">'
                "<figcaption>%s (%s)</figcaption></figure>"
                % (base64.b64encode(data).decode("ascii"), esc(caption), esc(rel), esc(caption),
                   esc(rel)))

    def add(self, key, title, body):
        """A section: body is its HTML, or None when it was not run."""
        if body is None:
            status = "not run"
            body = '<div class="notrun">Not run: %s</div>' % esc(" && ".join(
                self.command_lines(key)[0]))
        else:
            status = "shown"
            lines, source = self.command_lines(key)
            body = "<p>Made by (%s):</p><pre>%s</pre>%s" % (esc(source), esc("\n".join(lines)),
                                                            body)
        self.sections.append((key, title, status, body))

    def html(self):
        toc = table(("section", "status"),
                    [(title, status) for _, title, status, _ in self.sections])
        figs = "<ul>%s</ul>" % "".join("<li>%s: %s</li>" % (esc(k), esc(rel))
                                       for k, rel, _ in self.figures) if self.figures else \
            "<p>none</p>"
        parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
                 "<title>scoopsim: the study's analyses</title>", "<style>%s</style>" % STYLE,
                 "</head><body>",
                 "<h1>scoopsim: the study's analyses (paper section 4)</h1>",
                 "<p>Results folder %s; made %s by tools/report.py.</p>" % (
                     esc(os.path.abspath(self.root)),
                     datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")),
                 toc, "<p>Figures on this page (%d):</p>%s" % (len(self.figures), figs)]
        for key, title, _, body in self.sections:
            parts.append('<h2 id="%s">%s</h2>\n%s' % (esc(key), esc(title), body))
        parts.append("</body></html>")
        return "\n".join(parts) + "\n"


def read_commands(path):
    """{key: [command, ...]} from DIR/commands.txt, or {} without it."""
    out = {}
    if not os.path.isfile(path):
        return out
    try:
        lines = open(path).read().splitlines()
    except OSError as e:
        raise InputError("%s: cannot read (%s)" % (path, e.strerror))
    for k, line in enumerate(lines, 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        key, sep, command = line.partition(":")
        if not sep or key.strip() not in COMMANDS:
            raise InputError("%s:%d: expected `KEY: COMMAND` with KEY one of %s, got %r"
                             % (path, k, ", ".join(COMMANDS), line))
        out.setdefault(key.strip(), []).append(command.strip())
    return out


def read_csv(path, what):
    """('#' lines without the '#', [dict rows]) of a CSV with a header."""
    try:
        with open(path, newline="") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise InputError("%s: cannot read (%s)" % (path, e.strerror))
    notes = [l[1:].strip() for l in lines if l.startswith("#")]
    body = [l for l in lines if l.strip() and not l.startswith("#")]
    if not body:
        raise InputError("%s: no header line (expected %s)" % (path, what))
    return notes, list(csv.DictReader(body))


def need_columns(path, rows, columns):
    if not rows:
        raise InputError("%s: no rows" % path)
    missing = [c for c in columns if c not in rows[0]]
    if missing:
        raise InputError("%s: missing column %s" % (path, ", ".join(missing)))


def h5_text(value):
    """An HDF5 string (attribute or dataset element) as str: h5py gives bytes or str."""
    return value.decode() if isinstance(value, bytes) else str(value)


# The sections. Each returns its body's HTML, or None when its files are missing.

def dig_phrase(scene_text):
    """What the study's scene digs, from its trajectory preset (sim/input/scene.cpp: table1, table4 or
    none), for a sentence's start."""
    m = re.search(r"\bpreset:\s*([A-Za-z0-9_]+)", scene_text)
    preset = m.group(1) if m else ""
    if preset == "table1":
        return "The Table 1 dig"
    if preset == "table4":
        return "The Table 4 pass"
    if "start_buried: true" in scene_text:
        return "The scene's dig (the scoop starts buried, no preset trajectory)"
    return "The scene's dig (its own trajectory, no preset)"


def shape_section(rep):
    path = rep.path("shape", "shape.h5")
    if not os.path.isfile(path):
        return None
    import h5py
    try:
        with h5py.File(path, "r") as f:
            if "table" not in f:
                raise InputError("%s: missing group /table (expected `scoopsim study shape`'s "
                                 "output)" % path)
            columns = {k: np.asarray(f["table"][k][()]) for k in f["table"]}
            templates = str(f.attrs.get("templates", "")).split(",")
            scene_text = h5_text(f.attrs.get("scene_yaml", ""))
    except OSError as e:
        raise InputError("%s: cannot open as HDF5 (%s)" % (path, e))
    # /table's columns as `study shape` prints them: header, format.
    shown = {"spheres_per_clump": ("spheres/clump", "%d"), "clumps": ("clumps", "%d"),
             "spheres": ("spheres", "%d"), "time_step": ("dt [s]", "%.3g"),
             "bed_wall_s": ("bed wall [s]", "%.1f"), "dig_wall_s": ("dig wall [s]", "%.1f"),
             "dig_cpu_s": ("dig CPU [s]", "%.1f"), "peak_force": ("peak |F| [N]", "%.4g"),
             "mean_force": ("mean |F| [N]", "%.4g"),
             "peak_overlap": ("peak overlap [% of diameter]", "%.3g")}
    names = [c for c in shown if c in columns] + sorted(c for c in columns if c not in shown)
    n = max((len(v) for v in columns.values()), default=0)
    if any(len(columns[c]) != n for c in names):
        raise InputError("%s: the /table datasets differ in length" % path)
    cell = lambda c, v: (shown[c][1] % (100 * v if c == "peak_overlap" else v)
                         if c in shown and np.isfinite(v) else num(v))
    rows = []
    for k in range(n):
        t = templates[k] if k < len(templates) and templates[k] else "row %d" % k
        study = STUDY_SHAPE_HOURS.get(t)
        rows.append([t] + [cell(c, columns[c][k]) for c in names] +
                    ["%g" % study if study is not None else "-"])
    body = ("<p>%s once per clump template, each on its own bed of the same solid "
            "volume (paper section 4, Table 3, Fig. 8). peak/mean force: |F| in the world frame, "
            "the mean after first contact; peak overlap: the deepest overlap over the dig's "
            "steps.</p>") % esc(dig_phrase(scene_text))
    body += table(["template"] + [shown[c][0] if c in shown else c for c in names] +
                  ["the study's time [h] (Table 3)"], rows)
    body += rep.figure("shape", os.path.join("shape", "shape_force.png"),
                       "|F| against rho per template (Fig. 8 analogue)")
    return body


def size_section(rep):
    path = rep.path("size", "size_study.csv")
    if not os.path.isfile(path):
        return None
    notes, rows = read_csv(path, "size_study.csv's columns")
    need_columns(path, rows, ("size_mm", "beds", "peak_force_mean", "mpe_force_pct",
                              "peak_torque_mean", "mpe_torque_pct", "within_20"))
    spread = lambda r, a, b, c: "%s (%s .. %s)" % (num(r.get(a)), num(r.get(b)), num(r.get(c)))
    body = ("<p>The Table 1 dig on beds of spheres of each diameter (eq. 5), the same bed volume; "
            "the maximum percent error of each size's peak against the finest (eq. 6) for force "
            "and torque, mean over beds (min .. max over beds); the largest size within 20% "
            "(eq. 7).</p>")
    made = [re.match(r"scoopsim study particle-size (\S+)", n) for n in notes]
    made = [m.group(1) for m in made if m]
    # `# prior: sizes_mm=<list> from <file> (...)`: rows an earlier run made (--prior).
    priors = [m.group(1) for m in (re.match(r"prior: sizes_mm=\S+ from (\S+)", n) for n in notes)
              if m]
    if made:
        rep.recorded["size"] = ["build/scoopsim study particle-size %s -o %s%s"
                                % (made[0], rep.path("size"),
                                   "".join(" --prior " + p for p in priors))]
    # `# verdict: largest_within_20pct_mm=<d>` (bed means) and `# verdict_spread:
    # largest_within_20pct_all_beds_mm=<d>` (every bed), each against the study's 3.5 mm.
    # `# crossing: mpe_20pct_mm=<d> (...)`: where |MPE| reaches 20% between the sizes run.
    verdicts = [n for n in notes if n.lower().startswith(("verdict", "crossing"))]
    for v in verdicts:
        m = re.search(r"(?:largest_within_20pct\w*|mpe_20pct)_mm\s*=\s*([^\s,;]+)", v)
        text = esc(v)
        try:
            d = float(m.group(1)) if m else float("nan")
        except ValueError:
            d = float("nan")
        if np.isfinite(d):
            cmp = ("coarser than" if d > STUDY_SIZE_MM else
                   "finer than" if d < STUDY_SIZE_MM else "the same as")
            text += " &mdash; %g mm, %s the study's %g mm" % (d, cmp, STUDY_SIZE_MM)
        else:
            text += " &mdash; the study: %g mm" % STUDY_SIZE_MM
        body += '<div class="verdict">%s</div>' % text
    if not verdicts:
        body += '<p class="missing">No `# verdict:` line in %s.</p>' % esc(path)
    body += table(("size [mm]", "beds", "peak |F| [N]", "MPE |F| [%]", "peak |T| [N m]",
                   "MPE |T| [%]", "within 20%", "CPU [s] a bed"),
                  [(num(r["size_mm"]), r["beds"],
                    spread(r, "peak_force_mean", "peak_force_min", "peak_force_max"),
                    spread(r, "mpe_force_pct", "mpe_force_min_pct", "mpe_force_max_pct"),
                    spread(r, "peak_torque_mean", "peak_torque_min", "peak_torque_max"),
                    spread(r, "mpe_torque_pct", "mpe_torque_min_pct", "mpe_torque_max_pct"),
                    r["within_20"], num(r.get("cpu_s_mean"))) for r in rows])
    others = [n for n in notes if n not in verdicts]
    if others:
        body += "<details><summary>The study's notes</summary><pre>%s</pre></details>" % esc(
            "\n".join(others))
    for name, caption in (("size_force.png", "|F| and |T| against rho per size (Fig. 3 analogue)"),
                          ("size_stack.png", "the sizes stacked (Fig. 4 analogue)"),
                          ("size_mpe.png", "MPE per size for force and torque (Fig. 6 analogue)")):
        body += rep.figure("size", os.path.join("size", name), caption)
    return body


def balovnev_spans(d, spans=10):
    """The table `study balovnev` prints: the rows from the first to the last with depth > 0 in
    `spans` equal spans of time, each the mean of its rows, then the mean over every row cut."""
    cut = np.flatnonzero(d["depth"] > 0)
    if cut.size == 0:
        return []
    first, last = cut[0], cut[-1]
    t = d["time"]
    u = (t[first:last + 1] - t[first]) / max(t[last] - t[first], 1e-300)
    at = np.minimum(spans - 1, (u * spans).astype(int))
    keys = ("rho", "depth", "dem_horizontal", "balovnev_horizontal", "plugin_horizontal",
            "dem_down", "balovnev_vertical", "plugin_vertical")
    mean = lambda rows, label: [label] + [
        "%.1f" % (1e3 * d[k][rows].mean()) if k in ("rho", "depth") else num(d[k][rows].mean(), 3)
        for k in keys]
    out = []
    for s in range(spans):
        rows = first + np.flatnonzero(at == s)
        if rows.size:
            out.append(mean(rows, "%.3f" % t[rows].mean()))
    out.append(mean(cut, "mean, rows cut"))
    return out


def balovnev_section(rep):
    path = rep.path("balovnev", "dig.balovnev.csv")
    if not os.path.isfile(path):
        return None
    import plot_balovnev
    try:
        d, notes = plot_balovnev.read(path)
    except ValueError as e:
        raise InputError(str(e))
    made = [re.match(r"scoopsim study balovnev: (\S+); dig (\S+)", n) for n in notes]
    made = [m for m in made if m]
    if made:
        rep.recorded["balovnev"] = ["build/scoopsim study balovnev %s -o %s"
                                    % (made[0].group(1), made[0].group(2))]
    rows = balovnev_spans(d)
    body = ("<p>The dig's horizontal force (against the motion) and vertical force (downward on "
            "the scoop) against Balovnev's model evaluated at the blade tip's depth below the "
            "bed's surface before the dig (FACTS.md section 7; 'plugin': the lander plugin's "
            "A_II everywhere). Ten equal spans of time over the rows where the blade cuts, each "
            "the mean of its rows, and the mean over every row cut.</p>")
    body += "<pre>%s</pre>" % esc("\n".join(notes)) if notes else ""
    if rows:
        body += table(("t [s]", "rho [mm]", "depth [mm]", "DEM F_h [N]", "Balovnev F_h [N]",
                       "plugin F_h [N]", "DEM F_v down [N]", "Balovnev F_v [N]",
                       "plugin F_v [N]"), rows)
    else:
        body += "<p>The blade never went below the surface.</p>"
    body += rep.figure("balovnev", os.path.join("balovnev", "dig.balovnev.png"),
                       "DEM against Balovnev: horizontal and vertical force, depth")
    return body


def testbed_section(rep):
    png, summary = rep.path("testbed", "testbed_sand.png"), rep.path("testbed", "summary.csv")
    if not os.path.isfile(png) and not os.path.isfile(summary):
        return None
    body = ("<p>The scoop buried 30 mm in sand and pushed at 0.01 m/s along the trench (paper "
            "Fig. 12-13): the three body-frame force components against the distance pushed, "
            "each bed, the mean over beds and its 95% band.</p>")
    if os.path.isfile(summary):
        _, rows = read_csv(summary, "plot_testbed.py's summary")
        cols = ("component", "beds", "first10_mean_N", "first10_sd_N", "rest_mean_N", "rest_sd_N",
                "slope_mean_N_per_m", "slope_sd_N_per_m")
        need_columns(summary, rows, cols)
        pm = lambda mean, sd: "%s \u00b1 %s" % (num(mean, 3), num(sd, 2))
        body += table(("component", "beds", "first 10% [N]", "rest: mean [N]",
                       "rest: slope [N/m]"),
                      [(r["component"], r["beds"],
                        pm(r["first10_mean_N"], r["first10_sd_N"]),
                        pm(r["rest_mean_N"], r["rest_sd_N"]),
                        pm(r["slope_mean_N_per_m"], r["slope_sd_N_per_m"])) for r in rows])
        body += "<p>Over beds: mean &plusmn; sd.</p>"
    else:
        body += '<p class="missing">Summary missing: testbed/summary.csv</p>'
    times = rep.path("testbed", "times.txt")
    if os.path.isfile(times):
        try:
            body += "<p>CPU and wall time:</p><pre>%s</pre>" % esc(open(times).read().strip())
        except OSError as e:
            raise InputError("%s: cannot read (%s)" % (times, e.strerror))
    body += rep.figure("testbed", os.path.join("testbed", "testbed_sand.png"),
                       "body-frame force against distance pushed, over beds (Fig. 13 analogue)")
    if os.path.isfile(rep.path("testbed", "seed1.balovnev.png")):  # testbed_sand.sh's first bed
        body += rep.figure("testbed", os.path.join("testbed", "seed1.balovnev.png"),
                           "the first bed's push against Balovnev's model (study balovnev)")
    return body


def lookup_table_summary(path):
    """What the wrench table holds (materials and their particles, bite depths, passes), or ""
    without it."""
    if not os.path.isfile(path):
        return ""
    import h5py
    try:
        with h5py.File(path, "r") as f:
            materials = [h5_text(v) for v in f["materials/name"][()]]
            sizes = [h5_text(v) for v in f["materials/particle_size"][()]] \
                if "materials/particle_size" in f else [""] * len(materials)
            depths = 1e3 * np.asarray(f["bite_depth"][()], dtype=float)
            passes = [int(v) for v in f["pass"][()]]
    except (OSError, KeyError) as e:
        raise InputError("%s: not a readable wrench table (%s)" % (path, e))
    return "<p>The table (lookup/table.h5): %s; bite depths %s mm; passes %s.</p>" % (
        esc("; ".join("%s (%s)" % (m, z) if z else m for m, z in zip(materials, sizes))),
        esc(", ".join("%g" % d for d in depths)), esc(", ".join(map(str, passes))))


def lookup_section(rep):
    trends = rep.path("lookup", "lookup_trends.csv")
    figs = [os.path.join("lookup", "lookup_fig%d.png" % k) for k in (9, 10, 11)]
    if not os.path.isfile(trends) and not any(os.path.isfile(rep.path(f)) for f in figs):
        if os.path.isfile(rep.path("lookup", "table.h5")):  # the sweep ran: only the figures not
            rep.recorded["lookup"] = [COMMANDS["lookup"][1].replace("DIR", rep.root)]
        return None
    body = ("<p>The lookup set (paper Table 4-5) from the wrench table: force and torque "
            "against rho (the scoop CoM's travel along the trench since first contact), the "
            "trajectory's segments dotted. mean |F|: the mean of |F| over the rho grid nodes "
            "where the table has data; peak |F|: the largest there (raw table samples).</p>")
    body += lookup_table_summary(rep.path("lookup", "table.h5"))
    if os.path.isfile(trends):
        _, rows = read_csv(trends, "plot_lookup.py's lookup_trends.csv")
        need_columns(trends, rows, ("trend", "material", "bite_depth_mm", "pass", "statistic",
                                    "value", "detail"))
        by = lambda t: [r for r in rows if r["trend"] == t]
        ratio = by("ice_over_snow")
        body += "<h3>Ice against snow (the study: about an order of magnitude)</h3>"
        body += table(("bite depth [mm]", "pass", "statistic", "ice / snow", "detail"),
                      [(r["bite_depth_mm"], r["pass"], r["statistic"], num(r["value"]),
                        r["detail"]) for r in ratio], left=(4,)) if ratio else \
            "<p>The table does not hold both ice and snow at one bite depth and pass.</p>"
        for trend, what in (("vs_bite_depth", "bite depth"), ("vs_pass", "pass")):
            body += ("<h3>Force against %s (the study: it grows; 1 = grows at every step)</h3>"
                     % what)
            body += table(("material", "bite depth [mm]", "pass", "statistic", "grows", "values"),
                          [(r["material"], r["bite_depth_mm"], r["pass"], r["statistic"],
                            r["value"], r["detail"]) for r in by(trend)], left=(0, 5)) \
                if by(trend) else \
                "<p>Fewer than two %ss held.</p>" % what
        cells = {}
        for r in by("cell"):
            cells.setdefault((r["material"], r["bite_depth_mm"], r["pass"]), {})[
                r["statistic"]] = r["value"]
        body += "<h3>Per cell</h3>" + table(
            ("material", "bite depth [mm]", "pass", "mean |F| [N]", "peak |F| [N]",
             "mean |T| [N m]", "peak |T| [N m]", "nodes"),
            [k + tuple(num(v.get(s)) for s in ("mean_F_N", "peak_F_N", "mean_T_Nm", "peak_T_Nm",
                                                "nodes")) for k, v in cells.items()])
    else:
        body += '<p class="missing">Trends missing: lookup/lookup_trends.csv</p>'
    for rel, caption in zip(figs, ("Fig. 9 analogue: ice, 15 mm, passes 1-5",
                                   "Fig. 10 analogue: ice against snow, passes 1 and 5",
                                   "Fig. 11 analogue: snow, pass 1, bite depths 15/9/5/3 mm")):
        body += rep.figure("lookup", rel, caption)
    return body


def coarse_vs_fine_section(rep):
    path = rep.path("lookup", "coarse_vs_fine.csv")
    if not os.path.isfile(path):
        return None
    import compare_tables
    notes, rows = read_csv(path, "tools/compare_tables.py's columns")
    need_columns(path, rows, compare_tables.OUT_COLUMNS)
    made = [n for n in notes if n.startswith("tools/compare_tables.py ")]
    if made:
        rep.recorded["coarse_vs_fine"] = made[:1]
    value = lambda r, c: float(r[c]) if r[c] != "" else float("nan")
    both = [r for r in rows if r["status"] == "both"]
    predicted = [(value(r, "predicted_peak_F_ratio"), value(r, "predicted_peak_T_ratio"))
                 for r in rows[:1]]
    body = ("<p>The lookup table on coarse particles against the paper-resolution one, cell by "
            "cell (material, bite depth, pass): over the rho nodes where both tables hold data "
            "(the rows `table export-csv` writes, rho 0 to the pass's rho_end), the mean and the "
            "peak of |F| and of |T| of each, and their ratio coarse / fine. The particle-size "
            "study gives peak |F| and |T| against particle size, so it predicts the peak ratio; "
            "it measured snow, pass 1 of its own scene, so its prediction is for the snow pass-1 "
            "cells, and for ice and later passes only a reference. A measured ratio near the "
            "prediction says the coarse table errs as the size study says; far from it, more "
            "than particle size separates the two (the dig, the pass, the material), and the "
            "size study alone cannot correct the coarse table.</p>")
    if predicted and all(np.isfinite(v) for v in predicted[0]):
        body += ('<div class="verdict">Predicted (the size study, snow pass 1): peak |F| ratio '
                 "%s, peak |T| ratio %s</div>" % (num(predicted[0][0]), num(predicted[0][1])))
    else:
        body += ('<p class="missing">No prediction: the comparison was run without '
                 "--size-study.</p>")
    body += "<pre>%s</pre>" % esc("\n".join(n for n in notes if n not in made))
    summary = []
    for mid in sorted({int(r["material_id"]) for r in both}):
        sel = [r for r in both if int(r["material_id"]) == mid]
        m = sel[0]["material"]
        summary.append([m, len(sel)] + [compare_tables.median_range(
            [value(r, c) for r in sel]) for c in compare_tables.RATIOS])
    body += "<h3>Per material: median ratio (min .. max) over the cells in both</h3>"
    body += table(("material", "cells", "mean |F|", "peak |F|", "mean |T|", "peak |T|"),
                  summary) if summary else "<p>No cell is in both tables.</p>"
    pred = lambda r, c: "-" if r[c] == "" else num(r[c]) + (
        "" if r["prediction_applies"] == "1" else " (ref.)")
    body += "<h3>Per cell (coarse / fine)</h3>" + table(
        ("material", "bite depth [mm]", "pass", "status", "nodes", "rho_end coarse [mm]",
         "rho_end fine [mm]", "peak |F|", "predicted", "peak |T|", "predicted", "mean |F|",
         "mean |T|"),
        [(r["material"], num(r["bite_depth_mm"]), r["pass"], r["status"], r["nodes"],
          num(r["rho_end_mm_coarse"]) if r["rho_end_mm_coarse"] else "-",
          num(r["rho_end_mm_fine"]) if r["rho_end_mm_fine"] else "-",
          num(r["peak_F_ratio"]) if r["peak_F_ratio"] else "-", pred(r, "predicted_peak_F_ratio"),
          num(r["peak_T_ratio"]) if r["peak_T_ratio"] else "-", pred(r, "predicted_peak_T_ratio"),
          num(r["mean_F_ratio"]) if r["mean_F_ratio"] else "-",
          num(r["mean_T_ratio"]) if r["mean_T_ratio"] else "-") for r in rows], left=(0, 3))
    body += ("<p>predicted: the size study's snow pass-1 peak ratio; (ref.): a cell it does not "
             "predict (ice, or a pass after the first). status: both, coarse_only or fine_only "
             "(a cell in one table), no_common_nodes.</p>")
    return body


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dir", metavar="DIR", help="the results folder")
    parser.add_argument("-o", "--output", metavar="REPORT.html",
                        help="the page to write (default DIR/report.html)")
    args = parser.parse_args(argv)
    out = args.output or os.path.join(args.dir, "report.html")
    try:
        if not os.path.isdir(args.dir):
            raise InputError("%s: no such folder (expected the results folder; see --help)"
                             % args.dir)
        rep = Report(args.dir, read_commands(os.path.join(args.dir, "commands.txt")))
        for key, title, make in (
                ("shape", "Shape complexity of ice (Table 3, Fig. 8)", shape_section),
                ("size", "Particle-size convergence of snow (eq. 5-7, Fig. 3-6)", size_section),
                ("balovnev", "Balovnev's analytical model against the DEM", balovnev_section),
                ("testbed", "The sand testbed (Fig. 12-13)", testbed_section),
                ("lookup", "The lookup-set figures and trends (Fig. 9-11)", lookup_section),
                ("coarse_vs_fine", "Coarse against fine (issue 39)", coarse_vs_fine_section)):
            rep.add(key, title, make(rep))
        page = rep.html()
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
        with open(out, "w", encoding="utf-8") as f:
            f.write(page)
    except InputError as e:
        print("report: %s" % e, file=sys.stderr)
        return 2
    shown = [k for k, _, s, _ in rep.sections if s == "shown"]
    print("report: wrote %s (%d figures; sections shown: %s; not run: %s)" % (
        out, len(rep.figures), ", ".join(shown) or "none",
        ", ".join(k for k, _, s, _ in rep.sections if s != "shown") or "none"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
