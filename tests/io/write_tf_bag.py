#!/usr/bin/env python3
"""Writes a simulated KITTI-layout drive with its poses held the way robots record them, for the
tests of poses read from recordings. From DRIVE_DIR/poses.txt (the simulator's sensor-to-world
poses P_k, scan k stamped 100 + 0.1 k s as kitti_to_ros1_bag.py does) it makes:
  - /tf_static: base_link -> velodyne, a fixed mount M;
  - /tf: odom -> base_link at every scan stamp, B_k = P_k M^-1 (so odom -> velodyne is P_k), and
    map -> odom, a slow drift sampled every 0.25 s (not at the scans' stamps);
  - /odom: nav_msgs/Odometry of base_link in odom, the same B_k;
  - /pose: geometry_msgs/PoseStamped of the sensor in odom, P_k.
It writes OUT_DIR/transforms.json (every transform, for the other writers and the checker),
OUT_DIR/tf.bag (ROS 1, Debian's python3-rosbag, with the scans on /velodyne_points) and
OUT_DIR/truth.txt (P_k as TUM).

Usage: write_tf_bag.py DRIVE_DIR OUT_DIR"""
import json
import math
import os
import sys

import numpy as np
import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped
from nav_msgs.msg import Odometry
from tf2_msgs.msg import TFMessage

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from kitti_to_ros1_bag import cloud_messages  # noqa: E402


def quaternion(r):
    # Rotation matrix -> (x, y, z, w), by the largest diagonal term (Shepperd).
    t = np.trace(r)
    if t > 0:
        s = 2 * math.sqrt(1 + t)
        return ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4)
    i = int(np.argmax(np.diag(r)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2 * math.sqrt(1 + r[i, i] - r[j, j] - r[k, k])
    q = [0.0, 0.0, 0.0, 0.0]
    q[i] = s / 4
    q[j] = (r[j, i] + r[i, j]) / s
    q[k] = (r[k, i] + r[i, k]) / s
    q[3] = (r[k, j] - r[j, k]) / s
    return tuple(q)


def rotation(yaw, pitch, roll):
    cy, sy, cp, sp, cr, sr = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch), math.cos(roll), math.sin(roll)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def pose(r, t):
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = r, t
    return m


def entry(stamp_ns, parent, child, m):
    return {"stamp_ns": stamp_ns, "parent": parent, "child": child, "t": [float(v) for v in m[:3, 3]], "q": [float(v) for v in quaternion(m[:3, :3])]}


def main():
    drive, out = sys.argv[1:3]
    os.makedirs(out, exist_ok=True)
    rows = np.loadtxt(os.path.join(drive, "poses.txt"), ndmin=2)
    sensor = [np.vstack([r.reshape(3, 4), [0, 0, 0, 1]]) for r in rows]
    stamps = [100_000_000_000 + k * 100_000_000 for k in range(len(sensor))]
    mount = pose(rotation(0.08, 0.03, -0.02), [1.2, -0.1, 1.7])
    base = [p @ np.linalg.inv(mount) for p in sensor]
    drift_stamps = [100_000_000_000 + k * 250_000_000 for k in range(int(0.1 * len(sensor) / 0.25) + 2)]
    drift = [pose(rotation(0.002 * k, 0, 0), [0.05 * k, 0.02 * k, 0]) for k in range(len(drift_stamps))]
    transforms = {
        "static": [entry(stamps[0], "base_link", "velodyne", mount)],
        "tf": [entry(s, "odom", "base_link", b) for s, b in zip(stamps, base)] + [entry(s, "map", "odom", d) for s, d in zip(drift_stamps, drift)],
        "odom": [entry(s, "odom", "base_link", b) for s, b in zip(stamps, base)],
        "pose": [entry(s, "odom", "", p) for s, p in zip(stamps, sensor)],
    }
    with open(os.path.join(out, "transforms.json"), "w") as f:
        json.dump(transforms, f)
    with open(os.path.join(out, "truth.txt"), "w") as f:
        for s, p in zip(stamps, sensor):
            q = quaternion(p[:3, :3])
            f.write("%d.%09d %.15g %.15g %.15g %.17g %.17g %.17g %.17g\n" % (s // 10**9, s % 10**9, *p[:3, 3], *q))

    def time(ns):
        return rospy.Time(ns // 10**9, ns % 10**9)

    def stamped(e):
        m = TransformStamped()
        m.header.stamp, m.header.frame_id, m.child_frame_id = time(e["stamp_ns"]), e["parent"], e["child"]
        m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = e["t"]
        m.transform.rotation.x, m.transform.rotation.y, m.transform.rotation.z, m.transform.rotation.w = e["q"]
        return m

    def set_pose(p, e):
        p.position.x, p.position.y, p.position.z = e["t"]
        p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = e["q"]

    with rosbag.Bag(os.path.join(out, "tf.bag"), "w") as bag:
        messages = []
        messages.append((stamps[0], "/tf_static", TFMessage([stamped(e) for e in transforms["static"]])))
        for e in transforms["tf"]:
            messages.append((e["stamp_ns"], "/tf", TFMessage([stamped(e)])))
        for e in transforms["odom"]:
            m = Odometry()
            m.header.stamp, m.header.frame_id, m.child_frame_id = time(e["stamp_ns"]), e["parent"], e["child"]
            set_pose(m.pose.pose, e)
            messages.append((e["stamp_ns"], "/odom", m))
        for e in transforms["pose"]:
            m = PoseStamped()
            m.header.stamp, m.header.frame_id = time(e["stamp_ns"]), e["parent"]
            set_pose(m.pose, e)
            messages.append((e["stamp_ns"], "/pose", m))
        for stamp, msg in cloud_messages(drive):
            messages.append((stamp.to_nsec(), "/velodyne_points", msg))
        for ns, topic, msg in sorted(messages, key=lambda m: m[0]):
            bag.write(topic, msg, time(ns))


if __name__ == "__main__":
    main()
