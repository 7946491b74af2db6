#!/usr/bin/env python3
"""Read speed of recordings (docs/inputs.md, "Read speed"): writes 30 s of an Ouster pcap (the
OS-2-128 sweep of ../shared/data repeated with new frame ids), of a Velodyne HDL-64E pcap (data
packets written from the manual's layout, with a calibration of ../shared/data), of a ROS 1 bag of HDL-64E-sized
PointCloud2 messages (ROS's own writer), and of the same messages in CDR as a ROS 2 sqlite3 bag and
as an MCAP file of zstd chunks (Debian's zstd), then times `lidarsurf info` on each (median of 3).

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


def long_velodyne_pcap(path, scans):
    """An HDL-64E at 10 Hz: 6 firings a packet (an upper and a lower block each) 0.17 degree apart,
    353 packets a revolution, to UDP 2368; its S3 calibration beside the pcap."""
    rng = np.random.default_rng(2)
    revolution = []
    for k in range(353):
        b = bytearray(1206)
        for blk in range(12):
            struct.pack_into("<HH", b, 100 * blk, 0xDDFF if blk % 2 else 0xEEFF, (17 * (6 * k + blk // 2)) % 36000)
            struct.pack_into("<" + "HB" * 32, b, 100 * blk + 4, *[v for r in rng.integers(1500, 30000, 32) for v in (int(r), 60)])
        revolution.append(b)
    header = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
    with open(path, "wb") as f:
        f.write(header)
        for s in range(scans):
            for k, b in enumerate(revolution):
                t = 1700000000 * 10**6 + s * 100000 + k * 283
                struct.pack_into("<I", b, 1200, t % 3600000000)
                udp = struct.pack(">HHHH", 2369, 2368, 8 + len(b), 0) + b
                ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), k, 0, 64, 17, 0, bytes([192, 168, 1, 201]), bytes([192, 168, 1, 77]))
                frame = b"\xff" * 6 + b"\x60\x76\x88\x00\x00\x01\x08\x00" + ip + udp
                f.write(struct.pack("<IIII", t // 10**6, t % 10**6, len(frame), len(frame)) + frame)
    shutil.copy(os.path.join(SHARED, "..", "sensors", "velodyne_ros_drivers", "64e_s3-xiesc.yaml"), path[:-5] + ".yaml")


def hdl64_points():
    n = 125000
    dt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"), ("ring", "<u2"), ("pad", "<u2"), ("time", "<f4")])
    a = np.zeros(n, dt)
    rng = np.random.default_rng(1)
    az, r, el = rng.uniform(0, 2 * np.pi, n), rng.uniform(3, 60, n), rng.uniform(-0.4, 0.03, n)
    a["x"], a["y"], a["z"] = r * np.cos(az) * np.cos(el), r * np.sin(az) * np.cos(el), r * np.sin(el)
    a["time"], a["ring"] = az / (2 * np.pi) * 0.1, np.arange(n) % 64
    return a


FIELDS = [("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("intensity", 12, 7), ("ring", 16, 4), ("time", 20, 7)]


def long_bag(path, scans):
    import rosbag
    import rospy
    from sensor_msgs.msg import PointCloud2, PointField
    from std_msgs.msg import Header
    a = hdl64_points()
    n = len(a)
    fields = [PointField("x", 0, 7, 1), PointField("y", 4, 7, 1), PointField("z", 8, 7, 1), PointField("intensity", 12, 7, 1),
              PointField("ring", 16, 4, 1), PointField("time", 20, 7, 1)]
    with rosbag.Bag(path, "w") as bag:
        for k in range(scans):
            stamp = rospy.Time.from_sec(100 + 0.1 * k)
            bag.write("/velodyne_points", PointCloud2(header=Header(frame_id="velodyne", stamp=stamp), height=1, width=n, fields=fields,
                                                      point_step=24, row_step=24 * n, data=a.tobytes(), is_dense=True), stamp)


def cdr_cloud(k, a):
    """sensor_msgs/msg/PointCloud2 in little-endian CDR: every member here is 4-byte aligned as written."""
    def string(t):
        b = t.encode() + b"\0"
        return struct.pack("<I", len(b)) + b + b"\0" * (-len(b) % 4)
    out = b"\0\1\0\0" + struct.pack("<iI", 100 + k // 10, (k % 10) * 100000000) + string("velodyne")
    out += struct.pack("<III", 1, len(a), len(FIELDS))
    for name, offset, datatype in FIELDS:
        out += string(name) + struct.pack("<IB3xI", offset, datatype, 1)
    return out + struct.pack("<B3xIII", 0, 24, 24 * len(a), 24 * len(a)) + a.tobytes() + b"\1"


def long_db3(path, scans):
    import sqlite3
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)
    db = sqlite3.connect(os.path.join(path, "long_0.db3"))
    db.executescript("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT, type TEXT, serialization_format TEXT, offered_qos_profiles TEXT);"
                     "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB);"
                     "INSERT INTO topics VALUES (1, '/velodyne_points', 'sensor_msgs/msg/PointCloud2', 'cdr', '');")
    a = hdl64_points()
    for k in range(scans):
        db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (1, ?, ?)", ((100 * 10 + k) * 10**8, cdr_cloud(k, a)))
    db.commit()
    open(os.path.join(path, "metadata.yaml"), "w").write("rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n"
                                                          "  relative_file_paths:\n    - long_0.db3\n")


def long_mcap(path, scans):
    import zlib
    record = lambda op, content: bytes([op]) + struct.pack("<Q", len(content)) + content
    text = lambda t: struct.pack("<I", len(t)) + t.encode()
    a = hdl64_points()
    schema = record(3, struct.pack("<H", 1) + text("sensor_msgs/msg/PointCloud2") + text("ros2msg") + text(""))
    channel = record(4, struct.pack("<HH", 1, 1) + text("/velodyne_points") + text("cdr") + struct.pack("<I", 0))
    with open(path, "wb") as f:  # as a ROS 2 recorder writes it: chunks with their message indexes, a summary
        f.write(b"\x89MCAP0\r\n" + record(1, text("ros2") + text("recording_speed.py")))
        for k in range(scans):  # a chunk a message, as with a chunk size under a scan's
            t = (100 * 10 + k) * 10**8
            prefix = schema + channel if k == 0 else b""
            raw = prefix + record(5, struct.pack("<HIQQ", 1, k, t, t) + cdr_cloud(k, a))
            packed = subprocess.run(["zstd", "-q", "-1", "-c"], input=raw, capture_output=True, check=True).stdout
            f.write(record(6, struct.pack("<QQQI", t, t, len(raw), zlib.crc32(raw)) + text("zstd") + struct.pack("<Q", len(packed)) + packed))
            f.write(record(7, struct.pack("<HIQQ", 1, 16, t, len(prefix))))
        f.write(record(15, struct.pack("<I", 0)))
        start = f.tell()
        f.write(schema + channel + record(2, struct.pack("<QQI", start, 0, 0)) + b"\x89MCAP0\r\n")


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
    rows = [("Ouster OS-2-128 pcap", os.path.join(work, "long.pcap"), long_pcap),
            ("Velodyne HDL-64E pcap", os.path.join(work, "velodyne.pcap"), long_velodyne_pcap), ("ROS 1 bag, PointCloud2", os.path.join(work, "long.bag"), long_bag),
            ("ROS 2 bag (sqlite3), PointCloud2", os.path.join(work, "long_db3"), long_db3),
            ("MCAP, zstd chunks, PointCloud2", os.path.join(work, "long.mcap"), long_mcap)]
    print("| recording | size | scans | time | real time x | peak memory |\n|---|---|---|---|---|---|")
    for name, path, write in rows:
        write(path, scans)
        seconds, peak = timed(cli, path)
        size = sum(os.path.getsize(os.path.join(path, f)) for f in os.listdir(path)) if os.path.isdir(path) else os.path.getsize(path)
        print("| %s | %d MB | %d | %.2f s | %.0f | %.0f MiB |" % (name, size / 1e6, scans, seconds, 0.1 * scans / seconds, peak))


if __name__ == "__main__":
    main()
