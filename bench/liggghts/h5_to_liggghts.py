#!/usr/bin/python3
"""Convert a scoopsim bed (HDF5) to a LIGGGHTS data file (atom_style granular).

Usage:  h5_to_liggghts.py BED.h5 OUT.data [--density 300]

Input layout (scoopsim bed file):
  /particles/id               int64   (N)
  /particles/position         float64 (N, 3)  [m]
  /particles/velocity         float64 (N, 3)  [m/s]
  /particles/angular_velocity float64 (N, 3)  [rad/s]
  /particles/radius           float64 (N)     [m]
  /particles/material         int32   (N)     (all snow in the benchmark bed)
  optional root attributes box_min, box_max (3-vectors) [m]
  optional root attribute scene_yaml (scoopsim writes the scene there; its
           box: {min: [...], max: [...]} and materials are used if present)
  /contacts/{a,b,shear}       contact history (cannot be transferred, see below)

Output: LIGGGHTS data file with
  Atoms section      "id type diameter density x y z"   (atom_style granular)
  Velocities section "id vx vy vz wx wy wz"

Notes
  * Every particle gets atom type 1 (the benchmark bed is one material; the
    walls in in.bench also use type 1, so there is a single set of
    property/global values).  If the file holds more than one material id a
    warning is printed, but the type is still 1.
  * Density is not stored per particle in the bed file; it is a material
    property: --density if given, else the density of the particles'
    material in scene_yaml (when it holds the materials inline), else 300
    kg/m^3 (snow).
  * The box is taken from the root attributes box_min/box_max if present,
    else from scene_yaml's box min/max, else from the particle extents
    (min(x - r), max(x + r)).  The
    walls in in.bench are placed on xlo/xhi, ylo/yhi and zlo of this box; the
    top (zhi) is open (in.bench uses a shrink-wrapped 'm' boundary in z).
  * Contact history (/contacts: tangential spring displacements) is NOT
    transferred: a LIGGGHTS data file has no place for it (only restart
    files carry fix contacthistory).  LIGGGHTS starts with fresh contacts, just as
    the LIGGGHTS-made bed does (it is also written with write_data, which
    drops the history).  For a settled bed this only affects the first steps.
  * LIGGGHTS atom ids must be positive: 0-based ids are shifted by +1; if
    the ids are not unique (or negative) the particles are renumbered 1..N
    in file order.
"""
import argparse
import sys

import h5py
import numpy as np


def scene_from_attrs(f):
    """The scene stored in the root attribute scene_yaml, as a dict ({} if none)."""
    text = f.attrs.get("scene_yaml")
    if text is None:
        return {}
    if isinstance(text, bytes):
        text = text.decode()
    try:
        import yaml
        scene = yaml.safe_load(str(text))
    except Exception as e:  # no PyYAML or not YAML: fall back to the defaults
        print("h5_to_liggghts: cannot parse scene_yaml (%s)" % e, file=sys.stderr)
        return {}
    return scene if isinstance(scene, dict) else {}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("bed", help="scoopsim bed file (HDF5)")
    ap.add_argument("out", help="LIGGGHTS data file to write")
    ap.add_argument("--density", type=float, default=None,
                    help="particle density in kg/m^3 (default: from scene_yaml, "
                         "else 300, snow)")
    args = ap.parse_args(argv)

    with h5py.File(args.bed, "r") as f:
        p = f["particles"]
        pos = np.asarray(p["position"][...], dtype=np.float64).reshape(-1, 3)
        n = pos.shape[0]
        rad = np.asarray(p["radius"][...], dtype=np.float64).reshape(n)
        ids = (np.asarray(p["id"][...], dtype=np.int64).reshape(n)
               if "id" in p else np.arange(1, n + 1, dtype=np.int64))
        vel = (np.asarray(p["velocity"][...], dtype=np.float64).reshape(n, 3)
               if "velocity" in p else np.zeros((n, 3)))
        omg = (np.asarray(p["angular_velocity"][...], dtype=np.float64).reshape(n, 3)
               if "angular_velocity" in p else np.zeros((n, 3)))
        mat = (np.asarray(p["material"][...]).reshape(n)
               if "material" in p else np.zeros(n, dtype=np.int32))
        box_min = f.attrs.get("box_min")
        box_max = f.attrs.get("box_max")
        scene = scene_from_attrs(f)
        mat_names = None
        if "materials/names" in f:
            mat_names = [x.decode() if isinstance(x, bytes) else str(x)
                         for x in f["materials/names"][...].ravel()]

    density, density_from = args.density, "--density"
    if box_min is None or box_max is None:
        box = scene.get("box") if isinstance(scene, dict) else None
        if isinstance(box, dict) and "min" in box and "max" in box:
            box_min, box_max = box["min"], box["max"]
            print("h5_to_liggghts: box from scene_yaml", file=sys.stderr)
    if density is None:
        density, density_from = 300.0, "default (snow)"
        mats = scene.get("materials") if isinstance(scene, dict) else None
        ids_used = np.unique(mat) if len(mat) else []
        if isinstance(mats, dict) and mat_names and len(ids_used) == 1 \
                and 0 <= int(ids_used[0]) < len(mat_names):
            m = mats.get(mat_names[int(ids_used[0])])
            if isinstance(m, dict) and "density" in m:
                density = float(m["density"])
                density_from = "scene_yaml material %s" % mat_names[int(ids_used[0])]
    print("h5_to_liggghts: density %g kg/m^3 (%s)" % (density, density_from),
          file=sys.stderr)

    if n == 0:
        sys.exit("h5_to_liggghts: no particles in %s" % args.bed)
    if len(np.unique(mat)) > 1:
        print("h5_to_liggghts: warning: %d material ids %s, all mapped to type 1"
              % (len(np.unique(mat)), np.unique(mat)), file=sys.stderr)
    if len(np.unique(ids)) != n or ids.min() < 0:
        print("h5_to_liggghts: ids not unique/non-negative, renumbering 1..N",
              file=sys.stderr)
        ids = np.arange(1, n + 1, dtype=np.int64)
    elif ids.min() == 0:
        ids = ids + 1  # 0-based ids -> LIGGGHTS id = id + 1

    lo_p = (pos - rad[:, None]).min(axis=0)
    hi_p = (pos + rad[:, None]).max(axis=0)
    lo = np.asarray(box_min, dtype=np.float64).reshape(3) if box_min is not None else lo_p
    hi = np.asarray(box_max, dtype=np.float64).reshape(3) if box_max is not None else hi_p
    # LIGGGHTS needs every particle centre strictly inside the box; the top
    # is open, so make sure zhi is above the highest particle.
    hi = hi.copy()
    hi[2] = max(hi[2], hi_p[2])
    inside = np.all((pos > lo) & (pos < hi), axis=1)
    if not inside.all():
        sys.exit("h5_to_liggghts: %d particle centres lie outside the box %s..%s"
                 % ((~inside).sum(), lo, hi))

    order = np.argsort(ids, kind="stable")
    with open(args.out, "w") as out:
        out.write("LIGGGHTS data file from %s (h5_to_liggghts.py)\n\n" % args.bed)
        out.write("%d atoms\n1 atom types\n\n" % n)
        for k, name in enumerate("xyz"):
            out.write("%.16e %.16e %slo %shi\n" % (lo[k], hi[k], name, name))
        out.write("\nAtoms\n\n")
        for i in order:
            out.write("%d 1 %.16e %.16e %.16e %.16e %.16e\n"
                      % (ids[i], 2.0 * rad[i], density,
                         pos[i, 0], pos[i, 1], pos[i, 2]))
        out.write("\nVelocities\n\n")
        for i in order:
            out.write("%d %.16e %.16e %.16e %.16e %.16e %.16e\n"
                      % (ids[i], vel[i, 0], vel[i, 1], vel[i, 2],
                         omg[i, 0], omg[i, 1], omg[i, 2]))
    print("h5_to_liggghts: wrote %d particles to %s, box %s .. %s"
          % (n, args.out, lo.tolist(), hi.tolist()))


if __name__ == "__main__":
    main()
