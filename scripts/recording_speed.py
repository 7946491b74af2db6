#!/usr/bin/env python3
"""Read speed of recordings (docs/inputs.md, "Read speed"): writes 30 s of an Ouster pcap (the
OS-2-128 sweep of ../shared/data repeated with new frame ids) and of a ROS 1 bag of HDL-64E-sized
PointCloud2 messages (ROS's own writer), then times `lidarsurf info` on each (median of 3).

Usage: recording_speed.py LIDARSURF WORK_DIR [SCANS]   (Debian's /usr/bin/python3: rosbag, numpy)"""
import os
import shutil
import statistics
import struct
import subprocess
import sys
import time

import numpy as np

SHARED = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "data", "ouster")
OUSTER = "OS-2-128-U1_v2.3.0_1024x10"


def long_pcap(path, scans):
    """The sweep's lidar datagrams (UDP 7502, in IPv4 fragments) `scans` times, frame id k each."""
    data = open(os.path.join(SHARED, OUSTER + ".pcap"), "rb").read()
    records, at = [], 24
    while at + 16 <= len(data):
        incl = struct.unpack_from("<I", data, at + 8)[0]
        records.append(bytearray(data[at + 16:at + 16 + incl]))
        at += 16 + incl
    first = lambda r: struct.unpack_from(">H", r, 20)[0] & 0x1FFF == 0  # IPv4 fragment offset 0
    lidar = [r for r in records if not first(r) or struct.unpack_from(">H", r, 36)[0] == 7502]
    with open(path, "wb") as f:
        f.write(data[:24])
        for k in range(scans):
            for r in lidar:
                if first(r):
                    struct.pack_into("<H", r, 44, k & 0xFFFF)  # Ethernet 14 + IP 20 + UDP 8 + 2: the frame id
                t = 1700000000 * 10**6 + k * 100000
                f.write(struct.pack("<IIII", t // 10**6, t % 10**6, len(r), len(r)) + bytes(r))
    shutil.copy(os.path.join(SHARED, OUSTER + ".json"), path[:-5] + ".json")


def long_bag(path, scans):
    import rosbag
    import rospy
    from sensor_msgs.msg import PointCloud2, PointField
    from std_msgs.msg import Header
    n = 125000
    dt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"), ("ring", "<u2"), ("pad", "<u2"), ("time", "<f4")])
    a = np.zeros(n, dt)
    rng = np.random.default_rng(1)
    az, r, el = rng.uniform(0, 2 * np.pi, n), rng.uniform(3, 60, n), rng.uniform(-0.4, 0.03, n)
    a["x"], a["y"], a["z"] = r * np.cos(az) * np.cos(el), r * np.sin(az) * np.cos(el), r * np.sin(el)
    a["time"], a["ring"] = az / (2 * np.pi) * 0.1, np.arange(n) % 64
    fields = [PointField("x", 0, 7, 1), PointField("y", 4, 7, 1), PointField("z", 8, 7, 1), PointField("intensity", 12, 7, 1),
              PointField("ring", 16, 4, 1), PointField("time", 20, 7, 1)]
    with rosbag.Bag(path, "w") as bag:
        for k in range(scans):
            stamp = rospy.Time.from_sec(100 + 0.1 * k)
            bag.write("/velodyne_points", PointCloud2(header=Header(frame_id="velodyne", stamp=stamp), height=1, width=n, fields=fields,
                                                      point_step=24, row_step=24 * n, data=a.tobytes(), is_dense=True), stamp)


def timed(cli, path):
    times, peaks = [], []
    for _ in range(3):
        t = time.perf_counter()
        run = subprocess.run(["/usr/bin/time", "-f", "%M", cli, "info", path], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        times.append(time.perf_counter() - t)
        peaks.append(int(run.stderr.strip().splitlines()[-1]) / 1024)
    return statistics.median(times), max(peaks)


def main():
    cli, work = sys.argv[1], sys.argv[2]
    scans = int(sys.argv[3]) if len(sys.argv) > 3 else 300
    os.makedirs(work, exist_ok=True)
    rows = [("Ouster OS-2-128 pcap", os.path.join(work, "long.pcap"), long_pcap), ("ROS 1 bag, PointCloud2", os.path.join(work, "long.bag"), long_bag)]
    print("| recording | size | scans | time | real time x | peak memory |\n|---|---|---|---|---|---|")
    for name, path, write in rows:
        write(path, scans)
        seconds, peak = timed(cli, path)
        print("| %s | %d MB | %d | %.2f s | %.0f | %.0f MiB |" % (name, os.path.getsize(path) / 1e6, scans, seconds, 0.1 * scans / seconds, peak))


if __name__ == "__main__":
    main()
