#!/usr/bin/env python3
"""A proportional controller in Python driving the lander's arm through a dig, the DEM in the loop.

The scene's arm (scenes/arm/nominal_snow.yaml) starts buried at its path's first pose; from there
Python takes over: every control period it asks for a scoop velocity along the trench (the base
frame's +x, level, no rotation), slowed in proportion to how far the scoop's force is above a
limit, turns it into joint rates through the arm's Jacobian (scoopsim.Arm, resolved rate), and sets
the joint PID's reference (World.set_joint_reference). It writes its log (OUT.npz: t, q, tau, F)
and a plot (OUT.png).

    PYTHONPATH=build/python /usr/bin/python3 examples/arm_controller.py [OUT] [--set KEY=VALUE ...]
"""
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import scoopsim  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 and not sys.argv[1].startswith("--") else "arm_controller"
sets = [a for a in sys.argv[1:] if "=" in a]
scene = scoopsim.load_scene("scenes/arm/nominal_snow.yaml", overrides=sets)
arm = scoopsim.Arm("assets/lander_arm.urdf")
world = scoopsim.World(scene)

SPEED = 0.05     # asked scoop speed along the trench [m/s]
F_LIMIT = 1.0    # above this |F| the speed is cut in proportion [N]
K_F = 1.0        # speed cut per newton above the limit [1/N]
PERIOD = 20      # DEM (and Bullet) steps per control period
DURATION = 1.2   # [s] of pushing

world.step(1)  # the arm at the path's start pose
q_goal = world.joint_state()["q"].copy()
t0, log = world.time, []
while world.time - t0 < DURATION and not world.done():
    s = world.joint_state()
    force = world.scoop_wrench("world")[:3]
    cut = min(1.0, max(0.0, K_F * (np.linalg.norm(force) - F_LIMIT)))  # the proportional term
    v = np.array([SPEED * (1 - cut), 0, 0, 0, 0, 0])  # tip twist in the base frame
    qdot = np.linalg.pinv(arm.jacobian(q_goal)) @ v
    q_goal = q_goal + qdot * PERIOD * world.time_step
    world.set_joint_reference(q_goal)
    world.step(PERIOD)
    log.append((world.time - t0, *s["q"], *s["tau"], *force, cut))

log = np.array(log)
t, q, tau, f, cut = log[:, 0], log[:, 1:7], log[:, 7:13], log[:, 13:16], log[:, 16]
np.savez(out + ".npz", t=t, q=q, tau=tau, force=f, cut=cut,
         joints=[j["name"] for j in arm.info()["joints"]])
active, latched = world.fault_bits()
print(f"{len(t)} control periods, {t[-1]:.3f} s; peak |F| {np.linalg.norm(f, axis=1).max():.3g} N; "
      f"peak |tau| {np.abs(tau).max(axis=0).round(2).tolist()} N m; "
      f"faults latched: {scoopsim.fault_names(latched) or 'none'}")
fig, ax = plt.subplots(3, 1, sharex=True, figsize=(7, 7))
ax[0].plot(t, np.linalg.norm(f, axis=1)); ax[0].axhline(F_LIMIT, ls="--", c="k")
ax[0].set_ylabel("|F| on the scoop [N]")
ax[1].plot(t, tau); ax[1].set_ylabel("applied torque [N m]")
ax[2].plot(t, cut); ax[2].set_ylabel("speed cut [-]"); ax[2].set_xlabel("t since takeover [s]")
fig.savefig(out + ".png", dpi=110)
print(f"wrote {out}.npz, {out}.png")
