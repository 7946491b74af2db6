#!/usr/bin/env python3
"""Writes ROS 1 bags with ROS's own writer (Debian's python3-rosbag) for the recording tests.

write_ros1_bag.py OUT_DIR writes OUT_DIR/clouds.bag (uncompressed chunks), clouds_bz2.bag and
clouds_lz4.bag (the same messages in compressed chunks) and, per topic, OUT_DIR/<topic>.txt with the
points the bags hold: one line "x y z t i" per point with a return (t: seconds after the stamp,
i: the intensity the reader should give it; "none" when the message has none).
Topics:
  /float32_padded   x y z float32, intensity float32, t uint32 ns, ring uint16, reflectivity uint16
                    (the calibrated one: the reader's intensity); point_step 32
  /float64_big      x y z float64 big endian, time float32 s; 2 messages
  /organized        4 x 8 organized, float32, rays without return as NaN and as 0,0,0
  /hesai            x y z float32, timestamp float64 absolute seconds, intensity uint8
  /bad_row_step     a cloud whose row_step disagrees with its data (after one good message)
"""
import math
import os
import struct
import sys

import rosbag
import rospy
from sensor_msgs.msg import PointCloud2, PointField
from std_msgs.msg import Header

F32, F64, U16, U32 = PointField.FLOAT32, PointField.FLOAT64, PointField.UINT16, PointField.UINT32


def points(n, seed):
    # Points on a sphere of radius 5 + seed around the sensor, spread by a golden-angle spiral.
    out = []
    for i in range(n):
        z = 1 - 2 * (i + 0.5) / n
        r = math.sqrt(1 - z * z)
        a = i * 2.399963 + seed
        out.append(((5 + seed) * r * math.cos(a), (5 + seed) * r * math.sin(a), (5 + seed) * z))
    return out


def cloud(stamp, fields, step, rows, cols, data, big=False, row_step=None):
    m = PointCloud2()
    m.header = Header(frame_id="lidar", stamp=rospy.Time.from_sec(stamp))
    m.height, m.width = rows, cols
    m.fields = [PointField(name=n, offset=o, datatype=t, count=1) for n, o, t in fields]
    m.is_bigendian = big
    m.point_step = step
    m.row_step = step * cols if row_step is None else row_step
    m.data = bytes(data)
    m.is_dense = False
    return m


def main():
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for name, compression in (("clouds.bag", "none"), ("clouds_bz2.bag", "bz2"), ("clouds_lz4.bag", "lz4")):
        with rosbag.Bag(os.path.join(out, name), "w", compression=compression) as bag:
            expected = write_messages(bag)
    for topic, messages in expected.items():
        with open(os.path.join(out, topic + ".txt"), "w") as f:
            for k, lines in enumerate(messages):
                f.write("message %d\n" % k)
                for x, y, z, t, *i in lines:
                    f.write("%.9g %.9g %.9g %s %s\n" % (x, y, z, "none" if t is None else "%.9g" % t, "%.9g" % i[0] if i else "none"))


def write_messages(bag):
    """Writes the topics' messages; returns the points of each message by topic."""
    expected = {}
    # float32 with padding and a uint32 ns time (Ouster's driver layout).
    pts = points(50, 0)
    data = bytearray()
    lines = []
    for i, (x, y, z) in enumerate(pts):
        t_ns = 1000 * i
        data += struct.pack("<fff4xfIHH4x", x, y, z, 7.0, t_ns, i % 16, 3 * i + 1)
        xf, yf, zf = struct.unpack("<fff", struct.pack("<fff", x, y, z))
        lines.append((xf, yf, zf, t_ns * 1e-9, 3 * i + 1))
    bag.write("/float32_padded", cloud(100.0, [("x", 0, F32), ("y", 4, F32), ("z", 8, F32), ("intensity", 16, F32),
                                               ("t", 20, U32), ("ring", 24, U16), ("reflectivity", 26, U16)], 32, 1, len(pts), data),
              rospy.Time.from_sec(100.0))
    expected["float32_padded"] = [lines]
    # float64, big endian, float32 seconds (Velodyne's driver layout); two messages.
    expected["float64_big"] = []
    for k in range(2):
        pts = points(40, 1 + k)
        data = bytearray()
        lines = []
        for i, (x, y, z) in enumerate(pts):
            t = -0.1 + 0.0025 * i
            data += struct.pack(">dddf", x, y, z, t)
            lines.append((x, y, z, struct.unpack(">f", struct.pack(">f", t))[0]))
        bag.write("/float64_big", cloud(200.0 + 0.1 * k, [("x", 0, F64), ("y", 8, F64), ("z", 16, F64), ("time", 24, F32)],
                                        28, 1, len(pts), data, big=True), rospy.Time.from_sec(200.0 + 0.1 * k))
        expected["float64_big"].append(lines)
    # Organized 4 x 8: every third ray returned nothing (NaN), every fifth is all zeros.
    pts = points(32, 3)
    data = bytearray()
    lines = []
    for i, (x, y, z) in enumerate(pts):
        if i % 3 == 1:
            data += struct.pack("<fff", float("nan"), float("nan"), float("nan"))
        elif i % 5 == 2:
            data += struct.pack("<fff", 0, 0, 0)
        else:
            data += struct.pack("<fff", x, y, z)
            lines.append(struct.unpack("<fff", struct.pack("<fff", x, y, z)) + (None,))
    bag.write("/organized", cloud(300.0, [("x", 0, F32), ("y", 4, F32), ("z", 8, F32)], 12, 4, 8, data),
              rospy.Time.from_sec(300.0))
    expected["organized"] = [lines]
    # Absolute float64 timestamps (Hesai's driver layout).
    pts = points(20, 4)
    data = bytearray()
    lines = []
    for i, (x, y, z) in enumerate(pts):
        data += struct.pack("<fffdB", x, y, z, 400.0 + 0.001 * i, 200 - i)
        lines.append(struct.unpack("<fff", struct.pack("<fff", x, y, z)) + (0.001 * i, 200 - i))
    bag.write("/hesai", cloud(400.0, [("x", 0, F32), ("y", 4, F32), ("z", 8, F32), ("timestamp", 12, F64), ("intensity", 20, PointField.UINT8)],
                              21, 1, 20, data),
              rospy.Time.from_sec(400.0))
    expected["hesai"] = [lines]
    # One good message, then one whose row_step is 4 bytes short of its data.
    good = bytearray(struct.pack("<fff", 1, 2, 3) * 4)
    bag.write("/bad_row_step", cloud(500.0, [("x", 0, F32), ("y", 4, F32), ("z", 8, F32)], 12, 1, 4, good), rospy.Time.from_sec(500.0))
    bag.write("/bad_row_step", cloud(500.1, [("x", 0, F32), ("y", 4, F32), ("z", 8, F32)], 12, 1, 4, good, row_step=44),
              rospy.Time.from_sec(500.1))
    return expected


if __name__ == "__main__":
    main()
