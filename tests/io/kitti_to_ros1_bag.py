#!/usr/bin/env python3
"""Writes a KITTI-layout drive (velodyne/NNNNNN.bin, float32 x y z intensity) as a ROS 1 bag of
sensor_msgs/PointCloud2 with ROS's own writer (Debian's python3-rosbag), one message every 0.1 s
from 100 s, and the scans' times as KITTI's times.txt, for the golden test: the same drive fused
from both gives the same mesh, bit for bit.

Usage: kitti_to_ros1_bag.py DRIVE_DIR OUT.bag OUT_times.txt [lz4|bz2|none]"""
import os
import sys

import numpy as np
import rosbag
import rospy
from sensor_msgs.msg import PointCloud2, PointField
from std_msgs.msg import Header


def cloud_messages(drive):
    """(stamp, PointCloud2) of each scan of the drive, stamped 100 s, 100.1 s, ..."""
    scans = sorted(f for f in os.listdir(os.path.join(drive, "velodyne")) if f.endswith(".bin"))
    fields = [PointField("x", 0, PointField.FLOAT32, 1), PointField("y", 4, PointField.FLOAT32, 1),
              PointField("z", 8, PointField.FLOAT32, 1), PointField("intensity", 12, PointField.FLOAT32, 1)]
    for k, name in enumerate(scans):
        data = np.fromfile(os.path.join(drive, "velodyne", name), dtype="<f4")
        stamp = rospy.Time(100 + k // 10, (k % 10) * 100000000)
        yield stamp, PointCloud2(header=Header(frame_id="velodyne", stamp=stamp), height=1, width=data.size // 4, fields=fields,
                                 is_bigendian=False, point_step=16, row_step=16 * (data.size // 4), data=data.tobytes(), is_dense=False)


def main():
    drive, bag_path, times_path = sys.argv[1:4]
    compression = sys.argv[4] if len(sys.argv) > 4 else "none"
    with rosbag.Bag(bag_path, "w", compression=compression) as bag, open(times_path, "w") as times:
        for k, (stamp, msg) in enumerate(cloud_messages(drive)):
            bag.write("/velodyne_points", msg, stamp)
            times.write("%d.%d\n" % (100 + k // 10, k % 10))


if __name__ == "__main__":
    main()
