#!/usr/bin/env bash
# The sensors table (docs/benchmarks.md, "Every lidar"): every sensor preset on the town and the
# off-road scene, the same frames for every method, within 30 m of the sensor, against the true
# surface. Rows: lidarsurf's default, the paper's AN+GC as written and, when installed, the peers
# (Open3D's alpha shape and Poisson from Debian's python3-open3d; PCL's MLS + greedy projection
# when PCL_PEER names tools/pcl_peer's binary, `make accuracy-pcl` builds it; VDBFusion on each scan
# alone when VDBFUSION_PEER names tools/vdbfusion_peer's binary, `make map-peers` builds it: its KITTI
# settings, 0.1 m voxels, 0.3 m truncation, min weight 5, and the same with min weight 1 and with
# no weight filter).
#   scripts/accuracy_sensors.sh CLI OUT
# Environment: SEED (21), FRAMES (3), SENSORS, SCENES, METHODS (benchmark rows), O3D_METHODS.
# Prints the markdown table and writes OUT/sensors.json.
set -euo pipefail
cli=$1
out=$2
seed=${SEED:-21}
frames=${FRAMES:-3}
sensors=${SENSORS:-vlp16 hdl32 hdl64 os1-128}
scenes=${SCENES:-town offroad}
methods=${METHODS:-default,AN+GC kmax=5}
o3d_methods=${O3D_METHODS:-alpha-0.5,poisson-d9}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
have_open3d=0
/usr/bin/python3 -c 'import open3d' 2>/dev/null && have_open3d=1
for scene in $scenes; do
    for sensor in $sensors; do
        seq="$out/drives/$scene-$sensor-$seed"
        [ -f "$seq/sensor.json" ] || "$cli" simulate --scene "$scene" --sensor "$sensor" --frames "$frames" --seed "$seed" -o "$seq" -q
        peers=()
        if [ "$have_open3d" = 1 ]; then
            [ -f "$seq/peers/done-o3d" ] || { /usr/bin/python3 "$here/peers_open3d.py" "$seq" --methods "$o3d_methods" >/dev/null && touch "$seq/peers/done-o3d"; }
        fi
        if [ -n "${PCL_PEER:-}" ] && [ ! -f "$seq/peers/done-pcl" ]; then
            "$PCL_PEER" "$seq" "$seq/peers" >/dev/null && touch "$seq/peers/done-pcl"
        fi
        if [ -n "${VDBFUSION_PEER:-}" ] && [ ! -f "$seq/peers/done-vdbfusion" ]; then
            "$VDBFUSION_PEER" "$seq" "$seq/peers/vdbfusion-kitti" --single-scans --frames "$frames" --voxel-size 0.1 --sdf-trunc 0.3 --min-weight 5 2>/dev/null
            "$VDBFUSION_PEER" "$seq" "$seq/peers/vdbfusion-w1" --single-scans --frames "$frames" --voxel-size 0.1 --sdf-trunc 0.3 --min-weight 1 2>/dev/null
            "$VDBFUSION_PEER" "$seq" "$seq/peers/vdbfusion-w0" --single-scans --frames "$frames" --voxel-size 0.1 --sdf-trunc 0.3 --min-weight 0 2>/dev/null
            touch "$seq/peers/done-vdbfusion"
        fi
        [ -d "$seq/peers" ] && peers=(--peers "$seq/peers")
        "$cli" benchmark "$seq" --methods "$methods" "${peers[@]}" --max-range 30 --no-plots -q --out "$out/$scene-$sensor" >/dev/null
    done
done
/usr/bin/python3 - "$out" "$scenes" "$sensors" <<'PY'
import json, sys
out, scenes, sensors = sys.argv[1], sys.argv[2].split(), sys.argv[3].split()
cols = [(s, n) for s in scenes for n in sensors]
rows, table = [], {}
for scene, sensor in cols:
    for m in json.load(open(f"{out}/{scene}-{sensor}/results.json"))["methods"]:
        t = m["truth"]
        if m["name"] not in rows: rows.append(m["name"])
        table[(m["name"], scene, sensor)] = {"f": t["fscore"], "precision": t["precision"], "recall": t["recall"], "seconds": m["seconds"]}
names = {"default": "**lidarsurf default**", "AN+GC kmax=5": "the paper's AN+GC, as written", "alpha-0.5": "Open3D alpha shape, α = 0.5 m",
         "poisson-d9": "Open3D Poisson, depth 9, 5 % trim", "poisson-d10": "Open3D Poisson, depth 10, 5 % trim",
         "pcl-mls-gp": "PCL MLS + greedy projection",
         "vdbfusion-kitti": "VDBFusion, each scan alone, its KITTI settings (0.1 m, min weight 5)",
         "vdbfusion-w1": "VDBFusion, each scan alone, 0.1 m, min weight 1",
         "vdbfusion-w0": "VDBFusion, each scan alone, 0.1 m, no weight filter"}
print("| method | " + " | ".join(f"{s} {n}" for s, n in cols) + " |")
print("|---" * (len(cols) + 1) + "|")
for r in rows:
    cells = []
    for s, n in cols:
        v = table.get((r, s, n))
        cells.append(f"{100 * v['f']:.1f} ({100 * v['precision']:.0f}/{100 * v['recall']:.0f})" if v else "–")
    print(f"| {names.get(r, r)} | " + " | ".join(cells) + " |")
json.dump([{"method": r, "scene": s, "sensor": n, **table[(r, s, n)]} for r in rows for s, n in cols if (r, s, n) in table],
          open(f"{out}/sensors.json", "w"), indent=1)
PY
