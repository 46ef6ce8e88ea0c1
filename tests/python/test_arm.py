"""scoopsim.Arm on the lander's URDF. info() against the URDF read with xml.etree (joint names,
efforts); gravity_torques against `scoopsim arm info` (its table at the named poses, 6 significant
digits) and linear in g (closed form); jacobian against central finite differences of the tip's
position (link_pose), and its angular rows unit joint axes (closed form)."""

import os
import subprocess
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import scoopsim
from conftest import BIN, SOURCE

URDF = os.path.join(SOURCE, "assets", "lander_arm.urdf")
POSES = {"zero": [0, 0, 0, 0, 0, 0], "stowed": [-1.5, 1.5708, -2.65, 2.9, 0, 0],
         "unstowed": [0, 1.5707, -1.5707, 0, 1.5707, 0],
         "digging": [0, 0.8537, -1.5707, 0.7171, 1.5, 0]}  # arm/arm_model.h kLanderPoses


def test_info_reads_the_urdf():
    arm = scoopsim.Arm(URDF)
    info = arm.info()
    assert info["tip_link"] == "l_scoop"
    assert arm.dof == len(info["joints"]) == 6
    efforts = {j.get("name"): float(j.find("limit").get("effort"))
               for j in ET.parse(URDF).getroot().iter("joint") if j.find("limit") is not None}
    for j in info["joints"]:
        assert j["effort"] == efforts[j["name"]]


def test_gravity_torques_equal_the_cli_and_scale_with_g():
    arm = scoopsim.Arm(URDF)
    text = subprocess.run([BIN, "arm", "info", URDF, "--gravity", "1.3"], check=True,
                          capture_output=True, text=True).stdout
    rows = {line.split()[0]: line.split()[1:] for line in text.splitlines()
            if line.split() and line.split()[0] in POSES}
    assert set(rows) == set(POSES)
    for name, q in POSES.items():
        cli = np.array([float(v.rstrip("!")) for v in rows[name]])
        tau = arm.gravity_torques(np.array(q, float), 1.3)
        np.testing.assert_allclose(tau, cli, rtol=1e-5, atol=1e-5 * np.abs(cli).max())
    q = np.array(POSES["digging"], float)
    np.testing.assert_allclose(arm.gravity_torques(q, 2 * 3.71), 2 * arm.gravity_torques(q, 3.71),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(arm.gravity_torques(q, 0.0), np.zeros(6))
    with pytest.raises(ValueError):
        arm.gravity_torques(q[:3], 3.71)


def test_jacobian_is_the_derivative_of_the_tip_position():
    arm = scoopsim.Arm(URDF)
    q = np.array(POSES["digging"], float)
    J = arm.jacobian(q)
    assert J.shape == (6, 6)
    h = 1e-6
    for i in range(6):
        dq = np.zeros(6)
        dq[i] = h
        dp = (arm.link_pose(q + dq)[:3, 3] - arm.link_pose(q - dq)[:3, 3]) / (2 * h)
        np.testing.assert_allclose(J[:3, i], dp, atol=1e-7)
    np.testing.assert_allclose(np.linalg.norm(J[3:], axis=0), 1.0, rtol=1e-12)
