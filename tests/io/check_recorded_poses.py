#!/usr/bin/env python3
"""Checks a trajectory lidarsurf took from a recording (`info --save-poses`, TUM) against tf2's
own BufferCore (Debian's python3-tf2) fed the transforms write_tf_bag.py wrote: at each of its
stamps the pose must be tf2's lookup of SENSOR in FIXED within 1e-9 m and 1e-9 rad, and its
stamps must be every stamp of the moving links within the span they share.

Usage: check_recorded_poses.py TRANSFORMS_JSON OURS_TUM FIXED SENSOR SOURCE
SOURCE: tf (/tf and /tf_static), odom (/odom with /tf_static) or pose (/pose alone)."""
import json
import sys

import numpy as np
import rospy
import tf2_py
from geometry_msgs.msg import TransformStamped


def stamped(e, child=None):
    m = TransformStamped()
    m.header.stamp = rospy.Time(e["stamp_ns"] // 10**9, e["stamp_ns"] % 10**9)
    m.header.frame_id, m.child_frame_id = e["parent"], child or e["child"]
    m.transform.translation.x, m.transform.translation.y, m.transform.translation.z = e["t"]
    m.transform.rotation.x, m.transform.rotation.y, m.transform.rotation.z, m.transform.rotation.w = e["q"]
    return m


def main():
    transforms_path, ours_path, fixed, sensor, source = sys.argv[1:6]
    transforms = json.load(open(transforms_path))
    buffer = tf2_py.BufferCore(rospy.Duration(1000))
    moving = {"tf": transforms["tf"], "odom": transforms["odom"], "pose": transforms["pose"]}[source]
    if source != "pose":
        for e in transforms["static"]:
            buffer.set_transform_static(stamped(e), "test")
    links = {}
    for e in moving:
        buffer.set_transform(stamped(e, sensor if source == "pose" else None), "test")
        links.setdefault((e["parent"], e["child"]), []).append(e["stamp_ns"])
    # The moving links between FIXED and SENSOR: here every moving link is on the path, but for
    # map -> odom when FIXED is odom.
    on_path = [s for (parent, child), s in links.items() if not (fixed == "odom" and parent == "map")]
    first, last = max(min(s) for s in on_path), min(max(s) for s in on_path)
    expected = sorted({t for s in on_path for t in s if first <= t <= last})

    rows = [line.split() for line in open(ours_path) if line.strip() and not line.startswith("#")]
    stamps = []
    for r in rows:
        sec, frac = r[0].split(".")
        stamps.append(int(sec) * 10**9 + int(frac.ljust(9, "0")))
    failures = 0
    if stamps != expected:
        print("stamps differ: %d ours, %d expected" % (len(stamps), len(expected)))
        failures += 1
    worst_t = worst_r = 0.0
    for ns, r in zip(stamps, rows):
        x = buffer.lookup_transform_core(fixed, sensor, rospy.Time(ns // 10**9, ns % 10**9)).transform
        t = np.array([x.translation.x, x.translation.y, x.translation.z])
        q = np.array([x.rotation.x, x.rotation.y, x.rotation.z, x.rotation.w])
        ours_t, ours_q = np.array([float(v) for v in r[1:4]]), np.array([float(v) for v in r[4:8]])
        worst_t = max(worst_t, float(np.linalg.norm(ours_t - t)))
        q, ours_q = q / np.linalg.norm(q), ours_q / np.linalg.norm(ours_q)
        # 2 |q1 - q2| (q and -q the same rotation) is the angle between them, to first order.
        worst_r = max(worst_r, 2 * min(float(np.linalg.norm(ours_q - q)), float(np.linalg.norm(ours_q + q))))
    print("%d poses against tf2: worst %.2e m, %.2e rad" % (len(rows), worst_t, worst_r))
    if worst_t > 1e-9 or worst_r > 1e-9:
        failures += 1
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
