#!/usr/bin/env python3
"""Writes small ROS 1 bags (Debian's python3-rosbag) whose poses are wrong in one way each, for
the bad-input tests of poses read from recordings: two scans of 100 points in frame "velodyne" at
100 s and 100.1 s, and /tf_static base_link -> velodyne, then per OUT_DIR/<case>.bag:
  loop          /tf odom -> base_link and base_link -> odom
  two_parents   /tf odom -> base_link and map -> base_link
  nan           /tf odom -> base_link with a NaN rotation
  truncated     /tf odom -> base_link, then a TFMessage cut short
  unlinked      /tf odom -> base_link, and no /tf_static (velodyne is not in the tree)
  static_only   /tf_static odom -> base_link as well (nothing moves)
  odom_only     no /tf: nav_msgs/Odometry of base_link in odom on /odometry

Usage: write_bad_tf_bags.py OUT_DIR"""
import math
import os
import sys

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import PointCloud2, PointField
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage


def transform(ns, parent, child, x=0.0, qw=1.0):
    m = TransformStamped()
    m.header.stamp, m.header.frame_id, m.child_frame_id = rospy.Time(ns // 10**9, ns % 10**9), parent, child
    m.transform.translation.x = x
    m.transform.rotation.w = qw
    return m


def cloud(ns):
    import struct
    data = b"".join(struct.pack("<3f", 5 * math.cos(i), 5 * math.sin(i), 0.1 * i) for i in range(100))
    fields = [PointField(n, 4 * k, PointField.FLOAT32, 1) for k, n in enumerate("xyz")]
    return PointCloud2(header=Header(frame_id="velodyne", stamp=rospy.Time(ns // 10**9, ns % 10**9)), height=1, width=100, fields=fields,
                       is_bigendian=False, point_step=12, row_step=1200, data=data, is_dense=True)


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    stamps = [100 * 10**9, 100 * 10**9 + 10**8]
    cases = {
        "loop": [("odom", "base_link"), ("base_link", "odom")],
        "two_parents": [("odom", "base_link"), ("map", "base_link")],
        "nan": [("odom", "base_link")],
        "truncated": [("odom", "base_link")],
        "unlinked": [("odom", "base_link")],
        "static_only": [],
        "odom_only": [],
    }
    for case, links in cases.items():
        with rosbag.Bag(os.path.join(out, case + ".bag"), "w") as bag:
            t0 = rospy.Time(100)
            if case != "unlinked":
                static = [transform(stamps[0], "base_link", "velodyne")]
                if case == "static_only":
                    static.append(transform(stamps[0], "odom", "base_link"))
                bag.write("/tf_static", TFMessage(static), t0)
            for k, ns in enumerate(stamps):
                t = rospy.Time(ns // 10**9, ns % 10**9)
                tfs = [transform(ns, p, c, x=float(k), qw=float("nan") if case == "nan" and k == 1 else 1.0) for p, c in links]
                if tfs:
                    bag.write("/tf", TFMessage(tfs), t)
                bag.write("/velodyne_points", cloud(ns), t)
            if case == "odom_only":
                for k, ns in enumerate(stamps):
                    m = Odometry()
                    m.header.stamp, m.header.frame_id, m.child_frame_id = rospy.Time(ns // 10**9, ns % 10**9), "odom", "base_link"
                    m.pose.pose.position.x, m.pose.pose.orientation.w = float(k), 1.0
                    bag.write("/odometry", m, m.header.stamp)
            if case == "truncated":
                good = TFMessage([transform(stamps[1], "odom", "base_link")])
                import io
                buf = io.BytesIO()
                good.serialize(buf)
                data = buf.getvalue()[:-20]
                bag.write("/tf", ("tf2_msgs/TFMessage", data, good._md5sum, TFMessage), rospy.Time(100, 2 * 10**8), raw=True)


if __name__ == "__main__":
    main()
