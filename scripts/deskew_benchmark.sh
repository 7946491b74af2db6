#!/usr/bin/env bash
# De-skew on a turning drive (docs/benchmarks.md, "De-skew"): the town driven at 10 m/s weaving
# 1.5 m either side of its lane (up to 21 degrees a second of yaw), scanned by a sensor that turns
# once in 0.1 s while the rig moves (its seam ahead), written as a ROS 1 bag with per-point times
# (tests/io/kitti_to_ros1_bag.py, ROS's own writer) and fused from it with the trajectory, with
# and without --deskew; beside it the same drive scanned at one instant a frame. Each map is
# scored by map-benchmark against the drive's static scene.
# Usage: deskew_benchmark.sh LIDARSURF WORK_DIR [SEEDS (default "1 2")] [FRAMES (50)] [LENGTH (120)]
set -euo pipefail
cli=$1 work=$2 seeds=${3:-"1 2"} frames=${4:-50} length=${5:-120}
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$work"
drive=(--frames "$frames" --length "$length" --speed 10 --weave 1.5 --moving-cars 0 -q)
row() {  # the default row of a map-benchmark run: precision recall F ghost-share
    /usr/bin/python3 -c "
import json, sys
m = [x for x in json.load(open(sys.argv[1]))['rows'] if x['row'] == 'default'][0]
print('%.2f %.2f %.2f %.3f' % (100 * m['precision'], 100 * m['recall'], 100 * m['fscore'], 100 * m['ghost_share']))" "$1/results.json"
}
echo "| seed | scans | variant | precision % | recall % | F % | beyond 0.3 m % |"
echo "|---|---|---|---|---|---|---|"
for seed in $seeds; do
    w="$work/seed$seed"
    rm -rf "$w" && mkdir -p "$w"
    "$cli" simulate "${drive[@]}" --seed "$seed" -o "$w/instant" >/dev/null
    "$cli" simulate "${drive[@]}" --seed "$seed" --sweep-seconds 0.1 -o "$w/sweep" >/dev/null
    /usr/bin/python3 "$here/tests/io/kitti_to_ros1_bag.py" "$w/sweep" "$w/sweep.bag" "$w/sweep_times.txt" lz4
    "$cli" map-benchmark "$w/instant" --rows default --out "$w/instant_mb" -q >/dev/null
    "$cli" map-benchmark "$w/sweep" --rows default --fuse-input "$w/sweep.bag" --fuse-options "--poses $w/sweep_times_tum.txt" --out "$w/deskew_mb" -q >/dev/null
    "$cli" map-benchmark "$w/sweep" --rows default --fuse-input "$w/sweep.bag" --fuse-options "--poses $w/sweep_times_tum.txt --deskew 0" --out "$w/raw_mb" -q >/dev/null
    for v in instant_mb:"one instant a scan" deskew_mb:"0.1 s sweeps, de-skewed" raw_mb:"0.1 s sweeps, --deskew 0"; do
        read -r p r f g <<<"$(row "$w/${v%%:*}")"
        echo "| $seed | $frames | ${v#*:} | $p | $r | $f | $g |"
    done
done
