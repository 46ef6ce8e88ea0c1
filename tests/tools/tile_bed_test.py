#!/usr/bin/python3
"""tools/tile_bed.py on a synthetic bed: mirror tiling keeps every distance and every contact's
spring (lengths and their components along the pair axis, exactly), puts a seam particle at
twice its wall distance from its image (so two images overlap by twice the wall overlap, the
mirror closed form), keeps wall contacts only on outer walls, and writes a bed scoopsim loads.

    tile_bed_test.py [SCOOPSIM]   (with the binary, also the load check)
"""

import os
import subprocess
import sys

import h5py
import numpy as np

from cli_check import test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "tile_bed.py")
R = 1.75e-3
LX, LY = 12.2 * R, 10.2 * R  # room for 6 x 5 spheres at a pitch above 2 R


def make_bed(path):
    """Spheres on a lattice in a LX x LY box, the outer ones pressed 1e-6 m into the side walls,
    a contact record per touching pair and per wall contact."""
    rng = np.random.default_rng(3)
    xs = []
    for x in np.linspace(R - 1e-6, LX - R + 1e-6, 6):
        for y in np.linspace(R - 1e-6, LY - R + 1e-6, 5):
            xs.append([x, y, R])
    x = np.array(xs)
    n = len(x)
    ids = np.arange(n) * 2 + 5  # not 0..n-1: ids are offsets, not slots
    a, b, s = [], [], []
    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(x[i] - x[j]) < 2 * R + 1e-3:
                a.append(ids[i]); b.append(ids[j]); s.append(rng.normal(size=3) * 1e-6)
        for k, d in ((1, x[i, 0]), (2, LX - x[i, 0]), (3, x[i, 1]), (4, LY - x[i, 1])):
            if d < R:
                a.append(ids[i]); b.append(-1 - k); s.append(rng.normal(size=3) * 1e-6)
    with h5py.File(path, "w") as f:
        f.attrs["time"] = 0.5
        f["particles/id"] = ids
        f["particles/position"] = x
        f["particles/velocity"] = 1e-3 * rng.normal(size=(n, 3))
        f["particles/angular_velocity"] = 0.1 * rng.normal(size=(n, 3))
        f["particles/force"] = rng.normal(size=(n, 3))
        f["particles/torque"] = rng.normal(size=(n, 3))
        f["particles/radius"] = np.full(n, R)
        f["particles/material"] = np.zeros(n, np.int32)
        f.create_dataset("materials/names", data=[b"snow"], dtype=h5py.string_dtype())
        order = np.lexsort((np.array(b), np.array(a)))
        f["contacts/a"] = np.array(a)[order]
        f["contacts/b"] = np.array(b)[order]
        f["contacts/shear"] = np.array(s)[order]
    return n


def main():
    with test_dir("tile_bed") as tmp:
        small, big = os.path.join(tmp, "small.h5"), os.path.join(tmp, "big.h5")
        n = make_bed(small)
        r = subprocess.run([sys.executable, SCRIPT, small, "--box", "0", "0", repr(LX), repr(LY),
                            "--tiles", "2", "2", "-o", big], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        with h5py.File(small) as f, h5py.File(big) as g:
            ids0, x0 = f["particles/id"][:], f["particles/position"][:]
            ids, x = g["particles/id"][:], g["particles/position"][:]
            assert len(ids) == 4 * n and np.all(np.diff(ids) > 0), "ids must be ascending, unique"
            assert x[:, 0].min() > 0 and x[:, 0].max() < 2 * LX and x[:, 1].max() < 2 * LY
            pos = dict(zip(ids, x))
            pos0 = dict(zip(ids0, x0))
            span = ids0.max() + 1
            # Pair contacts: same distance, same spring length and axial component (1e-15 m).
            a0, b0, s0 = f["contacts/a"][:], f["contacts/b"][:], f["contacts/shear"][:]
            a, b, s = g["contacts/a"][:], g["contacts/b"][:], g["contacts/shear"][:]
            pairs = b >= 0
            assert pairs.sum() == 4 * (b0 >= 0).sum()
            src = {(ai, bi): si for ai, bi, si in zip(a0, b0, s0)}
            for ai, bi, si in zip(a[pairs], b[pairs], s[pairs]):
                t = ai // span
                assert bi // span == t
                o = src[(ai - t * span, bi - t * span)]
                d, d0 = pos[bi] - pos[ai], pos0[bi - t * span] - pos0[ai - t * span]
                assert abs(np.linalg.norm(d) - np.linalg.norm(d0)) < 1e-15
                assert abs(np.linalg.norm(si) - np.linalg.norm(o)) < 1e-18
                assert abs(si @ d - o @ d0) < 1e-21
            # Wall contacts: only on the big box's walls, the particle within r of that wall.
            walls = {1: lambda p: p[0], 2: lambda p: 2 * LX - p[0], 3: lambda p: p[1],
                     4: lambda p: 2 * LY - p[1]}
            for ai, bi in zip(a[~pairs], b[~pairs]):
                assert walls[-1 - bi](pos[ai]) < R, "wall contact %d on plane %d" % (ai, -1 - bi)
            # A particle pressed 1e-6 m into the seam wall and its image: 2e-6 m overlap.
            seam = x[np.abs(x[:, 0] - LX) < R]
            gaps = [np.min(np.linalg.norm(seam[:, :2] - p[:2], axis=1)[
                np.abs(seam[:, 0] - (2 * LX - p[0])) < 1e-12]) for p in seam]
            assert np.allclose(gaps, 2 * R - 2e-6, atol=1e-12), gaps[:3]
        # Bad input: one line, non-zero exit.
        r = subprocess.run([sys.executable, SCRIPT, small, "--box", "0", "0", "0.001", repr(LY),
                            "--tiles", "2", "2", "-o", big], capture_output=True, text=True)
        assert r.returncode != 0 and "outside --box" in r.stderr, r.stderr
        if len(sys.argv) > 1:  # scoopsim loads the tiled bed and steps it
            scene = os.path.join(tmp, "scene.yaml")
            with open(scene, "w") as out:
                out.write("materials: %s\ngravity: [0, 0, -1.3]\n"
                          "time_step: {rayleigh_fraction: 0.2}\nneighbor: {skin: 0.875e-3}\n"
                          "box: {min: [0, 0, 0], max: [%g, %g, 0.05], wall_material: wall}\n"
                          "bed: {material: snow, radius: %g, count: %d, file: big.h5}\n"
                          "duration: 1.0e-4\n" % (os.path.join(ROOT, "scenes", "materials.yaml"),
                                                 2 * LX, 2 * LY, R, 4 * n))
            r = subprocess.run([sys.argv[1], "run", scene, "-o", os.path.join(tmp, "run.h5"),
                                "-q", "--threads", "1"], capture_output=True, text=True)
            assert r.returncode == 0, r.stderr
    print("tile_bed_test: ok")


if __name__ == "__main__":
    main()
