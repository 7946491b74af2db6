#!/usr/bin/env bash
# ROS 2 bags through the CLI, written by the format maintainers' own writers (tests/io/ros2:
# @mcap/core and @foxglove/cdr; rosbag2's sqlite3 layout through Python's sqlite3). The golden
# test: one simulated drive as KITTI layout, ROS 1 bag, db3 and MCAP (zstd, lz4, uncompressed
# chunks, no chunks and no summary with big-endian CDR) gives the same map, bit for bit. Then
# damaged files: exit 3 naming the file, the byte or message and what is wrong; nothing written.
# The real Ouster ROS 1 bag of ../shared/data, its packets and metadata written again as ROS 2
# messages in MCAP, gives the same mesh as the bag (skipped when absent). Skipped when the writers'
# npm packages are absent (scripts/setup.sh installs them).
set -u
cli="$1" data="${2:-}" part="${3:-all}"  # part: all, golden (the maps) or readers (the rest)
here="$(cd "$(dirname "$0")" && pwd)"
writers="$here/../io/ros2"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
source "$here/expect.sh"
if [ ! -d "$writers/node_modules/@mcap/core" ] || ! command -v node >/dev/null; then
    echo "skip: the MCAP and CDR writers are absent (npm ci in tests/io/ros2; scripts/setup.sh does it)"
    exit 0
fi
"$cli" simulate --frames 3 -o "$dir/drive" -q >/dev/null || { echo "simulate failed"; exit 1; }
node "$writers/write_ros2.mjs" "$dir/drive" "$dir" || { echo "write_ros2.mjs failed"; exit 1; }
/usr/bin/python3 "$writers/write_db3.py" "$dir/messages.cdr" "$dir/db3bag" || { echo "write_db3.py failed"; exit 1; }
# The scans' times, as kitti_to_ros1_bag.py writes them: 100 s, 100.1 s, ...
printf '100.0\n100.1\n100.2\n' > "$dir/times.txt"
poses=(--poses "$dir/drive/poses.txt" --times "$dir/times.txt")

if [ "$part" != golden ]; then
# --- info: the topics, their types and counts, and what fuse reads.
expect 0 "/velodyne_points +sensor_msgs/msg/PointCloud2 +3 " -- "$cli" info "$dir/zstd.mcap"
expect 0 "/chatter +std_msgs/msg/String +3 " -- "$cli" info "$dir/zstd.mcap"
expect 0 "/velodyne_points +sensor_msgs/msg/PointCloud2 +3 " -- "$cli" info "$dir/db3bag"
expect 0 "3 scans .* per-point times: no" -- "$cli" info "$dir/db3bag"
points=$(( $(cat "$dir"/drive/velodyne/*.bin | wc -c) / 16 ))  # the KITTI files' float32 x, y, z, intensity
for rec in db3bag/db3bag_0.db3 lz4.mcap chunked.mcap plain.mcap; do
    expect 0 "3 scans \(0 partial: less than a revolution\), $points points" -- "$cli" info "$dir/$rec"
done
fi

if [ "$part" != readers ]; then
# --- The golden test.
"$cli" fuse "$dir/drive" -o "$dir/kitti.ply" -q --carve-empty-range 0 >/dev/null  # the bag's clouds do not say which rays returned nothing
for rec in db3bag db3bag/db3bag_0.db3 zstd.mcap lz4.mcap chunked.mcap plain.mcap; do
    expect 0 "3 frames fused .*3 of 3 scans within its span" -- "$cli" fuse "$dir/$rec" "${poses[@]}" -o "$dir/ros2.ply" -q
    check "$rec: the map is the KITTI layout's, bit for bit" -- cmp -s "$dir/kitti.ply" "$dir/ros2.ply"
    rm -f "$dir/ros2.ply"
done
for opts in "--tile-size 30" "--live"; do
    "$cli" fuse "$dir/drive" -o "$dir/kitti.ply" -q $opts --carve-empty-range 0 >/dev/null
    "$cli" fuse "$dir/zstd.mcap" "${poses[@]}" -o "$dir/ros2.ply" -q $opts >/dev/null
    check "fuse $opts: the MCAP's map is the KITTI layout's, bit for bit" -- cmp -s "$dir/kitti.ply" "$dir/ros2.ply"
done
expect 0 "scan 2: .* triangles" -- "$cli" reconstruct "$dir/lz4.mcap" --scan 2 -o "$dir/scan2.ply"
# --time T: the scan stamped nearest T s after the first (the writer stamps them 0.1 s apart).
expect 0 "scan 1 \(0.120000 s asked for\)" -- "$cli" reconstruct "$dir/db3bag" --time 0.12 -o "$dir/t1.ply"
expect 0 "scan 2 \(0.160000 s asked for\)" -- "$cli" reconstruct "$dir/plain.mcap" --time 0.16 -o "$dir/t2.ply"
check "--time 0.16 is scan 2, bit for bit" -- cmp -s "$dir/scan2.ply" "$dir/t2.ply"
expect 2 "5.000000 s asked for, but the scans span 0.200000 s" -- "$cli" reconstruct "$dir/zstd.mcap" --time 5 -o "$dir/t5.ply"
expect 2 "excludes" -- "$cli" reconstruct "$dir/zstd.mcap" --time 0.1 --scan 1 -o "$dir/t5.ply"
check "nothing written for a time past the scans" -- test ! -e "$dir/t5.ply"
expect 2 "no topic /nothing" -- "$cli" reconstruct "$dir/zstd.mcap" --topic /nothing -o "$dir/none.ply"
expect 2 "/chatter carries std_msgs/msg/String" -- "$cli" reconstruct "$dir/db3bag" --topic /chatter -o "$dir/none.ply"
fi
if [ "$part" = golden ]; then
    echo "$passed passed, $fail failed"
    [ "$fail" -eq 0 ]; exit
fi

# --- Damaged files. edit.py FILE OUT WHAT: a copy of FILE with one thing broken.
cat > "$dir/edit.py" <<'EOF'
import glob, shutil, sqlite3, struct, sys
src, out, what = sys.argv[1:4]
if what.startswith("db3-"):
    shutil.copytree(src, out)
    db = sqlite3.connect(glob.glob(out + "/*.db3")[0])
    row, data = db.execute("SELECT id, data FROM messages WHERE topic_id = 2 ORDER BY id LIMIT 1 OFFSET 1").fetchone()
    data = bytes([0, 2]) + data[2:] if what == "db3-kind" else data[:200]
    db.execute("UPDATE messages SET data = ? WHERE id = ?", (data, row))
    db.commit()
    sys.exit(0)
b = bytearray(open(src, "rb").read())
at = 8  # the records after the magic: opcode, uint64 length, content
while b[at] != 6 and what != "length":
    at += 9 + struct.unpack_from("<Q", b, at + 1)[0]
if what == "length":      # the header record says more bytes than the file holds
    struct.pack_into("<Q", b, 9, len(b))
elif what == "smaller":   # the first chunk declares fewer inflated bytes than it holds
    struct.pack_into("<Q", b, at + 9 + 16, struct.unpack_from("<Q", b, at + 9 + 16)[0] - 1)
elif what == "larger":
    struct.pack_into("<Q", b, at + 9 + 16, struct.unpack_from("<Q", b, at + 9 + 16)[0] + 1)
elif what == "compression":  # "zstd" -> "zzzz"
    name = at + 9 + 28 + 4  # after the start and end times, the size, the CRC and the string's length
    assert b[name:name + 4] == b"zstd"
    b[name:name + 4] = b"zzzz"
elif what == "crc":       # a byte of the first chunk's (uncompressed: compression "") records
    b[at + 9 + 28 + 4 + 8 + 1000] ^= 0xFF
open(out, "wb").write(b)
EOF
edit() { /usr/bin/python3 "$dir/edit.py" "$@"; }
out="$dir/out.ply"
head -c 3000000 "$dir/zstd.mcap" > "$dir/cut.mcap"
expect 3 "cut.mcap: truncated: the record at byte [0-9]+ says [0-9]+ bytes" -- "$cli" fuse "$dir/cut.mcap" "${poses[@]}" -o "$out"
head -c 3000000 "$dir/plain.mcap" > "$dir/cut_plain.mcap"
expect 3 "cut_plain.mcap: truncated" -- "$cli" reconstruct "$dir/cut_plain.mcap" --scan 2 -o "$out"
edit "$dir/plain.mcap" "$dir/length.mcap" length
expect 3 "length.mcap: truncated: the record at byte 8 says" -- "$cli" info "$dir/length.mcap"
edit "$dir/zstd.mcap" "$dir/smaller.mcap" smaller
expect 3 "smaller.mcap: chunk at byte [0-9]+: the chunk inflates past its declared" -- "$cli" fuse "$dir/smaller.mcap" "${poses[@]}" -o "$out"
edit "$dir/lz4.mcap" "$dir/larger.mcap" larger
expect 3 "larger.mcap: chunk at byte [0-9]+: the chunk inflates to [0-9]+ bytes where it declares" -- "$cli" fuse "$dir/larger.mcap" "${poses[@]}" -o "$out"
edit "$dir/zstd.mcap" "$dir/zzzz.mcap" compression
expect 3 "zzzz.mcap: chunk at byte [0-9]+: chunk compression 'zzzz'" -- "$cli" reconstruct "$dir/zzzz.mcap" -o "$out"
edit "$dir/chunked.mcap" "$dir/crc.mcap" crc
expect 3 "crc.mcap: chunk at byte [0-9]+: CRC mismatch" -- "$cli" reconstruct "$dir/crc.mcap" -o "$out"
printf 'not an mcap file' > "$dir/text.mcap"
expect 3 "text.mcap: not an MCAP file" -- "$cli" info "$dir/text.mcap"
printf 'not a database, not at all: this text is longer than a sqlite header' > "$dir/text.db3"
expect 3 "text.db3: not a readable ROS 2 sqlite3 bag" -- "$cli" reconstruct "$dir/text.db3" -o "$out"
edit "$dir/db3bag" "$dir/bad_kind" db3-kind
expect 3 "bad_kind_0.db3|db3bag_0.db3: message 1 on /velodyne_points \(row [0-9]+\): CDR encapsulation kind 2" -- "$cli" fuse "$dir/bad_kind" "${poses[@]}" -o "$out"
edit "$dir/db3bag" "$dir/bad_short" db3-short
expect 3 "db3: message 1 on /velodyne_points \(row [0-9]+\): message truncated" -- "$cli" fuse "$dir/bad_short" "${poses[@]}" -o "$out"
mkdir "$dir/listed" && sed 's/db3bag_0.db3/absent.db3/' "$dir/db3bag/metadata.yaml" > "$dir/listed/metadata.yaml"
expect 4 "absent.db3: no such file \(listed in" -- "$cli" info "$dir/listed"
mkdir "$dir/zipped" && sed 's/compression_mode: ""/compression_mode: FILE/; s/compression_format: ""/compression_format: zstd/' "$dir/db3bag/metadata.yaml" > "$dir/zipped/metadata.yaml"
expect 3 "a bag compressed by rosbag2 \(zstd per FILE\)" -- "$cli" info "$dir/zipped"
check "no output after the failures" -- test ! -e "$out"

# --- The Ouster driver's raw packets in a ROS 2 bag: the real ROS 1 bag's, written again.
bag="$data/ouster/ouster_ros_512x10_raw.bag"
if [ -f "$bag" ] && "$cli" info "$bag" >/dev/null 2>&1 && /usr/bin/python3 "$writers/ros1_packets.py" "$bag" "$dir/ouster.msgs" 2>/dev/null; then
    node "$writers/write_packets.mjs" "$dir/ouster.msgs" "$dir/ouster.mcap"
    expect 0 "/os_node0/lidar_packets \(Ouster OS-0-128, RNG15_RFL8_NIR8, 128 x 512 packets\), ROS 2 bag" -- "$cli" info "$dir/ouster.mcap"
    "$cli" reconstruct "$bag" -o "$dir/ouster_ros1.ply" >/dev/null
    expect 0 "scan 0: .* triangles" -- "$cli" reconstruct "$dir/ouster.mcap" -o "$dir/ouster_ros2.ply"
    check "the Ouster packets give the same mesh from ROS 1 and ROS 2, bit for bit" -- cmp -s "$dir/ouster_ros1.ply" "$dir/ouster_ros2.ply"
else
    echo "skip: the real Ouster bag, python3-rosbag or this build's ROS 1 reader is absent"
fi
echo "$passed passed, $fail failed"
[ "$fail" -eq 0 ]
