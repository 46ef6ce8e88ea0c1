#!/usr/bin/env python3
"""Compare the /arm/ and /scoop/ series of two table-driven (or coupled) arm runs: a reference
(small step) and a candidate (another step, or another D term), the candidate interpolated
linearly onto the reference's row times within each pass (/scoop/pass; rows of the reference
outside the candidate's times of that pass are left out). Prints, per joint, the RMS and the largest difference of
the applied torque over the reference's peak |applied torque| of that joint (%), the largest joint
position difference [mrad], the largest scoop CoM difference [mm] and the F/T sensor's force RMS
over its peak (%); with --csv, appends one row per joint.

  /usr/bin/python3 bench/arm_step_accuracy.py REF.h5 CAND.h5 [--label NAME] [--csv FILE]
"""
import argparse
import datetime
import os

import h5py
import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("reference")
    ap.add_argument("candidate")
    ap.add_argument("--label", default="")
    ap.add_argument("--csv", default="")
    a = ap.parse_args()
    ref, cand = h5py.File(a.reference, "r"), h5py.File(a.candidate, "r")
    t_ref, t_c = ref["arm/time"][:], cand["arm/time"][:]
    p_ref, p_c = ref["scoop/pass"][:], cand["scoop/pass"][:]
    keep = np.zeros(len(t_ref), dtype=bool)
    for p in np.unique(p_ref):
        tc = t_c[p_c == p]
        if len(tc):
            keep |= (p_ref == p) & (t_ref >= tc[0]) & (t_ref <= tc[-1])
    joints = ref.attrs.get("arm_joints", "")
    joints = joints.decode() if isinstance(joints, bytes) else str(joints)
    names = joints.split(",") if joints else [f"j{i}" for i in range(6)]

    def com_rows(f):
        """The scoop's CoM in the world per row [m]: /scoop/pose turned and shifted by the root
        attributes scoop_com_x/y/z (quaternion w, x, y, z), or /scoop/com of a table-driven run
        before issue 41."""
        if "scoop/com" in f:
            return f["scoop/com"][:]
        pose = f["scoop/pose"][:]
        c = np.array([f.attrs["scoop_com_x"], f.attrs["scoop_com_y"], f.attrs["scoop_com_z"]])
        w, v = pose[:, 3:4], pose[:, 4:7]
        t = 2 * np.cross(v, c)
        return pose[:, :3] + c + w * t + np.cross(v, t)

    def on_ref(name):
        c = com_rows(cand) if name == "scoop/com" else cand[name][:]
        c = c.reshape(len(c), -1)
        out = np.zeros((len(t_ref), c.shape[1]))
        for p in np.unique(p_ref):
            mine, theirs = p_ref == p, p_c == p
            if not theirs.any():
                continue
            for k in range(c.shape[1]):
                out[mine, k] = np.interp(t_ref[mine], t_c[theirs], c[theirs, k])
        return out[keep]

    def at_ref(name):
        r = com_rows(ref) if name == "scoop/com" else ref[name][:]
        return r.reshape(len(r), -1)[keep]

    tau_r, tau_c = at_ref("arm/torque_applied"), on_ref("arm/torque_applied")
    q_r, q_c = at_ref("arm/joint_position"), on_ref("arm/joint_position")
    com_r, com_c = at_ref("scoop/com"), on_ref("scoop/com")
    ft_r, ft_c = at_ref("arm/ft_sensor")[:, :3], on_ref("arm/ft_sensor")[:, :3]
    t_ref = t_ref[keep]
    com_max = 1e3 * np.max(np.linalg.norm(com_r - com_c, axis=1))
    ft_peak = np.max(np.linalg.norm(ft_r, axis=1))
    ft_rms = 100 * np.sqrt(np.mean(np.sum((ft_r - ft_c) ** 2, axis=1))) / ft_peak
    print(f"{a.label or a.candidate} against {a.reference}: {len(t_ref)} rows, "
          f"scoop CoM max diff {com_max:.3g} mm, F/T force RMS diff {ft_rms:.3g}% of its peak "
          f"{ft_peak:.3g} N")
    print("| joint | peak abs(applied), ref [N m] | RMS diff, % of peak | max diff, % of peak "
          "| max position diff [mrad] |")
    rows = []
    for j, name in enumerate(names):
        peak = np.max(np.abs(tau_r[:, j]))
        d = tau_c[:, j] - tau_r[:, j]
        rms = 100 * np.sqrt(np.mean(d * d)) / peak
        mx = 100 * np.max(np.abs(d)) / peak
        dq = 1e3 * np.max(np.abs(q_c[:, j] - q_r[:, j]))
        print(f"| {name} | {peak:.4g} | {rms:.3g} | {mx:.3g} | {dq:.3g} |")
        rows.append((name, peak, rms, mx, dq))
    if a.csv:
        new = not os.path.exists(a.csv) or os.path.getsize(a.csv) == 0
        with open(a.csv, "a") as f:
            if new:
                f.write("date,label,reference,candidate,joint,peak_applied_Nm,rms_diff_pct,"
                        "max_diff_pct,max_position_diff_mrad,com_max_diff_mm,ft_rms_diff_pct\n")
            for name, peak, rms, mx, dq in rows:
                f.write(f"{datetime.date.today()},{a.label},{os.path.basename(a.reference)},"
                        f"{os.path.basename(a.candidate)},{name},{peak:.4g},{rms:.3g},{mx:.3g},"
                        f"{dq:.3g},{com_max:.3g},{ft_rms:.3g}\n")


if __name__ == "__main__":
    main()
