#!/usr/bin/env python3
"""Writes the fuzzers' seed corpus (fuzz/corpus/<harness>/): a few small valid files per format,
so libFuzzer starts from the shapes real files have. Deterministic; rerun after a format change."""
import math
import os
import struct
import sys

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
PTS = [(1.0 + 0.1 * i, -2.0 + 0.05 * i, 0.3 * math.sin(i)) for i in range(6)]


def put(harness, name, data):
    d = os.path.join(root, harness)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def lzf_literal(raw):
    """LZF stream made of literal runs only (control byte < 32 = run of ctrl + 1 bytes)."""
    out = b""
    for i in range(0, len(raw), 32):
        chunk = raw[i:i + 32]
        out += bytes([len(chunk) - 1]) + chunk
    return out


# KITTI .bin: the harness's first byte picks fields = 3 + byte % 6 (1 -> 4, 2 -> 5).
for fields, tag in ((4, b"\x01"), (5, b"\x02")):
    put("fuzz_kitti_bin", f"f{fields}.bin", tag + b"".join(struct.pack("<" + "f" * fields, *p, *([7.0] * (fields - 3))) for p in PTS))

# PLY points: ascii, binary little and big endian, with extra properties.
hdr = "ply\nformat {} 1.0\ncomment seed\nelement vertex {}\nproperty float x\nproperty float y\nproperty double z\nproperty uchar level\nend_header\n"
put("fuzz_ply_points", "ascii.ply", hdr.format("ascii", len(PTS)) + "".join(f"{x} {y} {z} 3\n" for x, y, z in PTS))
# One ascii record a line: a short row and a long one.
put("fuzz_ply_points", "ascii_rows.ply", hdr.format("ascii", len(PTS)) + "".join(f"{x} {y} {z}{'' if i == 1 else ' 3 7' if i == 2 else ' 3'}\n" for i, (x, y, z) in enumerate(PTS)))
for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
    put("fuzz_ply_points", fmt + ".ply", hdr.format(fmt, len(PTS)).encode() + b"".join(struct.pack(e + "ffdB", *p, 3) for p in PTS))

# PCD: ascii, binary and binary_compressed (fields stored one after another, then LZF).
def pcd_header(data):
    n = len(PTS)
    return (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
            f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n").encode()
put("fuzz_pcd_points", "ascii.pcd", pcd_header("ascii") + "".join(f"{x} {y} {z} 5\n" for x, y, z in PTS).encode())
put("fuzz_pcd_points", "binary.pcd", pcd_header("binary") + b"".join(struct.pack("<4f", *p, 5.0) for p in PTS))
soa = b"".join(struct.pack("<f", p[a] if a < 3 else 5.0) for a in range(4) for p in PTS)
packed = lzf_literal(soa)
put("fuzz_pcd_points", "compressed.pcd", pcd_header("binary_compressed") + struct.pack("<II", len(packed), len(soa)) + packed)

# XYZ / CSV text.
put("fuzz_text_points", "points.xyz", "".join(f"{x} {y} {z}\n" for x, y, z in PTS))
put("fuzz_text_points", "points.csv", "x,y,z,intensity\n" + "".join(f"{x},{y},{z},1\n" for x, y, z in PTS))
# A decimal-comma spreadsheet export with a byte-order mark and quoted names.
put("fuzz_text_points", "decimal_comma.csv", "\ufeff\"x\";\"y\";\"z\"\n" + "".join(f"{x};{y};{z}\n".replace(".", ",") for x, y, z in PTS))
# PCD sizes whose product wraps around 2^64 (2^45 + 1 records of 2^19 bytes).
put("fuzz_pcd_points", "wrap.pcd", b"VERSION 0.7\nFIELDS x y z pad\nSIZE 8 8 8 8\nTYPE F F F F\nCOUNT 1 1 1 65533\n"
    b"WIDTH 35184372088833\nHEIGHT 1\nPOINTS 35184372088833\nDATA binary_compressed\n" + struct.pack("<II", 16, 1 << 19) + bytes(16))

# KITTI poses: identity, then a yaw of 30 degrees with a translation.
c, s = math.cos(math.pi / 6), math.sin(math.pi / 6)
put("fuzz_poses", "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n" + f"{c} {-s} 0 1.5 {s} {c} 0 -2 0 0 1 0.25\n")

# Meshes: the harness's first byte picks PLY (even) or OBJ (odd).
tet_v = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
tet_f = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
mh = "ply\nformat {} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
put("fuzz_mesh_reader", "ascii.ply", "\x00" + mh.format("ascii") + "".join(f"{x} {y} {z}\n" for x, y, z in tet_v)
    + "".join(f"3 {a} {b} {c}\n" for a, b, c in tet_f))
put("fuzz_mesh_reader", "binary.ply", b"\x00" + mh.format("binary_little_endian").encode()
    + b"".join(struct.pack("<3f", *v) for v in tet_v) + b"".join(struct.pack("<B3i", 3, *f) for f in tet_f))
put("fuzz_mesh_reader", "quad.obj", "\x01# seed\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in tet_v) + "f 1 2 3 4\nf -1/1 -2/2 -3/3\n")

# Sensor JSON.
put("fuzz_sensor_json", "beams.json", '{"name": "s", "beams": 8, "elevation_max_deg": 5, "elevation_min_deg": -20, "azimuth_step_deg": 1}')
put("fuzz_sensor_json", "elevations.json", '{"elevations_deg": [2, 0, -2.5], "min_range": 1, "max_range": 80, "range_noise": 0.02, "dropout": 0.1}')

# Whole reconstruction: 12 parameter bytes (see fuzz_reconstruct.cpp), 3 sensor bytes, then int16
# points in 1/128 m. A noisy plane seen from above, and a box corner (three planes).
def recon(flags, pts):
    params = bytes([0, 90, 50, 10, 5, 3, 25, 109, 1, 0, 0, flags, 0, 0, 20])
    return params + b"".join(struct.pack("<3h", *(int(round(128 * c)) for c in p)) for p in pts)
plane = [(0.07 * i, 0.07 * j, 0.01 * math.sin(i * j)) for i in range(25) for j in range(25)]
corner = [q for i in range(18) for j in range(18) for q in ((0.08 * i, 0.08 * j, 0.0), (0.08 * i, 0.0, 0.08 * j), (0.0, 0.08 * i, 0.08 * j))]
put("fuzz_reconstruct", "plane", recon(0, plane))
put("fuzz_reconstruct", "corner_imls", recon(2, corner))
put("fuzz_reconstruct", "corner_far", recon(4, corner))
# The live view's stream (viz/live_stream.hpp): a header, a trajectory point, a removed block and a
# block of one triangle; and a header alone. Its blocks are in meshoptimizer's codecs: the messages
# come from lidarsurf's own encoder (PYTHONPATH=build/python), kept as they are without it.
try:
    import lidarsurf
except ImportError:
    lidarsurf = None
    print("make_corpus: lidarsurf is not importable (PYTHONPATH=build/python): fuzz_live_stream's seeds left as they are")
if lidarsurf is not None:
    def live(flags, blocks):
        pose = [[1, 0, 0, 1003], [0, 1, 0, 2004], [0, 0, 1, 10.5], [0, 0, 0, 1]]
        return lidarsurf.encode_live_message(3, (1000.0, 2000.0, 10.0), pose, [[1003, 2004, 10.5]], [(-1, 2, -3)],
                                             [((5, 6, -7), tri) for tri in blocks],
                                             reset=bool(flags & 1), final=bool(flags & 2), more=bool(flags & 4))
    tri = lidarsurf.Mesh([[1000, 2000, 10], [1001, 2000, 10], [1000, 2001, 10.5]], [[0, 1, 2]])
    put("fuzz_live_stream", "one_block", live(1, [tri]))
    put("fuzz_live_stream", "two_blocks_final", live(2, [tri, tri]))
    put("fuzz_live_stream", "header_only", live(4, []))
# Ouster pcaps (fuzz_ouster_pcap.cpp: 8 beams, 64 columns a frame, 16 a packet; the first byte
# picks the profile). One frame's packets over Ethernet/IPv4/UDP to port 7502, the larger ones
# in 1480-byte IPv4 fragments.
OUSTER = [("LEGACY", 12), ("RNG19_RFL8_SIG16_NIR16", 12), ("RNG19_RFL8_SIG16_NIR16_DUAL", 16), ("RNG15_RFL8_NIR8", 4),
          ("FUSA_RNG15_RFL8_NIR8_DUAL", 8)]


def ouster_packet(profile, px, frame, first):
    legacy = profile == "LEGACY"
    col = 16 + 8 * px + 4 if legacy else 12 + 8 * px
    b = bytearray((0 if legacy else 64) + 16 * col)
    if not legacy:
        struct.pack_into("<HH", b, 0, 1, frame)
    for c in range(16):
        at = (0 if legacy else 32) + c * col
        struct.pack_into("<QH", b, at, 10**9 + 50000 * (first + c), first + c)
        if legacy:
            struct.pack_into("<H", b, at + 10, frame)
            struct.pack_into("<I", b, at + col - 4, 0xFFFFFFFF)
        else:
            struct.pack_into("<H", b, at + 10, 1)
        for beam in range(8):
            struct.pack_into("<I", b, at + (16 if legacy else 12) + beam * px, (3000 + 40 * c + beam) if (c + beam) % 5 else 0)
    return bytes(b)


def pcap_of(datagrams, port=7502):
    out = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
    for n, payload in enumerate(datagrams):
        udp = struct.pack(">HHHH", 7245, port, 8 + len(payload), 0) + payload
        for off in range(0, len(udp), 1480):
            part = udp[off:off + 1480]
            more = 0x2000 if off + len(part) < len(udp) else 0
            ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(part), 100 + n, more | off // 8, 64, 17, 0, bytes([192, 168, 1, 10]),
                             bytes([192, 168, 1, 1])) + part
            frame = b"\xff" * 6 + b"\x02" * 6 + b"\x08\x00" + ip
            out += struct.pack("<IIII", 1700000000, 10 * n, len(frame), len(frame)) + frame
    return out


for i, (profile, px) in enumerate(OUSTER):
    packets = [ouster_packet(profile, px, 7, first) for first in range(0, 64, 16)] + [ouster_packet(profile, px, 8, 0)]
    put("fuzz_ouster_pcap", profile.lower() + ".pcap", bytes([i]) + pcap_of(packets))

# Velodyne pcaps (fuzz_velodyne_pcap.cpp: the first byte picks the model, 0x08 both returns, 0x40
# a calibration YAML): 1206-byte data packets to port 2368 crossing the azimuth's wrap.


def velodyne_packet(first_azimuth, step, stamp_us, product, mode=0x37, dual=False, banks=1):
    b = bytearray(1206)
    for blk in range(12):
        firing = blk // (2 if dual else 1) // banks
        flag = 0xDDFF if banks == 2 and blk % 2 else 0xEEFF
        struct.pack_into("<HH", b, 100 * blk, flag, (first_azimuth + step * firing) % 36000)
        for j in range(32):
            struct.pack_into("<HB", b, 100 * blk + 4 + 3 * j, 0 if (blk + j) % 7 == 3 else 2500 + 13 * j + blk, 40)
    struct.pack_into("<IBB", b, 1200, stamp_us, mode, product)
    return bytes(b)


put("fuzz_velodyne_pcap", "vlp16.pcap", bytes([0]) + pcap_of([velodyne_packet(35760 + 240 * k, 20, 800000000 + 1327 * k, 0x22) for k in range(3)], 2368))
put("fuzz_velodyne_pcap", "vlp16_dual.pcap", bytes([0x08]) + pcap_of([velodyne_packet(35880 + 120 * k, 20, 1000 + 664 * k, 0x22, 0x39, True) for k in range(3)], 2368))
put("fuzz_velodyne_pcap", "hdl32e.pcap", bytes([3]) + pcap_of([velodyne_packet(35800 + 192 * k, 16, 5000 + 553 * k, 0x21) for k in range(3)], 2368))
put("fuzz_velodyne_pcap", "hdl64e.pcap", bytes([4]) + pcap_of([velodyne_packet(35900 + 102 * k, 17, 7000 + 290 * k, 0x41, 0x54, False, 2) for k in range(3)], 2368))
put("fuzz_velodyne_pcap", "calibration.yaml", bytes([0x40]) + b"distance_resolution: 0.002\nlasers:\n- {laser_id: 0, vert_correction: -0.1, rot_correction: 0.02}\n"
    b"- laser_id: 1\n  vert_correction: 0.1\n  two_pt_correction_available: true\n  dist_correction_x: 0.03\nnum_lasers: 2\n")

# sensor_msgs/PointCloud2, ROS 1 serialization: float32 with a uint32 time and padding; float64
# big endian; an organized 2 x 3 cloud with a NaN.


def ros_string(s):
    return struct.pack("<I", len(s)) + s.encode()


def cloud2(fields, step, rows, cols, data, big=False):
    out = struct.pack("<III", 1, 100, 5) + ros_string("lidar") + struct.pack("<II", rows, cols) + struct.pack("<I", len(fields))
    for name, off, ty in fields:
        out += ros_string(name) + struct.pack("<IBI", off, ty, 1)
    return out + struct.pack("<BII", big, step, step * cols) + struct.pack("<I", len(data)) + data + b"\x00"


put("fuzz_point_cloud2", "float32_t.msg", cloud2([("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("t", 16, 6)], 24, 1, len(PTS),
                                                 b"".join(struct.pack("<fff4xI4x", *p, 1000 * i) for i, p in enumerate(PTS))))
put("fuzz_point_cloud2", "float64_big.msg", cloud2([("x", 0, 8), ("y", 8, 8), ("z", 16, 8), ("time", 24, 7)], 28, 1, len(PTS),
                                                   b"".join(struct.pack(">dddf", *p, 0.01 * i) for i, p in enumerate(PTS)), big=True))
put("fuzz_point_cloud2", "organized.msg", cloud2([("x", 0, 7), ("y", 4, 7), ("z", 8, 7)], 12, 2, 3,
                                                 b"".join(struct.pack("<fff", *p) for p in PTS[:5]) + struct.pack("<fff", *[float("nan")] * 3)))

# The same clouds in CDR (ROS 2): the encapsulation header, members aligned to their size from
# its end, strings with their NUL; little and big endian.


def cdr_cloud(fields, step, rows, cols, data, big=False):
    e = ">" if big else "<"
    out = bytearray(b"\x00\x00" if big else b"\x00\x01") + b"\x00\x00"

    def align(n):
        while (len(out) - 4) % n:
            out.append(0)

    def u32(v):
        align(4)
        out.extend(struct.pack(e + "I", v))

    def string(s):
        u32(len(s) + 1)
        out.extend(s.encode() + b"\x00")

    u32(100), u32(5), string("lidar"), u32(rows), u32(cols), u32(len(fields))
    for name, off, ty in fields:
        string(name), u32(off), out.append(ty), u32(1)
    out.append(big)
    u32(step), u32(step * cols), u32(len(data))
    out.extend(data)
    out.append(0)
    return bytes(out)


put("fuzz_cdr_point_cloud2", "float32_t.cdr", cdr_cloud([("x", 0, 7), ("y", 4, 7), ("z", 8, 7), ("t", 16, 6)], 24, 1, len(PTS),
                                                        b"".join(struct.pack("<fff4xI4x", *p, 1000 * i) for i, p in enumerate(PTS))))
put("fuzz_cdr_point_cloud2", "float64_big.cdr", cdr_cloud([("x", 0, 8), ("y", 8, 8), ("z", 16, 8), ("time", 24, 7)], 28, 1, len(PTS),
                                                          b"".join(struct.pack(">dddf", *p, 0.01 * i) for i, p in enumerate(PTS)), big=True))

# MCAP (fuzz_mcap.cpp): a schema, a channel and two PointCloud2 messages; unchunked, in an
# uncompressed chunk with its CRC, in zstd and lz4 chunks (Debian's zstd and lz4 tools), and with
# a summary section.
import subprocess
import zlib

MAGIC = b"\x89MCAP0\r\n"


def record(op, content):
    return bytes([op]) + struct.pack("<Q", len(content)) + content


def mstr(s):
    return struct.pack("<I", len(s)) + s.encode()


def mcap(chunk=None, summary=False):
    cloud = cdr_cloud([("x", 0, 7), ("y", 4, 7), ("z", 8, 7)], 12, 1, len(PTS), b"".join(struct.pack("<fff", *p) for p in PTS))
    schema = record(3, struct.pack("<H", 1) + mstr("sensor_msgs/msg/PointCloud2") + mstr("ros2msg") + mstr(""))
    channel = record(4, struct.pack("<HH", 1, 1) + mstr("/points") + mstr("cdr") + struct.pack("<I", 0))
    messages = b"".join(record(5, struct.pack("<HIQQ", 1, k, 100 + k, 100 + k) + cloud) for k in range(2))
    data = schema + channel + messages
    if chunk is not None:
        packed = {"": data, "zstd": subprocess.run(["zstd", "-q", "-c"], input=data, capture_output=True).stdout,
                  "lz4": subprocess.run(["lz4", "-q", "-c"], input=data, capture_output=True).stdout}[chunk]
        data = record(6, struct.pack("<QQQI", 100, 101, len(data), zlib.crc32(data)) + mstr(chunk) + struct.pack("<Q", len(packed)) + packed)
    out = MAGIC + record(1, mstr("ros2") + mstr("seed")) + data + record(15, struct.pack("<I", 0))
    start = 0
    if summary:
        start = len(out)
        out += schema + channel
    return out + record(2, struct.pack("<QQI", start, 0, 0)) + MAGIC


put("fuzz_mcap", "plain.mcap", mcap())
put("fuzz_mcap", "chunk.mcap", mcap(""))
put("fuzz_mcap", "zstd.mcap", mcap("zstd", summary=True))
put("fuzz_mcap", "lz4.mcap", mcap("lz4"))
# Poses (fuzz_tf.cpp): the first byte picks the encoding (bit 0: CDR) and the message (bits 1-2:
# TFMessage, Odometry, PoseStamped). A TFMessage with a chain of two links, an Odometry, a PoseStamped.


def ros1_header(stamp, frame):
    return struct.pack("<III", 0, stamp, 0) + ros_string(frame)


def cdr_writer():
    out = bytearray(b"\x00\x01\x00\x00")

    def align(n):
        while (len(out) - 4) % n:
            out.append(0)

    def put_(fmt, *v):
        align(struct.calcsize("<" + fmt[0]))
        out.extend(struct.pack("<" + fmt, *v))

    def string(s):
        put_("I", len(s) + 1)
        out.extend(s.encode() + b"\x00")

    return out, put_, string


POSE = (1.0, 2.0, 0.5, 0.0, 0.0, 0.38268343236, 0.92387953251)
links = [("odom", "base_link", 100), ("base_link", "lidar", 100), ("odom", "base_link", 101)]
put("fuzz_tf", "tf.ros1", bytes([0]) + struct.pack("<I", len(links)) +
    b"".join(ros1_header(t, p) + ros_string(c) + struct.pack("<7d", *POSE) for p, c, t in links))
out, put_, string = cdr_writer()
put_("I", len(links))
for p, c, t in links:
    put_("i", t), put_("I", 0), string(p), string(c)
    for v in POSE:
        put_("d", v)
put("fuzz_tf", "tf.cdr", bytes([1]) + bytes(out))
put("fuzz_tf", "odometry.ros1", bytes([2]) + ros1_header(100, "odom") + ros_string("base_link") + struct.pack("<7d", *POSE) + bytes(8 * 78))
put("fuzz_tf", "pose.ros1", bytes([4]) + ros1_header(100, "odom") + struct.pack("<7d", *POSE))
print("corpus written to", root, file=sys.stderr)
