#!/usr/bin/env bash
# Binary glTF end to end (make viewer-check): a scan meshed by `reconstruct`, a drive fused whole
# by `fuse` (written tile by tile, welded) and the same drive fused in tiles by lidarsurf.fuse_tiles
# (one .glb a tile), each as glTF and Draco-compressed glTF beside the PLY of the same run. Every
# file must pass the Khronos validator and load in Chromium through three.js's GLTFLoader and
# DRACOLoader with the PLY's triangles and box (tests/viewer/gltf_check.mjs).
# Usage: gltf_check.sh LIDARSURF_CLI PYTHONPATH [WORK_DIR]
set -euo pipefail
cli=$(realpath "$1")
pythonpath=$(realpath "$2")
work=${3:-$(mktemp -d)}
here=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$work" && mkdir -p "$work"
[ -d "$here/tests/viewer/node_modules/gltf-validator" ] || { echo "gltf-check: no gltf-validator (scripts/setup.sh viewer)"; exit 1; }
cd "$work"
"$cli" simulate --scene demo -o scan.bin >/dev/null
for out in scan.ply scan.glb; do "$cli" reconstruct scan.bin -o $out >/dev/null; done
"$cli" reconstruct scan.bin -o scan_draco.glb --mesh-format glb-draco >/dev/null
"$cli" simulate --frames 30 --length 80 --gt-beams 0 -o drive --quiet >/dev/null
for out in map.ply map.glb; do "$cli" fuse drive -o $out --quiet >/dev/null; done
"$cli" fuse drive -o map_draco.glb --mesh-format glb-draco --quiet >/dev/null
PYTHONPATH="$pythonpath" /usr/bin/python3 -m lidarsurf.tiles drive tiles --tile-size 40 --mesh-format glb-draco >/dev/null
tiles=$(/usr/bin/python3 -c 'import json; print(",".join("tiles/" + t["path"] for t in json.load(open("tiles/index.json"))["tiles"]))')
ls -l scan.ply scan.glb scan_draco.glb map.ply map.glb map_draco.glb | awk '{print "gltf-check: " $5 " bytes " $9}'
node "$here/tests/viewer/gltf_check.mjs" "$here/viewer/node_modules/three" "$work" \
  "scan=scan.glb=scan.ply" "scan, Draco=scan_draco.glb=scan.ply" \
  "map=map.glb=map.ply" "map, Draco=map_draco.glb=map.ply" "map in tiles, Draco=$tiles=map.ply"
