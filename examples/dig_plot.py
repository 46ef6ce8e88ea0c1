#!/usr/bin/env python3
"""A dig plotted in ten lines: tiny_dig stepped from Python, the scoop's force in l_scoop.

    PYTHONPATH=build/python python3 examples/dig_plot.py [OUT.png]
"""
import sys, numpy as np, matplotlib; matplotlib.use("Agg"); import matplotlib.pyplot as plt
import scoopsim

world = scoopsim.World(scoopsim.load_scene("scenes/tiny_dig.yaml"))  # pours the bed, starts the dig
rows = []
while world.step(100):  # 0 steps once the dig is done
    rows.append([world.time, *world.scoop_wrench("l_scoop")[:3]])
t, fx, fy, fz = np.array(rows).T
plt.plot(t, fx, label="Fx"); plt.plot(t, fy, label="Fy"); plt.plot(t, fz, label="Fz")
plt.xlabel("t [s]"); plt.ylabel("force on the scoop, l_scoop [N]"); plt.legend()
plt.savefig(sys.argv[1] if len(sys.argv) > 1 else "dig_plot.png", dpi=120)
