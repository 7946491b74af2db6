#!/usr/bin/env python3
"""Writes a KITTI-layout drive (velodyne/NNNNNN.bin, float32 x y z intensity) as a ROS 1 bag of
sensor_msgs/PointCloud2 with ROS's own writer (Debian's python3-rosbag), one message every 0.1 s
from 100 s, and the scans' times as KITTI's times.txt, for the golden test: the same drive fused
from both gives the same mesh, bit for bit. A drive simulated with --sweep-seconds (times.txt,
times/NNNNNN.bin, poses_tum.txt) is stamped 100 s after its own frame times, its messages carry a
float32 `time` field (s after the stamp, Velodyne's), and its trajectory is written again with the
same 100 s added as OUT_times.txt's stem + "_tum.txt" (scripts/deskew_benchmark.sh).

Usage: kitti_to_ros1_bag.py DRIVE_DIR OUT.bag OUT_times.txt [lz4|bz2|none]"""
import os
import sys

import numpy as np
import rosbag
import rospy
from sensor_msgs.msg import PointCloud2, PointField
from std_msgs.msg import Header


def sweep_times(drive):
    """The frame times of a drive simulated with sweeps that take time, or None."""
    path = os.path.join(drive, "times.txt")
    return [float(line) for line in open(path)] if os.path.isdir(os.path.join(drive, "times")) and os.path.exists(path) else None


def cloud_messages(drive):
    """(stamp, PointCloud2) of each scan of the drive, stamped 100 s, 100.1 s, ... (or 100 s + its frame time)."""
    scans = sorted(f for f in os.listdir(os.path.join(drive, "velodyne")) if f.endswith(".bin"))
    fields = [PointField("x", 0, PointField.FLOAT32, 1), PointField("y", 4, PointField.FLOAT32, 1),
              PointField("z", 8, PointField.FLOAT32, 1), PointField("intensity", 12, PointField.FLOAT32, 1)]
    frame_times = sweep_times(drive)
    if frame_times:
        fields.append(PointField("time", 16, PointField.FLOAT32, 1))
    for k, name in enumerate(scans):
        data = np.fromfile(os.path.join(drive, "velodyne", name), dtype="<f4")
        step = 16
        if frame_times:
            t = np.fromfile(os.path.join(drive, "times", name), dtype="<f4")
            data = np.column_stack([data.reshape(-1, 4), t]).astype("<f4").ravel()
            step = 20
            stamp = rospy.Time.from_sec(100 + frame_times[k])
        else:
            stamp = rospy.Time(100 + k // 10, (k % 10) * 100000000)
        n = data.size // (step // 4)
        yield stamp, PointCloud2(header=Header(frame_id="velodyne", stamp=stamp), height=1, width=n, fields=fields,
                                 is_bigendian=False, point_step=step, row_step=step * n, data=data.tobytes(), is_dense=False)


def main():
    drive, bag_path, times_path = sys.argv[1:4]
    compression = sys.argv[4] if len(sys.argv) > 4 else "none"
    with rosbag.Bag(bag_path, "w", compression=compression) as bag, open(times_path, "w") as times:
        for k, (stamp, msg) in enumerate(cloud_messages(drive)):
            bag.write("/velodyne_points", msg, stamp)
            times.write("%.9f\n" % stamp.to_sec() if sweep_times(drive) else "%d.%d\n" % (100 + k // 10, k % 10))
    if sweep_times(drive):
        with open(os.path.join(drive, "poses_tum.txt")) as src, open(os.path.splitext(times_path)[0] + "_tum.txt", "w") as out:
            for line in src:
                v = line.split()
                out.write(" ".join(["%.9f" % (100 + float(v[0]))] + v[1:]) + "\n")


if __name__ == "__main__":
    main()
