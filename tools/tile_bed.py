#!/usr/bin/env python3
"""Makes a large bed from a small settled one by mirror tiling (LIGGGHTS `replicate`, mirrored).

    tools/tile_bed.py SMALL.h5 --box XMIN YMIN XMAX YMAX --tiles NX NY -o BIG.h5

SMALL.h5 is a bed file of `scoopsim bed` (a box whose floor is [XMIN, XMAX] x [YMIN, YMAX]).
Tile (a, b) is the small bed shifted by (a * Lx, b * Ly) and, for odd a (odd b), mirrored in x
(in y), so that every seam joins a bed to its own mirror image: the particles that leaned on the
small box's side wall lean on their images instead, and no two particles overlap more than a wall
contact did. Positions, velocities, forces and tangential springs are mirrored as polar vectors,
angular velocities and torques as axial ones. Wall contacts on a side wall that became a seam are
dropped; those on an outer wall are kept, on the plane now there. The result is a bed file that
`scoopsim run` loads (scene key bed.file), in a box of NX * Lx by NY * Ly.
"""
import argparse
import sys

import h5py
import numpy as np

# Plane order of sim::MakeSystemConfig: floor, x_min, x_max, y_min, y_max.
FLOOR, X_MIN, X_MAX, Y_MIN, Y_MAX = range(5)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bed", help="settled bed file of scoopsim bed")
    ap.add_argument("--box", type=float, nargs=4, metavar=("XMIN", "YMIN", "XMAX", "YMAX"),
                    required=True, help="floor of the small bed's box [m]")
    ap.add_argument("--tiles", type=int, nargs=2, metavar=("NX", "NY"), required=True)
    ap.add_argument("-o", "--output", required=True)
    a = ap.parse_args()
    x0, y0, x1, y1 = a.box
    nx, ny = a.tiles
    if not (x1 > x0 and y1 > y0) or nx < 1 or ny < 1:
        sys.exit("tile_bed.py: --box needs XMAX > XMIN and YMAX > YMIN, --tiles at least 1 1")
    lx, ly = x1 - x0, y1 - y0
    with h5py.File(a.bed, "r") as f:
        p = {k: f["particles/" + k][:] for k in
             ("id", "position", "velocity", "angular_velocity", "force", "torque", "radius",
              "material")}
        names = f["materials/names"][:]
        ca, cb, cs = f["contacts/a"][:], f["contacts/b"][:], f["contacts/shear"][:]
        time = float(f.attrs["time"])
        if "clumps" in f:
            sys.exit(f"tile_bed.py: {a.bed}: beds of clumps are not supported")
    xs = p["position"]
    if (xs[:, 0].min() < x0 or xs[:, 0].max() > x1 or xs[:, 1].min() < y0 or
            xs[:, 1].max() > y1):
        sys.exit(f"tile_bed.py: {a.bed}: particles lie outside --box")
    n = len(p["id"])
    span = int(p["id"].max()) + 1  # ids of tile t are id + t * span
    out = {k: [] for k in p}
    oa, ob, osh = [], [], []
    for b in range(ny):
        for t_a in range(nx):
            t = b * nx + t_a
            mx, my = t_a % 2 == 1, b % 2 == 1
            pos = xs.copy()
            pos[:, 0] = (x0 + t_a * lx) + ((x1 - xs[:, 0]) if mx else (xs[:, 0] - x0))
            pos[:, 1] = (y0 + b * ly) + ((y1 - xs[:, 1]) if my else (xs[:, 1] - y0))
            polar = np.array([-1.0 if mx else 1.0, -1.0 if my else 1.0, 1.0])
            axial = polar * np.prod(polar)  # a reflection flips the axial components it keeps
            out["id"].append(p["id"] + t * span)
            out["position"].append(pos)
            for k in ("velocity", "force"):
                out[k].append(p[k] * polar)
            for k in ("angular_velocity", "torque"):
                out[k].append(p[k] * axial)
            out["radius"].append(p["radius"])
            out["material"].append(p["material"])
            # Contacts between particles of the tile, and wall contacts still on an outer wall.
            keep = np.ones(len(ca), bool)
            plane = cb.copy()
            walls = cb < 0
            k = -1 - cb
            # Where each small-box side wall lands in the big box, or -1 on a seam.
            xlo = X_MIN if t_a == 0 else -1
            xhi = X_MAX if t_a == nx - 1 else -1
            if mx:  # the small x_min wall is now on the tile's high side
                xlo, xhi = (X_MAX if t_a == nx - 1 else -1), (X_MIN if t_a == 0 else -1)
            ylo = Y_MIN if b == 0 else -1
            yhi = Y_MAX if b == ny - 1 else -1
            if my:
                ylo, yhi = (Y_MAX if b == ny - 1 else -1), (Y_MIN if b == 0 else -1)
            remap = {FLOOR: FLOOR, X_MIN: xlo, X_MAX: xhi, Y_MIN: ylo, Y_MAX: yhi}
            for old, new in remap.items():
                sel = walls & (k == old)
                if new < 0:
                    keep[sel] = False
                else:
                    plane[sel] = -1 - new
            oa.append(ca[keep] + t * span)
            ob.append(np.where(cb[keep] >= 0, cb[keep] + t * span, plane[keep]))
            osh.append(cs[keep] * polar)
    order = np.argsort(np.concatenate(out["id"]), kind="stable")
    with h5py.File(a.output, "w") as g:
        g.attrs["version"] = "tile_bed.py"
        g.attrs["time"] = time
        g.attrs["tiled_from"] = a.bed
        for k, v in out.items():
            g.create_dataset("particles/" + k, data=np.concatenate(v)[order])
        g.create_dataset("materials/names", data=names, dtype=h5py.string_dtype())
        a_all, b_all, s_all = np.concatenate(oa), np.concatenate(ob), np.concatenate(osh)
        c_order = np.lexsort((b_all, a_all))
        g.create_dataset("contacts/a", data=a_all[c_order])
        g.create_dataset("contacts/b", data=b_all[c_order])
        g.create_dataset("contacts/shear", data=s_all[c_order])
    print(f"tile_bed.py: {n * nx * ny} particles in {nx} x {ny} tiles, box "
          f"[{x0}, {x0 + nx * lx}] x [{y0}, {y0 + ny * ly}]; wrote {a.output}")


if __name__ == "__main__":
    main()
