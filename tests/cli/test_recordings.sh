#!/usr/bin/env bash
# Recordings through the CLI: `info`, `reconstruct --scan` and `fuse --poses` on the real Ouster
# recordings of ../shared/data (skipped when absent), and bad recordings: exit 3 (or 2 for a
# missing argument) naming the file and what is wrong, with nothing written.
set -u
cli="$1" data="$2"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
source "$(dirname "$0")/expect.sh"
out="$dir/out.ply"

# --- Bad recordings: nothing is written.
printf 'hello' > "$dir/text.pcap"
printf '{"beam_altitude_angles": [1, 2], "beam_azimuth_angles": [0, 0], "lidar_mode": "512x10"}' > "$dir/text.json"
expect 3 "text.pcap: not a packet capture" -- "$cli" reconstruct "$dir/text.pcap" -o "$out"
expect 3 "text.pcap: not a packet capture" -- "$cli" info "$dir/text.pcap"
# --- Velodyne pcaps (tests/io/velodyne_pcap.py: packets written from the manuals' layout).
vp="$(dirname "$0")/../io/velodyne_pcap.py"
/usr/bin/python3 "$vp" VLP16 75 "$dir/vlp16.pcap" 35000
expect 0 "Velodyne VLP-16, strongest return, 16 lasers \(built-in VLP-16\), UDP port 2368, pcap" -- "$cli" info "$dir/vlp16.pcap"
expect 0 "2 scans \(2 partial: less than a revolution\), 26182 points" -- "$cli" info "$dir/vlp16.pcap"
expect 0 "vlp16.pcap scan 1: .* triangles" -- "$cli" reconstruct "$dir/vlp16.pcap" --scan 1 -o "$dir/vlp16.ply"
/usr/bin/python3 "$vp" HDL64E 40 "$dir/hdl64.pcap"
expect 2 "without a product id \(an HDL-64E\?\) need the sensor's calibration.*--metadata" -- "$cli" reconstruct "$dir/hdl64.pcap" -o "$out"
printf 'lasers:\n- {laser_id: 0, vert_correction: 0.1}\n- {laser_id: 0, vert_correction: 0.2}\n' > "$dir/hdl64.yaml"
expect 3 "hdl64.yaml: Velodyne calibration: laser_id 0 repeats" -- "$cli" reconstruct "$dir/hdl64.pcap" -o "$out"
printf 'lasers:\n- {laser_id: 0, vert_correction: 0.1}\n- {laser_id: 1, vert_correction: 0.2}\n' > "$dir/two.yaml"
expect 3 "two.yaml: a calibration of 2 lasers for a Velodyne VLP-16, which has 16" -- "$cli" reconstruct "$dir/vlp16.pcap" --metadata "$dir/two.yaml" -o "$out"
check "no output after the failures" -- test ! -e "$out"
printf '#ROSBAG V2.0\nnot a bag at all' > "$dir/text.bag"
expect 3 "text.bag: not a readable ROS 1 bag|reads no ROS 1 bags" -- "$cli" reconstruct "$dir/text.bag" -o "$out"
mkdir -p "$dir/ros2" && : > "$dir/ros2/metadata.yaml"
expect 3 "ROS 2 bag" -- "$cli" info "$dir/ros2"
expect 2 "needs the sensor's trajectory.*--poses" -- "$cli" fuse "$dir/text.pcap" -o "$out"
check "no output after the failures" -- test ! -e "$out"

# --- The golden test: one simulated drive as KITTI layout and as a ROS 1 bag (written by ROS's own
# writer, lz4 chunks) gives the same map, bit for bit, whole, in tiles and live.
# (The layout's sensor.json says which rays returned nothing, the bag's clouds do not: the layout's
# map it matches is the one fused without them, --carve-empty-range 0.)
"$cli" simulate --frames 3 -o "$dir/drive" -q >/dev/null || { echo "simulate failed"; exit 1; }
if /usr/bin/python3 "$(dirname "$0")/../io/kitti_to_ros1_bag.py" "$dir/drive" "$dir/drive.bag" "$dir/times.txt" lz4 2>/dev/null \
   && "$cli" info "$dir/drive.bag" >/dev/null 2>&1; then
    for opts in "" "--tile-size 30" "--live"; do
        "$cli" fuse "$dir/drive" -o "$dir/kitti.ply" -q $opts --carve-empty-range 0 >/dev/null
        expect 0 "3 frames fused .*3 of 3 scans within its span" -- "$cli" fuse "$dir/drive.bag" --poses "$dir/drive/poses.txt" --times "$dir/times.txt" -o "$dir/bag.ply" -q $opts
        check "fuse $opts: the bag's map is the KITTI layout's, bit for bit" -- cmp -s "$dir/kitti.ply" "$dir/bag.ply"
    done
    expect 2 "KITTI poses have no times.*--times" -- "$cli" fuse "$dir/drive.bag" --poses "$dir/drive/poses.txt" -o "$dir/no.ply"
else
    echo "skip: python3-rosbag or this build's ROS 1 bag reader is absent (the golden test)"
fi

ouster="$data/ouster"
if [ ! -d "$ouster" ]; then
    echo "skip: $ouster is absent (the real recordings); $passed passed"
    [ "$fail" -eq 0 ]; exit
fi
pcap="$ouster/OS-2-128-U1_v2.3.0_1024x10.pcap"
expect 0 "1 scans .*per-point times: yes" -- "$cli" info "$pcap" --json "$dir/info.json"
check "info --json lists the scans" -- grep -q '"scans": 1' "$dir/info.json"
expect 0 "scan 0: .* triangles" -- "$cli" reconstruct "$pcap" -o "$out"
check "a mesh from the pcap" -- test -s "$out"
expect 0 "view: .* triangles, 119682 points" -- "$cli" view "$out" -o "$dir/view.html" --points "$pcap" --max-points 1000000
expect 2 "scan 5 asked for, but the recording holds 1" -- "$cli" reconstruct "$pcap" --scan 5 -o "$dir/five.ply"
check "nothing written for a scan that is not there" -- test ! -e "$dir/five.ply"
# Metadata of another sensor: the packets' size disagrees, exit 3 naming the packet.
expect 3 "packet [0-9]+.* bytes where the metadata's" -- "$cli" reconstruct "$pcap" --metadata "$ouster/OS-0-32-U1_v2.2.0_1024x10.json" -o "$dir/m.ply"
check "nothing written for mismatched metadata" -- test ! -e "$dir/m.ply"
# Ouster packets without their metadata beside them.
cp "$pcap" "$dir/alone.pcap"
expect 2 "no Velodyne data packet, and no sensor metadata: .*alone.json is absent.*--metadata" -- "$cli" reconstruct "$dir/alone.pcap" -o "$dir/a.ply"
# The SDK's one-packet capture: 1212-byte datagrams with Velodyne block flags, not a data packet.
expect 3 "VLP-16-one-packet.pcap: packet 0: 1212-byte datagrams to port 2368 with Velodyne block flags" -- "$cli" info "$ouster/VLP-16-one-packet.pcap"
# A pcap cut in the middle of a packet.
head -c 300000 "$pcap" > "$dir/cut.pcap" && cp "${pcap%.pcap}.json" "$dir/cut.json"
expect 3 "cut.pcap: packet [0-9]+ \(byte [0-9]+\)" -- "$cli" reconstruct "$dir/cut.pcap" -o "$dir/cut.ply"
# Fused with a trajectory: a sensor standing still for the second the recording lasts.
stamp=$("$cli" info "$pcap" --json "$dir/i.json" >/dev/null && python3 -c "import json; print(json.load(open('$dir/i.json'))['first_stamp_ns'] / 1e9)")
printf '%s 0 0 0 0 0 0 1\n%s 0 0 0 0 0 0 1\n' "$(python3 -c "print($stamp - 1)")" "$(python3 -c "print($stamp + 1)")" > "$dir/still.txt"
expect 0 "1 frames fused .*poses from --poses \(1 of 1 scans within its span, de-skewed\)" -- "$cli" fuse "$pcap" --poses "$dir/still.txt" -o "$dir/fused.ply" -q
"$cli" fuse "$pcap" --poses "$dir/still.txt" -o "$dir/fused_raw.ply" -q --deskew 0 >/dev/null
check "de-skewing a still sensor's sweep moves nothing" -- cmp -s "$dir/fused.ply" "$dir/fused_raw.ply"
if "$cli" info "$ouster/ouster_ros_512x10_raw.bag" >/dev/null 2>&1; then
    expect 0 "/os_node0/lidar_packets \(Ouster OS-0-128, RNG15_RFL8_NIR8, 128 x 512 packets\)" -- "$cli" info "$ouster/ouster_ros_512x10_raw.bag"
    expect 0 "scan 0: .* triangles" -- "$cli" reconstruct "$ouster/ouster_ros_512x10_raw.bag" -o "$dir/bag.ply"
fi
echo "$passed passed, $fail failed"
[ "$fail" -eq 0 ]
