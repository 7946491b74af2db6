"""Velodyne data packets written from the manuals' layout (12 blocks of flag, azimuth and 32 x
(distance, intensity); timestamp, return mode, product byte), and pcaps of them (Ethernet, IPv4,
UDP to port 2368), for the tests (python/tests/test_velodyne.py, tests/cli/test_recordings.sh).

Usage: velodyne_pcap.py MODEL PACKETS OUT.pcap [FIRST_AZIMUTH]   (MODEL: VLP16, VLP32C, HDL32E, HDL64E)"""
import struct
import sys

# model: (product byte, lasers, µs a block, when channel j fires after its block's first)
MODELS = {
    "VLP16": (0x22, 16, 110.592, lambda j: (j // 16) * 55.296 + (j % 16) * 2.304),
    "VLP32C": (0x28, 32, 55.296, lambda j: (j // 2) * 2.304),
    "HDL32E": (0x21, 32, 46.08, lambda j: j * 1.152),
    "HDL64E": (0x00, 64, 0.0, lambda j: 0.0),
}


def packet(model, k, raw, first=9000):
    """Packet k of a sensor turning at 10 Hz (0.36 hundredths of a degree a microsecond); raw(k, block, j) in counts."""
    product, lasers, block_us, _ = MODELS[model]
    step = round(0.36 * (block_us or 48))
    b = bytearray(1206)
    for blk in range(12):
        firing = blk // 2 if lasers == 64 else blk
        flag = 0xDDFF if lasers == 64 and blk % 2 else 0xEEFF
        struct.pack_into("<HH", b, 100 * blk, flag, (first + step * (6 if lasers == 64 else 12) * k + step * firing) % 36000)
        for j in range(32):
            struct.pack_into("<HB", b, 100 * blk + 4 + 3 * j, raw(k, blk, j), 60)
    struct.pack_into("<IBB", b, 1200, 5000 + 1327 * k, 0x37 if lasers < 64 else ord("T"), product)
    return bytes(b)


def write_pcap(path, packets, port=2368):
    out = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
    for n, payload in enumerate(packets):
        udp = struct.pack(">HHHH", 2369, port, 8 + len(payload), 0) + payload
        ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), n, 0, 64, 17, 0, bytes([192, 168, 1, 201]), bytes([192, 168, 1, 77])) + udp
        frame = b"\xff" * 6 + b"\x60\x76\x88\x00\x00\x01" + b"\x08\x00" + ip
        out += struct.pack("<IIII", 1700000000, 1327 * n, len(frame), len(frame)) + frame
    with open(path, "wb") as f:
        f.write(out)


if __name__ == "__main__":
    model, count, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    first = int(sys.argv[4]) if len(sys.argv) > 4 else 9000
    write_pcap(out, [packet(model, k, lambda k, b, j: 0 if (3 * k + b + j) % 11 == 5 else 1500 + (97 * k + 31 * b + 7 * j) % 20000, first)
                     for k in range(count)])
