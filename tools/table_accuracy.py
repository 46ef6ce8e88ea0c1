#!/usr/bin/env python3
"""How good is a wrench table at a bite depth it does not hold (issue 20 item 5).

From a sweep's output folder holding a low and a high bite depth case, a DEM reference case at
the bite depth in between and a second reference on another bed (another bed.seed), per pass:
  - builds three tables with `scoopsim table build` (the same resampling onto rho for all): the
    bracket (low + high), the reference alone, the second bed alone;
  - queries the bracket table at the reference's bite depth with `scoopsim table query`: linear
    interpolation (WrenchTable::Query), and the nearest key (each of the two stored depths: the
    lander simulator's lookup takes the nearest key, and midway both are nearest);
  - per component (Fx..Tz, l_scoop frame about the CoM, the lander's), over the rho nodes where
    every table has data: RMS(estimate - reference) / max |reference|, in %; the noise floor is
    the same figure for the second bed's reference against the first's.
Prints the table, writes it as CSV (a row per pass and component) and draws component vs rho
(a PNG per pass: <png stem>_p<pass>.png).

  python3 tools/table_accuracy.py out/accuracy7 [--low b5 --high b9 --ref b7
      --noise b7_bed2 --material snow --passes 1,2,3] [--scoopsim build/scoopsim]
      [--csv bench/results/vm/table_accuracy_7mm.csv] [--png /tmp/issue20_figs/table_accuracy_7mm.png]
"""
import argparse
import json
import os
import subprocess
import sys

import h5py
import numpy as np

COMPONENTS = ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
UNITS = ["N", "N", "N", "N m", "N m", "N m"]


def fail(message):
    print("table_accuracy: " + message, file=sys.stderr)
    sys.exit(2)


def build_table(scoopsim, sweep_dir, name, cases):
    """A table of `cases` alone: DIR/tables/<name>/cases/<case>.h5 links, then table build."""
    folder = os.path.join(sweep_dir, "tables", name)
    os.makedirs(os.path.join(folder, "cases"), exist_ok=True)
    for case in cases:
        source = os.path.abspath(os.path.join(sweep_dir, "cases", case + ".h5"))
        if not os.path.isfile(source):
            fail(f"{source}: no such case file (is the sweep done?)")
        link = os.path.join(folder, "cases", case + ".h5")
        if os.path.lexists(link):
            os.remove(link)
        os.symlink(source, link)
    table = os.path.join(folder, "table.h5")
    subprocess.run([scoopsim, "table", "build", folder, "-o", table], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return table


def stored(table, material, pass_):
    """rho [m], the one bite depth's samples (R x 6, l_scoop frame) and rho_end [m]."""
    with h5py.File(table, "r") as f:
        names = [n.decode() if isinstance(n, bytes) else n for n in f["/materials/name"][:]]
        m = names.index(material)
        p = list(f["/pass"][:]).index(pass_)
        force = f["/scoop/force_scoop"][m, 0, p, :, :]
        torque = f["/scoop/torque_scoop"][m, 0, p, :, :]
        return (f["/rho"][:], np.hstack([force, torque]), float(f["/cells/rho_end"][m, 0, p]),
                float(f["/bite_depth"][0]))


def query(scoopsim, table, material, depth_mm, pass_, rho_mm):
    out = subprocess.run([scoopsim, "table", "query", table, "--material", material,
                          "--bite-depth-mm", repr(depth_mm), "--pass", str(pass_), "--rho-mm",
                          repr(rho_mm)], check=True, capture_output=True, text=True).stdout
    w = json.loads(out)  # {"frame": "l_scoop", "F": [x, y, z], "T": [x, y, z]}
    return w["F"] + w["T"]


def compare(a, tables, pass_):
    """One pass: the rows of the table (per component) and the figure."""
    rho, ref, ref_end, depth = stored(tables["ref"], a.material, pass_)
    _, noise, noise_end, _ = stored(tables["noise"], a.material, pass_)
    _, low, low_end, low_depth = stored(tables["low"], a.material, pass_)
    _, high, high_end, high_depth = stored(tables["high"], a.material, pass_)
    depth_mm, low_mm, high_mm = 1e3 * depth, 1e3 * low_depth, 1e3 * high_depth
    end = min(ref_end, noise_end, low_end, high_end)
    keep = rho <= end + 1e-12
    rho = rho[keep]
    ref, noise, low, high = ref[keep], noise[keep], low[keep], high[keep]
    # The interpolated table, through the table's own query (WrenchTable::Query).
    interp = np.array([query(a.scoopsim, tables["bracket"], a.material, depth_mm, pass_, 1e3 * r)
                       for r in rho])
    peak = np.max(np.abs(ref), axis=0)

    def rel_rms(x):
        return 100 * np.sqrt(np.mean((x - ref) ** 2, axis=0)) / peak

    e_interp, e_low, e_high, e_noise = rel_rms(interp), rel_rms(low), rel_rms(high), rel_rms(noise)
    print(f"table_accuracy: {a.material}, pass {pass_}, bite depth {depth_mm:g} mm, rho 0.."
          f"{1e3 * rho[-1]:.0f} mm ({len(rho)} nodes), l_scoop frame about the CoM; "
          "RMS over the pass / peak abs(component) of the DEM reference, %")
    print(f"| pass | component | peak abs(DEM {depth_mm:g} mm) | interpolated {low_mm:g}/{high_mm:g}"
          f" mm | nearest key {low_mm:g} mm | nearest key {high_mm:g} mm | noise floor (2nd bed) |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for c in range(6):
        print(f"| {pass_} | {COMPONENTS[c]} | {peak[c]:.4g} {UNITS[c]} | {e_interp[c]:.1f} | "
              f"{e_low[c]:.1f} | {e_high[c]:.1f} | {e_noise[c]:.1f} |")
        rows.append([pass_, COMPONENTS[c], peak[c], e_interp[c], e_low[c], e_high[c], e_noise[c],
                     1e3 * rho[-1]])
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        os.makedirs(os.path.dirname(a.png) or ".", exist_ok=True)
        fig, axes = plt.subplots(2, 3, figsize=(14, 7), sharex=True)
        x = 1e3 * rho
        for c, ax in enumerate(axes.flat):
            ax.plot(x, ref[:, c], color="k", lw=1.4, label=f"DEM {depth_mm:g} mm")
            ax.plot(x, noise[:, c], color="0.6", lw=0.9, label=f"DEM {depth_mm:g} mm, 2nd bed")
            ax.plot(x, interp[:, c], color="C0", lw=1.2,
                    label=f"interpolated {low_mm:g}/{high_mm:g}")
            ax.plot(x, low[:, c], color="C1", lw=0.9, ls="--", label=f"nearest key {low_mm:g} mm")
            ax.plot(x, high[:, c], color="C2", lw=0.9, ls="--", label=f"nearest key {high_mm:g} mm")
            ax.set_title(f"{COMPONENTS[c]}: interp {e_interp[c]:.0f}%, nearest {e_low[c]:.0f}/"
                         f"{e_high[c]:.0f}%, noise {e_noise[c]:.0f}%", fontsize=9)
            ax.set_ylabel(f"{COMPONENTS[c]} [{UNITS[c]}]")
            if c >= 3:
                ax.set_xlabel("rho [mm]")
        axes.flat[0].legend(fontsize=7)
        fig.suptitle(f"{a.material}, pass {pass_}: the {depth_mm:g} mm cut (DEM) against the "
                     f"table of {low_mm:g} and {high_mm:g} mm (l_scoop frame about the CoM)")
        fig.tight_layout()
        stem, ext = os.path.splitext(a.png)
        png = f"{stem}_p{pass_}{ext or '.png'}"
        fig.savefig(png, dpi=110)
        plt.close(fig)
        print(f"table_accuracy: wrote {png}")
    return rows, (depth_mm, low_mm, high_mm)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dir")
    parser.add_argument("--low", default="b5")
    parser.add_argument("--high", default="b9")
    parser.add_argument("--ref", default="b7")
    parser.add_argument("--noise", default="b7_bed2")
    parser.add_argument("--material", default="snow")
    parser.add_argument("--passes", default="", help="comma list (default: every pass of --ref)")
    parser.add_argument("--scoopsim", default="build/scoopsim")
    parser.add_argument("--csv", default="", help="default: DIR/accuracy.csv")
    parser.add_argument("--png", default="", help="default: DIR/accuracy.png")
    a = parser.parse_args()
    a.csv = a.csv or os.path.join(a.dir, "accuracy.csv")
    a.png = a.png or os.path.join(a.dir, "accuracy.png")
    if not os.path.isdir(os.path.join(a.dir, "cases")):
        fail(f"{a.dir}: not a sweep output folder (no cases/)")
    tables = {"bracket": build_table(a.scoopsim, a.dir, "bracket", [a.low, a.high])}
    for name in ("ref", "noise", "low", "high"):
        tables[name] = build_table(a.scoopsim, a.dir, name, [getattr(a, name)])
    with h5py.File(tables["ref"], "r") as f:
        passes = [int(p) for p in f["/pass"][:]]
    if a.passes:
        passes = [int(p) for p in a.passes.split(",")]
    rows = []
    for pass_ in passes:
        r, depths = compare(a, tables, pass_)
        rows += r
    if a.csv:
        os.makedirs(os.path.dirname(a.csv) or ".", exist_ok=True)
        depth_mm, low_mm, high_mm = depths
        with open(a.csv, "w") as f:
            f.write(f"# tools/table_accuracy.py {a.dir}: {a.material}, reference {a.ref} "
                    f"({depth_mm:g} mm), table from {a.low} ({low_mm:g} mm) and {a.high} "
                    f"({high_mm:g} mm), noise floor {a.noise} (another bed); l_scoop frame about "
                    "the CoM; RMS over the pass / peak abs(reference component), in %\n")
            f.write("pass,component,peak_ref,interp_rms_pct,nearest_low_rms_pct,"
                    "nearest_high_rms_pct,noise_floor_rms_pct,rho_end_mm\n")
            for r in rows:
                f.write(f"{r[0]},{r[1]},{r[2]:.6g},{r[3]:.4g},{r[4]:.4g},{r[5]:.4g},{r[6]:.4g},"
                        f"{r[7]:.0f}\n")
        print(f"table_accuracy: wrote {a.csv}")


if __name__ == "__main__":
    main()
