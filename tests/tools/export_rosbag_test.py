#!/usr/bin/env python3
"""tools/export_rosbag.py and `scoopsim export rosbag` on the boulder fault run
(scenes/fault/boulder.yaml, ~10 s: label slow), read back with python3-rosbag:
- one message per /arm/ row on each per-row topic, one /tf_static (latched), one
  /arm/fault_events per event of /arm/fault_events;
- every stamp (header and record) the row's time to the nearest nanosecond (epoch 0), and
  --epoch adds its seconds;
- joint states, demanded torque, limits (URDF x derate, on a copy derated to 0.6; and a copy as
  files before the derate's dataset, the derated limit alone), the l_scoop wrench and the fault
  bits bit for bit equal to the HDF5; frame ids l_scoop, base_link, world;
- the base_link wrench: rotated back by Rz(arm_base_yaw) it is /scoop/force_world, torque_world
  (closed form, on a copy of the run given a yaw of 0.7 rad: the run's own yaw is 0);
- the /tf chain world -> l_scoop (the URDF in Python) against /scoop/pose, the pose Bullet gave
  the DEM (an independent oracle): with bullet_first timing the DEM's step to t uses the Bullet
  state at t, so /scoop/pose is l_scoop at the row's own q, to 1e-12 m and 1e-12 in the
  quaternion (found ~1e-15). The pose one step before (q - h qd, h the first row's time minus
  start_time) must be off by more than 1e-7 m (found ~3e-6): the check tells the two apart;
- the CLI writes the same bytes as the script;
- a file without /arm/ gives one line naming the file and /arm/, exit 2 (the script and the CLI)."""

import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
import rosbag
from cli_check import expect_refused, test_dir

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SCRIPT = os.path.join(ROOT, "tools", "export_rosbag.py")
sys.path.insert(0, os.path.join(ROOT, "tools"))
import export_rosbag  # noqa: E402  (its quaternion and matrices, to compose the bag's /tf)

PER_ROW = ("/joint_states", "/arm/joint_reference", "/arm/torque_demanded", "/arm/effort_limit",
           "/scoop/wrench", "/scoop/wrench_base", "/arm_faults_status", "/tf")


def export(args):
    return subprocess.run([sys.executable, SCRIPT] + args, capture_output=True, text=True)


def bits(a):
    """float64 values as their bits, to compare bit for bit."""
    return np.asarray(a, dtype=np.float64).view(np.uint64)


def read_bag(path):
    topics = {}
    with rosbag.Bag(path) as bag:
        for topic, msg, t, header in bag.read_messages(return_connection_header=True):
            topics.setdefault(topic, []).append((msg, t))
            assert header.get("latching", b"0") == (b"1" if topic == "/tf_static" else b"0"), topic
    return topics


def matrix(tf):
    """4x4 of a geometry_msgs/Transform."""
    r, p = tf.rotation, tf.translation
    x, y, z, w = r.x, r.y, r.z, r.w
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = [p.x, p.y, p.z]
    return m


def check_bag(topics, f, epoch=0.0):
    t = f["arm/time"][()]
    n = len(t)
    joints = str(f.attrs["arm_joints"]).split(",")
    events = f["arm/fault_events"][()]
    assert n > 500 and len(events) == 1, (n, len(events))
    for topic in PER_ROW:
        assert len(topics[topic]) == n, "%s: %d messages, %d rows" % (topic, len(topics[topic]), n)
    assert len(topics["/tf_static"]) == 1 and len(topics["/arm/fault_events"]) == len(events)
    expected_ns = np.round((epoch + t) * 1e9).astype(np.int64)
    for topic in PER_ROW:
        for (msg, when), ns in zip(topics[topic], expected_ns):
            stamps = [m.header.stamp for m in msg.transforms] if topic == "/tf" else [
                msg.header.stamp]
            assert when.to_nsec() == ns and all(s.to_nsec() == ns for s in stamps), (topic, ns)
    assert abs(topics["/arm/fault_events"][0][1].to_sec() - (epoch + events[0]["time"])) < 1e-9
    assert topics["/arm/fault_events"][0][0].data.startswith("JOINT_TORQUE_LIMIT joint %s "
                                                             % joints[events[0]["joint"]])

    def column(topic, field):
        return np.array([getattr(m, field) for m, _ in topics[topic]])

    for topic, field, name in (("/joint_states", "position", "joint_position"),
                               ("/joint_states", "velocity", "joint_velocity"),
                               ("/joint_states", "effort", "torque_applied"),
                               ("/arm/joint_reference", "position", "joint_reference"),
                               ("/arm/torque_demanded", "effort", "torque_demanded")):
        assert (bits(column(topic, field)) == bits(f["arm/" + name][()])).all(), (topic, field)
    limit = f["arm/effort_limit"][()]  # a file before the derate holds the derated limit here
    if "arm/effort_derate" in f:
        limit = limit * f["arm/effort_derate"][()]
    assert (bits(column("/arm/effort_limit", "effort")) == bits(limit)).all()
    assert all(list(m.name) == joints for m, _ in topics["/joint_states"])
    assert [m.value for m, _ in topics["/arm_faults_status"]] == [
        int(b) for b in f["arm/fault_bits"][()]]
    assert any(m.value == 32 for m, _ in topics["/arm_faults_status"])  # JOINT_TORQUE_LIMIT
    assert topics["/arm_faults_status"][0][0]._type == "owl_msgs/ArmFaultsStatus"

    def wrench(topic, frame):
        assert all(m.header.frame_id == frame for m, _ in topics[topic]), topic
        w = [m.wrench for m, _ in topics[topic]]
        return (np.array([[v.force.x, v.force.y, v.force.z] for v in w]),
                np.array([[v.torque.x, v.torque.y, v.torque.z] for v in w]))

    force, torque = wrench("/scoop/wrench", "l_scoop")
    assert (bits(force) == bits(f["scoop/force_scoop"][()])).all()
    assert (bits(torque) == bits(f["scoop/torque_scoop"][()])).all()
    return wrench("/scoop/wrench_base", "base_link")


def check_tf(topics, f):
    """world -> base_link -> ... -> l_scoop from the bag against /scoop/pose (module docstring)."""
    static = {(m.header.frame_id, m.child_frame_id): matrix(m.transform)
              for m in topics["/tf_static"][0][0].transforms}
    urdf = export_rosbag.Urdf(os.path.join(ROOT, "assets", "lander_arm.urdf"))
    chain = urdf.chain_to("l_scoop")
    pose = f["scoop/pose"][()]
    q, qd = f["arm/joint_position"][()], f["arm/joint_velocity"][()]
    h = f["scoop/time"][0] - f.attrs["start_time"]
    assert 1e-5 < h < 1e-4, h
    joints = str(f.attrs["arm_joints"]).split(",")
    worst_bag = worst_pose = worst_back = 0.0
    for i, (msg, _) in enumerate(topics["/tf"]):
        moving = {(m.header.frame_id, m.child_frame_id): matrix(m.transform)
                  for m in msg.transforms}
        m = static[("world", "base_link")]
        for name in chain:
            _, parent, child, _, _ = urdf.joints[name]
            m = m @ moving.get((parent, child), static.get((parent, child)))
        # The bag's l_scoop and /scoop/pose against the Python chain at q; the chain one step
        # back (q - h qd) against /scoop/pose, which must differ.
        here = export_rosbag.link_pose(urdf, joints, q[i], static[("world", "base_link")],
                                       "l_scoop")
        back = export_rosbag.link_pose(urdf, joints, q[i] - h * qd[i], static[("world",
                                                                               "base_link")],
                                       "l_scoop")
        worst_bag = max(worst_bag, np.abs(m - here).max())
        qh = pose[i, [4, 5, 6, 3]]
        for fk, worst in ((here, "pose"), (back, "back")):
            qq = export_rosbag.quaternion(fk[:3, :3])
            off = max(np.abs(fk[:3, 3] - pose[i, :3]).max(),
                      min(np.abs(qq - qh).max(), np.abs(qq + qh).max()))
            if worst == "pose":
                worst_pose = max(worst_pose, off)
            else:
                worst_back = max(worst_back, off)
    print("tf: bag's chain vs FK(q) %.3g; FK(q) vs /scoop/pose %.3g; FK(q - h qd) vs /scoop/pose "
          "%.3g (h %.6g s)" % (worst_bag, worst_pose, worst_back, h))
    assert worst_bag < 1e-12 and worst_pose < 1e-12, (worst_bag, worst_pose)
    assert worst_back > 1e-7, worst_back


def main():
    binary = sys.argv[1]
    with test_dir("export_rosbag") as d:
        run = os.path.join(d, "boulder.h5")
        subprocess.run([binary, "run", os.path.join(ROOT, "scenes", "fault", "boulder.yaml"),
                        "-o", run], check=True, cwd=ROOT, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        bag = os.path.join(d, "boulder.bag")
        result = export([run, "-o", bag])
        assert result.returncode == 0, result.stderr
        print(result.stdout.strip())
        with h5py.File(run, "r") as f:
            topics = read_bag(bag)
            force, torque = check_bag(topics, f)
            assert f.attrs["arm_base_yaw"] == 0
            assert (bits(force) == bits(f["scoop/force_world"][()])).all()
            check_tf(topics, f)
        # --epoch shifts every stamp; the CLI writes the same bag as the script.
        assert export([run, "-o", os.path.join(d, "e.bag"), "--epoch", "100"]).returncode == 0
        with h5py.File(run, "r") as f:
            check_bag(read_bag(os.path.join(d, "e.bag")), f, epoch=100.0)
        cli = subprocess.run([binary, "export", "rosbag", run, "-o", os.path.join(d, "cli.bag")],
                             capture_output=True, text=True)
        assert cli.returncode == 0, cli.stderr
        with open(bag, "rb") as a, open(os.path.join(d, "cli.bag"), "rb") as b:
            assert a.read() == b.read(), "the CLI's bag differs from the script's"
        # The base frame on a copy turned by 0.7 rad: Rz(yaw) base = world; its joints derated
        # to 0.6 (the limit is the product).
        yawed = os.path.join(d, "yawed.h5")
        shutil.copy(run, yawed)
        with h5py.File(yawed, "r+") as f:
            f.attrs["arm_base_yaw"] = 0.7
            f["arm/effort_derate"][...] = 0.6
        assert export([yawed, "-o", os.path.join(d, "yawed.bag")]).returncode == 0
        rz = export_rosbag.axis_matrix((0, 0, 1), 0.7)
        with h5py.File(yawed, "r") as f:
            force, torque = check_bag(read_bag(os.path.join(d, "yawed.bag")), f)
            for base, world in ((force, f["scoop/force_world"][()]),
                                (torque, f["scoop/torque_world"][()])):
                scale = np.abs(world).max()
                assert np.abs(base @ rz.T - world).max() <= 1e-14 * scale
                assert np.abs(base - world).max() > 0.1 * scale  # the yaw did turn it
        # A file from before the derate's dataset: effort_limit holds the derated limit.
        old = os.path.join(d, "old.h5")
        shutil.copy(yawed, old)
        with h5py.File(old, "r+") as f:
            f["arm/effort_limit"][...] = f["arm/effort_limit"][()] * f["arm/effort_derate"][()]
            del f["arm/effort_derate"]
        assert export([old, "-o", os.path.join(d, "old.bag")]).returncode == 0
        with h5py.File(old, "r") as f:
            check_bag(read_bag(os.path.join(d, "old.bag")), f)
        # Bad input: a file without /arm/.
        plain = os.path.join(d, "plain.h5")
        with h5py.File(plain, "w") as f:
            f["scoop/time"] = np.zeros(3)
        expect_refused(export, [([plain, "-o", os.path.join(d, "x.bag")], plain + ": no /arm/"),
                                ([os.path.join(d, "none.h5"), "-o", os.path.join(d, "x.bag")],
                                 "no such file")])
        # The CLI passes the script's refusal on: exit 2, its line on stderr, nothing more.
        cli = subprocess.run([binary, "export", "rosbag", plain, "-o", os.path.join(d, "y.bag")],
                             capture_output=True, text=True)
        assert cli.returncode == 2, (cli.returncode, cli.stderr)
        assert cli.stderr.strip().splitlines() == [cli.stderr.strip()], cli.stderr
        assert plain + ": no /arm/" in cli.stderr, cli.stderr
    print("export_rosbag: ok")


if __name__ == "__main__":
    main()
