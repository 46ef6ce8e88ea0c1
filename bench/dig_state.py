#!/usr/bin/python3
"""A mid-dig state as a bed file, for `scoopsim bench step` (the full-scale step without the pass).

    bench/dig_state.py RUN.h5 BED.h5 -o STATE.h5 [--snapshot K]

RUN.h5 is a dig run with particle snapshots (scene key output.snapshot_every) started from
BED.h5. STATE.h5 is BED.h5 with the positions, velocities and spins of snapshot K (default: the
last) and its sleep flags (/particles/awake); the contact history and the last forces stay the
bed's (a snapshot holds neither), so the first steps relax the difference. The scoop is not in
it: the state measures what a step of the disturbed bed costs, not the dig's wrench.
"""
import argparse
import shutil
import sys

import h5py
import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="dig run with particle snapshots")
    ap.add_argument("bed", help="the bed file that run started from")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--snapshot", type=int, default=-1, help="snapshot index (default: the last)")
    a = ap.parse_args()
    with h5py.File(a.run, "r") as run:
        if "snapshots" not in run or len(run["snapshots"]) == 0:
            sys.exit(f"dig_state.py: {a.run}: /snapshots: expected particle snapshots "
                     "(scene key output.snapshot_every)")
        names = sorted(run["snapshots"].keys())
        name = names[a.snapshot]
        s = run["snapshots/" + name]
        ids = s["id"][:]
        order = np.argsort(ids)
        snap = {k: s[k][:][order] for k in ("position", "velocity", "angular_velocity", "awake")}
        time = float(s.attrs["time"])
        ids = ids[order]
    shutil.copyfile(a.bed, a.output)
    with h5py.File(a.output, "r+") as out:
        bed_ids = out["particles/id"][:]
        if not np.array_equal(bed_ids, ids):
            sys.exit(f"dig_state.py: {a.run}: snapshot {name}: its particle ids are not those of "
                     f"{a.bed} (a pass that removed particles, or another bed)")
        for k in ("position", "velocity", "angular_velocity"):
            out["particles/" + k][...] = snap[k]
        out.create_dataset("particles/awake", data=(snap["awake"] != 0).astype(np.uint8))
        out.attrs["time"] = time
    awake = int(np.count_nonzero(snap["awake"]))
    print(f"dig_state.py: {a.output}: snapshot {name} of {a.run} at t = {time:.4f} s, "
          f"{awake} of {len(ids)} particles awake")


if __name__ == "__main__":
    main()
