#!/usr/bin/env bash
# What moving objects leave in a fused map, over many drives (docs/benchmarks.md, "Ghosts over many
# drives"): each drive of DRIVES is simulated (150 scans of the town), fused by every row of ROWS
# (`lidarsurf map-benchmark`: default, no-carving and, with VDBFUSION_PEER, VDBFusion with space
# carving) and scored against what stands at the end of the drive; prints one table, a row per
# drive and method, and writes OUT_DIR/ghosts.json.
# Usage: ghost_table.sh LIDARSURF_CLI OUT_DIR [VDBFUSION_PEER]
#   DRIVES_DIR (default OUT_DIR/drives): where the drives are simulated, once, and reused by later runs
#   DRIVES: "name:seed:simulate options;..." (default: the set below); ROWS (default: default,no-carving[,vdbfusion-carving])
#   FUSE_OPTIONS: more options for the lidarsurf rows (map-benchmark --fuse-options), one string
set -euo pipefail
cli=$(realpath "$1") out=$2 peer=${3:-}
drives_dir=${DRIVES_DIR:-$out/drives}
mkdir -p "$out" "$drives_dir"
default_drives="cars6:3:--moving-cars 6;cars6:11:--moving-cars 6;\
walkers:4:--moving-cars 4 --pedestrians 10 --cyclists 4;walkers:12:--moving-cars 4 --pedestrians 10 --cyclists 4;\
parking:5:--moving-cars 3 --leaving-cars 6 --parking-cars 4;parking:13:--moving-cars 3 --leaving-cars 6 --parking-cars 4;\
cars6:31:--moving-cars 6;walkers:32:--moving-cars 4 --pedestrians 10 --cyclists 4;\
parking:33:--moving-cars 3 --leaving-cars 6 --parking-cars 4;dark:34:--moving-cars 6 --pedestrians 6 --dark-cars 6"
drives=${DRIVES:-$default_drives}
rows=${ROWS:-default,no-carving${peer:+,vdbfusion-carving}}
IFS=';' read -ra list <<<"$drives"
for d in "${list[@]}"; do
  IFS=':' read -r name seed opts <<<"$d"
  dir="$drives_dir/$name-$seed"
  # shellcheck disable=SC2086  # the options are words
  [ -d "$dir/velodyne" ] || "$cli" simulate --frames 150 --seed "$seed" $opts -o "$dir" --quiet >/dev/null
  rm -rf "$out/$name-$seed"
  "$cli" map-benchmark "$dir" --rows "$rows" ${peer:+--vdbfusion "$peer"} ${FUSE_OPTIONS:+--fuse-options "$FUSE_OPTIONS"} \
    --out "$out/$name-$seed" -q >/dev/null
done
/usr/bin/python3 - "$out" "$drives" <<'PY'
import json, os, sys
out, drives = sys.argv[1], [d for d in sys.argv[2].split(";") if d]
rows, table = [], ["| drive | seed | method | ghost share | ghost area | on the movers' paths | F@0.1 | recall | precision | insert + carve / scan |",
                   "|---|---|---|---|---|---|---|---|---|---|"]
for d in drives:
    name, seed, opts = d.split(":", 2)
    results = json.load(open(os.path.join(out, f"{name}-{seed}", "results.json")))
    for r in results["rows"]:
        rows.append({"drive": name, "seed": int(seed), "options": opts.strip(), **{k: r[k] for k in
                     ("row", "label", "ghost_share", "ghost_area", "path_ghost_area", "fscore", "recall", "precision", "integrate_ms_per_scan")}})
        table.append(f"| {name} | {seed} | {r['label']} | {100 * r['ghost_share']:.2f} % | {r['ghost_area']:.0f} m² | {r['path_ghost_area']:.1f} m² | "
                     f"{100 * r['fscore']:.1f} % | {100 * r['recall']:.1f} % | {100 * r['precision']:.1f} % | {r['integrate_ms_per_scan']:.1f} ms |")
json.dump(rows, open(os.path.join(out, "ghosts.json"), "w"), indent=1)
print("\n".join(table))
PY
