#!/usr/bin/env bash
# Poses read from recordings through the CLI. A simulated drive's true sensor poses are written
# the way robots record them (tests/io/write_tf_bag.py): /tf_static base_link -> velodyne, /tf
# odom -> base_link at each scan and a map -> odom drift between them, /odom (Odometry) and /pose
# (PoseStamped); in a ROS 1 bag (Debian's python3-rosbag) and in MCAP (@mcap/core, @foxglove/cdr).
# The trajectory `info --save-poses` writes is checked against tf2's own BufferCore (Debian's
# python3-tf2); fusing the bag on its /tf gives the map fused on the true poses; the MCAP gives the
# bag's trajectories and map, bit for bit. Bags whose tf is wrong (tests/io/write_bad_tf_bags.py)
# give exit 3 naming the file and what is wrong, and nothing is written. Skipped when
# python3-rosbag or python3-tf2 is absent (scripts/setup.sh installs them).
set -u
cli="$1" part="${2:-all}"  # part: all, golden (the trajectories and maps) or readers (the wrong poses)
here="$(cd "$(dirname "$0")" && pwd)"
io="$here/../io"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
source "$here/expect.sh"
py=/usr/bin/python3
if ! $py -c "import rosbag, tf2_py, tf2_msgs.msg, nav_msgs.msg" 2>/dev/null; then
    echo "skip: python3-rosbag, python3-tf2 or the message packages are absent"
    exit 0
fi
$py "$io/write_bad_tf_bags.py" "$dir/bad" || { echo "write_bad_tf_bags.py failed"; exit 1; }
if "$cli" info "$dir/bad/loop.bag" 2>&1 | grep -q "reads no ROS 1 bags"; then
    echo "skip: this build reads no ROS 1 bags"
    exit 0
fi
out="$dir/out.ply"

if [ "$part" != golden ]; then
# --- Wrong poses: exit 3 naming the file and what is wrong, nothing written.
expect 3 "loop.bag: the tf frames loop: odom <- base_link <- odom" -- "$cli" fuse "$dir/bad/loop.bag" -o "$out"
expect 3 "two_parents.bag: message 0 on /tf: frame 'base_link' has two parents, 'odom' and 'map'" -- "$cli" fuse "$dir/bad/two_parents.bag" -o "$out"
expect 3 "nan.bag: message 1 on /tf: the transform of 'base_link' in 'odom' is not finite" -- "$cli" fuse "$dir/bad/nan.bag" -o "$out"
expect 3 "truncated.bag: message 2 on /tf: message truncated" -- "$cli" fuse "$dir/bad/truncated.bag" -o "$out"
expect 3 "unlinked.bag: the scans' frame 'velodyne' is not linked in the tf tree" -- "$cli" fuse "$dir/bad/unlinked.bag" -o "$out"
expect 3 "static_only.bag: the transform from 'odom' to 'velodyne' never changes" -- "$cli" fuse "$dir/bad/static_only.bag" -o "$out"
expect 3 "truncated.bag: message 2 on /tf: message truncated" -- "$cli" info "$dir/bad/truncated.bag" --save-poses "$dir/poses.txt"
expect 0 "poses for fuse: none from the recording \(.*never changes" -- "$cli" info "$dir/bad/static_only.bag"
expect 2 "odom_only.bag: no moving link in /tf: name one of its pose topics with --pose-topic: /odometry \(nav_msgs/Odometry\)" -- "$cli" fuse "$dir/bad/odom_only.bag" -o "$out"
expect 0 "poses for fuse: /odometry from odom to velodyne, 2 poses" -- "$cli" info "$dir/bad/odom_only.bag" --pose-topic /odometry
check "nothing written after the failures" -- test ! -e "$out" -a ! -e "$dir/poses.txt"
fi
if [ "$part" = readers ]; then
    echo "$passed passed, $fail failed"
    [ "$fail" -eq 0 ]; exit
fi

"$cli" simulate --frames 6 --length 80 -o "$dir/drive" -q >/dev/null || { echo "simulate failed"; exit 1; }
$py "$io/write_tf_bag.py" "$dir/drive" "$dir" || { echo "write_tf_bag.py failed"; exit 1; }

# --- info: the tf tree, and the trajectory checked against tf2.
expect 0 "odom +-> base_link +moving, 6 transforms over 0.500 s" -- "$cli" info "$dir/tf.bag"
expect 0 "map +-> odom +moving, 4 transforms" -- "$cli" info "$dir/tf.bag"
expect 0 "base_link +-> velodyne +static" -- "$cli" info "$dir/tf.bag"
expect 0 "poses for fuse: /tf from odom to velodyne, 6 poses over 0.500 s; 6 of 6 scans" -- "$cli" info "$dir/tf.bag" --save-poses "$dir/odom.txt"
# With map: the scans' stamps and the drift's at 100.25 s in between.
expect 0 "poses for fuse: /tf from map to velodyne, 7 poses" -- "$cli" info "$dir/tf.bag" --fixed-frame map --save-poses "$dir/map.txt"
expect 0 "/odom from odom to velodyne" -- "$cli" info "$dir/tf.bag" --pose-topic /odom --save-poses "$dir/podom.txt"
expect 0 "/pose from odom to velodyne" -- "$cli" info "$dir/tf.bag" --pose-topic /pose --save-poses "$dir/ppose.txt"
expect 0 "6 poses against tf2" -- $py "$io/check_recorded_poses.py" "$dir/transforms.json" "$dir/odom.txt" odom velodyne tf
expect 0 "7 poses against tf2" -- $py "$io/check_recorded_poses.py" "$dir/transforms.json" "$dir/map.txt" map velodyne tf
expect 0 "6 poses against tf2" -- $py "$io/check_recorded_poses.py" "$dir/transforms.json" "$dir/podom.txt" odom velodyne odom
expect 0 "6 poses against tf2" -- $py "$io/check_recorded_poses.py" "$dir/transforms.json" "$dir/ppose.txt" odom velodyne pose

# --- fuse on the bag's /tf: the map fused on the true poses (poses.txt). The chained poses differ
# from them by ~1e-13 m, which moves a point lying on a voxel's face to the next voxel: at most
# 0.1% of either mesh's vertices lie more than 1e-5 m from the other's vertices, at most 0.01% more
# than half a voxel (0.1 m: a sliver that appears or goes).
"$cli" fuse "$dir/drive" -o "$dir/truth.ply" -q --carve-empty-range 0 >/dev/null  # the bag's clouds do not say which rays returned nothing
expect 0 "6 frames fused .*poses from /tf \(odom -> velodyne\) \(6 of 6 scans within its span\)" -- "$cli" fuse "$dir/tf.bag" -o "$dir/tf.ply" -q
expect 0 "alike" -- $py "$io/compare_meshes.py" "$dir/truth.ply" "$dir/tf.ply" 1e-5 0.001 0.1 0.0001
"$cli" fuse "$dir/tf.bag" --pose-topic /odom -o "$dir/odom.ply" -q >/dev/null
check "/odom through /tf_static gives /tf's map, bit for bit" -- cmp -s "$dir/tf.ply" "$dir/odom.ply"

# --- The same poses in MCAP (ROS 2 CDR): the bag's trajectories and map, bit for bit.
if [ -d "$io/ros2/node_modules/@mcap/core" ] && command -v node >/dev/null; then
    node "$io/ros2/write_ros2.mjs" "$dir/drive" "$dir" "$dir/transforms.json" || { echo "write_ros2.mjs failed"; exit 1; }
    for f in odom:"" map:"--fixed-frame map" podom:"--pose-topic /odom" ppose:"--pose-topic /pose"; do
        "$cli" info "$dir/tf.mcap" ${f#*:} --save-poses "$dir/mcap_${f%%:*}.txt" >/dev/null
        check "MCAP ${f#*:}: the bag's trajectory" -- cmp -s "$dir/${f%%:*}.txt" "$dir/mcap_${f%%:*}.txt"
    done
    "$cli" fuse "$dir/tf.mcap" -o "$dir/mcap.ply" -q >/dev/null
    check "MCAP: the bag's map, bit for bit" -- cmp -s "$dir/tf.ply" "$dir/mcap.ply"
    # Two recordings in one fuse, each on its own /tf: the map of the bag given twice.
    expect 0 "tf.bag \+ [^ ]*tf.mcap: 4 frames fused" -- "$cli" fuse "$dir/tf.bag" "$dir/tf.mcap" --frames 2 -o "$dir/two.ply" -q
    "$cli" fuse "$dir/tf.bag" "$dir/tf.bag" --frames 2 -o "$dir/twice.ply" -q >/dev/null
    check "two recordings: the bag given twice, bit for bit" -- cmp -s "$dir/two.ply" "$dir/twice.ply"
else
    echo "skip: the MCAP writers are absent (npm ci in tests/io/ros2)"
fi

# --- Wrong choices: exit 2 saying what to give, nothing written.
expect 2 "tf.bag: no frame 'nowhere' in the tf tree \(its frames: base_link, map, odom, velodyne\)" -- "$cli" fuse "$dir/tf.bag" --fixed-frame nowhere -o "$out"
expect 2 "/velodyne_points is sensor_msgs/PointCloud2, not nav_msgs/Odometry" -- "$cli" fuse "$dir/tf.bag" --pose-topic /velodyne_points -o "$out"
expect 2 "poses gives the trajectory" -- "$cli" fuse "$dir/tf.bag" --poses "$dir/odom.txt" --fixed-frame map -o "$out"
$py "$io/kitti_to_ros1_bag.py" "$dir/drive" "$dir/clouds.bag" "$dir/times.txt"
expect 2 "clouds.bag: a recording needs the sensor's trajectory .* holds no /tf or pose topic" -- "$cli" fuse "$dir/clouds.bag" -o "$out"
expect 0 "poses for fuse: none from the recording \(.*no /tf" -- "$cli" info "$dir/clouds.bag"
check "nothing written after the failures" -- test ! -e "$out"
echo "$passed passed, $fail failed"
[ "$fail" -eq 0 ]
