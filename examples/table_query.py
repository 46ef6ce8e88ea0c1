#!/usr/bin/env python3
"""A wrench table queried over a grid of rho at three bite depths, vectorised, in metres.

    PYTHONPATH=build/python python3 examples/table_query.py TABLE.h5 [MATERIAL] [OUT.png]

TABLE.h5 is `scoopsim table build` output (docs/studies.md).
"""
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import scoopsim  # noqa: E402

table = scoopsim.Table(sys.argv[1])
material = sys.argv[2] if len(sys.argv) > 2 else table.materials[0]
rho = np.linspace(table.rho[0], table.rho[-1], 200)  # [m]
depths = np.linspace(table.bite_depths[0], table.bite_depths[-1], 3)[:, None]  # [m], (3, 1)
w = table.query(material, depths, table.passes[0], rho, clamp=True)  # (3, 200, 6)
for d, wd in zip(depths[:, 0], w):
    plt.plot(1e3 * rho, wd[:, 2], label=f"bite {1e3 * d:.1f} mm")
plt.xlabel("rho [mm]")
plt.ylabel(f"Fz in l_scoop [N], {material}, pass {table.passes[0]}")
plt.legend()
plt.savefig(sys.argv[3] if len(sys.argv) > 3 else "table_query.png", dpi=120)
print(f"{material}: peak |Fz| {np.abs(w[..., 2]).max():.3g} N over {w.shape[:2]} queries")
