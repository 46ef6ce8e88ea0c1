#!/usr/bin/env python3
"""Writes a saved run of an arm scene (scoopsim run -o RUN.h5) as a ROS 1 bag.

    tools/export_rosbag.py RUN.h5 -o OUT.bag [--epoch S]
    scoopsim export rosbag RUN.h5 -o OUT.bag

One message per /arm/ row on each per-row topic (the rows of /scoop/ and /arm/ are the same
instants), stamped and recorded at the row's time on the run's one clock (README "One clock":
t = 0 when the pour began) plus --epoch (default 0: the bag's time is the simulation's, as
Gazebo's /clock that the lander's stack runs on with use_sim_time), rounded to the nanosecond.
Topics (docs/ros.md):
  /joint_states          sensor_msgs/JointState: position, velocity, effort = applied torque
  /arm/joint_reference   sensor_msgs/JointState: position = the path's joint reference
  /arm/torque_demanded   sensor_msgs/JointState: effort = the PID's demand (before the clamp)
  /arm/effort_limit      sensor_msgs/JointState: effort = the limit the arm saturates at
                         (/arm/effort_limit x /arm/effort_derate; older files hold that product)
  /scoop/wrench          geometry_msgs/WrenchStamped, frame l_scoop: /scoop/force_scoop,
                         torque_scoop (about the scoop's centre of mass)
  /scoop/wrench_base     geometry_msgs/WrenchStamped, frame base_link: /scoop/force_world and
                         torque_world rotated by Rz(-arm_base_yaw) (base_link's axes are world's
                         turned by the yaw; the torque stays about the centre of mass)
  /arm_faults_status     owl_msgs/ArmFaultsStatus (the lander's layout: Header, uint64 value):
                         /arm/fault_bits, every bit active since the previous row
  /arm/fault_events      std_msgs/String, one per event at its time: "FLAG joint value limit"
  /tf                    tf2_msgs/TFMessage: each movable joint's parent -> child link transform
  /tf_static             tf2_msgs/TFMessage, once at the first row, latched: world -> base_link
                         (the root attributes arm_base_x, _y, _z, _yaw) and the URDF's fixed
                         joints
The link transforms are the URDF's joint chain (origin xyz, rpy as R = Rz(Y) Ry(P) Rx(R), then
the rotation by q about the joint's axis), computed here from the URDF named by the root
attribute arm_urdf (or --urdf); the test checks that the chain to l_scoop gives /scoop/pose.

Exit status: 0 written; 2 bad input (a missing file, a file without /arm/, a URDF that does not
match), one line on stderr naming the file and what it lacks. Needs python3-h5py, python3-numpy,
python3-rosbag and the ROS message packages (Debian: tools/install-deps.sh).
"""

import argparse
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
# The same flag names, bad-input error, file opening and reader of events.
from plot_fault_timeline import FLAGS, InputError, open_run, read_events  # noqa: E402

PER_ROW = ("time", "joint_position", "joint_velocity", "joint_reference", "torque_demanded",
           "torque_applied", "effort_limit", "fault_bits")
SCOOP = ("time", "force_scoop", "torque_scoop", "force_world", "torque_world")

# owl_msgs/ArmFaultsStatus as the lander's stack defines it (a Header and the uint64 bit set),
# with the flag values of arm/fault_monitor.h as constants. Made at run time by genpy (no
# catkin build): its md5 is that of this text, which a node built against the lander's own
# owl_msgs has only if the constants' names there are these. The lander's own code (nasa/
# ow_simulator's ow_lander Python) uses ArmFaultsStatus.NONE, HARDWARE, TRAJECTORY_GENERATION,
# COLLISION, E_STOP and NO_FORCE_DATA: NONE = 0 comes first, then the bits in order.
FAULTS_TYPE = "owl_msgs/ArmFaultsStatus"
FAULTS_TEXT = "Header header\nuint64 value\nuint64 NONE=0\n" + "".join(
    "uint64 %s=%d\n" % (name, bit) for bit, name in sorted(FLAGS.items()))


def stamp(t, epoch):
    """rospy.Time of run time t [s] plus epoch, to the nearest nanosecond."""
    import rospy
    ns = int(round((epoch + t) * 1e9))
    return rospy.Time(ns // 1000000000, ns % 1000000000)


def rpy_matrix(r, p, y):
    """URDF rpy: R = Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_matrix(axis, q):
    """Rotation by q [rad] about the unit vector axis (Rodrigues)."""
    x, y, z = axis
    c, s = np.cos(q), np.sin(q)
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def quaternion(m):
    """Unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method), w >= 0."""
    t = np.trace(m)
    if t > 0:
        s = 2 * np.sqrt(1 + t)
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2 * np.sqrt(1 + m[i, i] - m[j, j] - m[k, k])
        q = [0.0] * 4
        q[i], q[j], q[k] = s / 4, (m[j, i] + m[i, j]) / s, (m[k, i] + m[i, k]) / s
        q[3] = (m[k, j] - m[j, k]) / s
    q = np.array(q)
    return q if q[3] >= 0 else -q


class Urdf:
    """The joints of a URDF: name -> (type, parent, child, origin 4x4, axis)."""

    def __init__(self, path):
        try:
            root = ET.parse(path).getroot()
        except (OSError, ET.ParseError) as e:
            raise InputError("%s: cannot read the URDF (%s)" % (path, e))
        self.joints = {}
        for j in root.findall("joint"):
            origin = j.find("origin")
            xyz = [float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None
                                      else "0 0 0").split()]
            rpy = [float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None
                                      else "0 0 0").split()]
            t = np.eye(4)
            t[:3, :3] = rpy_matrix(*rpy)
            t[:3, 3] = xyz
            axis = j.find("axis")
            a = np.array([float(v) for v in (axis.get("xyz") if axis is not None
                                             else "1 0 0").split()])
            self.joints[j.get("name")] = (j.get("type"), j.find("parent").get("link"),
                                          j.find("child").get("link"), t, a / np.linalg.norm(a))

    def transform(self, name, q):
        """parent -> child transform of joint `name` at q [rad] (0 for a fixed joint)."""
        kind, _, _, origin, axis = self.joints[name]
        t = origin.copy()
        if kind in ("revolute", "continuous"):
            t[:3, :3] = origin[:3, :3] @ axis_matrix(axis, q)
        return t

    def chain_to(self, link):
        """The joints from the root to `link`, in order."""
        by_child = {j[2]: name for name, j in self.joints.items()}
        names = []
        while link in by_child:
            names.append(by_child[link])
            link = self.joints[by_child[link]][1]
        return names[::-1]


def base_transform(attrs):
    """world -> base_link: translation (arm_base_x, _y, _z), then yaw about world z."""
    t = np.eye(4)
    t[:3, :3] = axis_matrix((0.0, 0.0, 1.0), float(attrs["arm_base_yaw"]))
    t[:3, 3] = [float(attrs["arm_base_" + c]) for c in "xyz"]
    return t


def link_pose(urdf, joints, q, base, link):
    """World pose (4x4) of `link` at joint positions q (values in the order of `joints`)."""
    t = base.copy()
    for name in urdf.chain_to(link):
        t = t @ urdf.transform(name, q[joints.index(name)] if name in joints else 0.0)
    return t


def read_run(path, urdf_path=None):
    """The datasets and attributes the bag needs; InputError names the file and what it lacks."""
    with open_run(path) as f:
        if "arm" not in f:
            raise InputError("%s: no /arm/ group (expected a run of a scene with an arm: block, "
                             "scoopsim run -o)" % path)
        run = {"path": path}
        for group, names in (("arm", PER_ROW), ("scoop", SCOOP)):
            for name in names:
                if group + "/" + name not in f:
                    raise InputError("%s: missing dataset /%s/%s" % (path, group, name))
        # The rows both groups hold in full: each group's time is written last in a flush, so a
        # file killed in a flush (or read while its run writes) may hold more of the others.
        rows = min(f["arm/time"].shape[0], f["scoop/time"].shape[0])
        for name in PER_ROW:
            run[name] = f["arm/" + name][:rows]
        for name in SCOOP:
            run["scoop_" + name] = f["scoop/" + name][:rows]
        for name in ("arm_joints", "arm_urdf", "arm_base_x", "arm_base_y", "arm_base_z",
                     "arm_base_yaw"):
            if name not in f.attrs:
                raise InputError("%s: missing root attribute %s" % (path, name))
        run["joints"] = str(f.attrs["arm_joints"]).split(",")
        run["base"] = base_transform(f.attrs)
        run["yaw"] = float(f.attrs["arm_base_yaw"])
        # The limit the arm saturated at: the URDF's times the derate (files before the derate
        # had its own dataset hold the product in effort_limit).
        run["limit"] = run["effort_limit"] * (f["arm/effort_derate"][:rows]
                                              if "arm/effort_derate" in f else 1.0)
        run["events"] = read_events(f)
        urdf = urdf_path or str(f.attrs["arm_urdf"])
    n, dof = len(run["time"]), len(run["joints"])
    if run["joint_position"].shape != (n, dof):
        raise InputError("%s: /arm/joint_position has shape %s, expected (%d, %d) (one column per "
                         "joint of arm_joints)" % (path, run["joint_position"].shape, n, dof))
    if len(run["scoop_time"]) != n:
        raise InputError("%s: /scoop/time has %d rows, /arm/time %d (expected one /arm/ row per "
                         "/scoop/ row)" % (path, len(run["scoop_time"]), n))
    # arm_urdf is as the scene gave it, relative to the folder scoopsim ran in: tried from here,
    # from the run file's folder and from this checkout's root.
    if not os.path.isabs(urdf) and not os.path.isfile(urdf):
        for folder in (os.path.dirname(os.path.abspath(path)), os.path.join(HERE, "..")):
            if os.path.isfile(os.path.join(folder, urdf)):
                urdf = os.path.normpath(os.path.join(folder, urdf))
                break
        else:
            raise InputError("%s: no URDF at its arm_urdf %s (from here, the run's folder or %s); "
                             "give it with --urdf" % (path, urdf, os.path.normpath(
                                 os.path.join(HERE, ".."))))
    run["urdf"] = Urdf(urdf)
    missing = [j for j in run["joints"] if j not in run["urdf"].joints]
    if missing:
        raise InputError("%s: the URDF %s has no joint %s (arm_joints of %s)"
                         % (urdf, urdf, missing[0], path))
    return run


def transform_msg(parent, child, t, when):
    from geometry_msgs.msg import TransformStamped
    m = TransformStamped()
    m.header.stamp = when
    m.header.frame_id = parent
    m.child_frame_id = child
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = t[:3, 3]
    q = quaternion(t[:3, :3])
    r = m.transform.rotation
    r.x, r.y, r.z, r.w = q
    return m


def joint_state(names, when, position=(), velocity=(), effort=()):
    from sensor_msgs.msg import JointState
    m = JointState()
    m.header.stamp = when
    m.name = list(names)
    m.position, m.velocity, m.effort = list(position), list(velocity), list(effort)
    return m


def wrench(frame, when, force, torque):
    from geometry_msgs.msg import WrenchStamped
    m = WrenchStamped()
    m.header.stamp = when
    m.header.frame_id = frame
    w = m.wrench
    w.force.x, w.force.y, w.force.z = (float(v) for v in force)
    w.torque.x, w.torque.y, w.torque.z = (float(v) for v in torque)
    return m


def faults_class():
    """owl_msgs/ArmFaultsStatus, generated at run time from FAULTS_TEXT."""
    import genpy.dynamic
    from std_msgs.msg import Header
    text = FAULTS_TEXT + "\n" + "=" * 80 + "\nMSG: std_msgs/Header\n" + Header._full_text
    return genpy.dynamic.generate_dynamic(FAULTS_TYPE, text)[FAULTS_TYPE]


def event_text(event, joints):
    """One /arm/fault_events record as text: "JOINT_TORQUE_LIMIT joint j value V limit L"."""
    _, flag, k, value, limit = event
    return "%s joint %s value %.17g limit %.17g" % (
        FLAGS.get(flag, "flag %d" % flag), joints[k] if 0 <= k < len(joints) else "-", value,
        limit)


def write_bag(run, out, epoch):
    import rosbag
    from std_msgs.msg import String
    from tf2_msgs.msg import TFMessage
    urdf, joints = run["urdf"], run["joints"]
    moving = [n for n, j in urdf.joints.items() if j[0] in ("revolute", "continuous")]
    fixed = [n for n in urdf.joints if n not in moving]
    faults = faults_class()
    rz = axis_matrix((0.0, 0.0, 1.0), -run["yaw"])  # world axes -> base_link axes
    counts = {}
    with rosbag.Bag(out, "w") as bag:
        def put(topic, msg, when):
            # /tf_static latched, as tf2's static broadcaster: `rosbag play` keeps it for late
            # subscribers (RViz).
            header = None
            if topic == "/tf_static":  # the whole connection header, as rosbag takes it
                header = {"topic": topic, "type": msg._type, "md5sum": msg._md5sum,
                          "message_definition": msg._full_text, "latching": "1"}
            bag.write(topic, msg, when, connection_header=header)
            counts[topic] = counts.get(topic, 0) + 1

        t0 = stamp(run["time"][0], epoch)
        static = [transform_msg("world", "base_link", run["base"], t0)]
        static += [transform_msg(urdf.joints[n][1], urdf.joints[n][2], urdf.transform(n, 0.0), t0)
                   for n in fixed]
        put("/tf_static", TFMessage(transforms=static), t0)
        events = sorted(run["events"])
        e = 0
        for i, t in enumerate(run["time"]):
            when = stamp(t, epoch)
            while e < len(events) and events[e][0] <= t:  # events up to this row, in time order
                put("/arm/fault_events", String(data=event_text(events[e], joints)),
                    stamp(events[e][0], epoch))
                e += 1
            q = run["joint_position"][i]
            put("/joint_states", joint_state(joints, when, q, run["joint_velocity"][i],
                                             run["torque_applied"][i]), when)
            put("/arm/joint_reference", joint_state(joints, when, run["joint_reference"][i]),
                when)
            put("/arm/torque_demanded", joint_state(joints, when,
                                                    effort=run["torque_demanded"][i]), when)
            put("/arm/effort_limit", joint_state(joints, when, effort=run["limit"][i]), when)
            put("/scoop/wrench", wrench("l_scoop", when, run["scoop_force_scoop"][i],
                                        run["scoop_torque_scoop"][i]), when)
            put("/scoop/wrench_base", wrench("base_link", when, rz @ run["scoop_force_world"][i],
                                             rz @ run["scoop_torque_world"][i]), when)
            status = faults()
            status.header.stamp = when
            status.value = int(run["fault_bits"][i])
            put("/arm_faults_status", status, when)
            tf = [transform_msg(urdf.joints[n][1], urdf.joints[n][2],
                                urdf.transform(n, q[joints.index(n)] if n in joints else 0.0),
                                when) for n in moving]
            put("/tf", TFMessage(transforms=tf), when)
        for event in events[e:]:  # after the last row (none in practice)
            put("/arm/fault_events", String(data=event_text(event, joints)),
                stamp(event[0], epoch))
    return counts


def main(argv=None):
    parser = argparse.ArgumentParser(description="Write a scoopsim arm run (RUN.h5) as a ROS 1 "
                                     "bag")
    parser.add_argument("run", help="a scoopsim run file of a scene with an arm (.h5)")
    parser.add_argument("-o", "--output", required=True, help="the bag to write (.bag)")
    parser.add_argument("--epoch", type=float, default=0.0,
                        help="seconds added to the run's time for the bag's time (default 0)")
    parser.add_argument("--urdf", help="the arm's URDF (default: the run's attribute arm_urdf)")
    args = parser.parse_args(argv)
    try:
        run = read_run(args.run, args.urdf)
        if os.path.exists(args.output) and os.path.samefile(args.output, args.run):
            raise InputError("%s: -o names the run itself; give another output file"
                             % args.output)
        os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
        counts = write_bag(run, args.output, args.epoch)
    except InputError as e:
        print("export_rosbag: %s" % e, file=sys.stderr)
        return 2
    print("export_rosbag: wrote %s: %d rows, t = %.4f to %.4f s (bag time = run time + %g s); %s"
          % (args.output, len(run["time"]), run["time"][0], run["time"][-1], args.epoch,
             ", ".join("%s %d" % kv for kv in sorted(counts.items()))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
