#!/usr/bin/env bash
# The long-drive table (docs/benchmarks.md, "Long drives in tiles"): town drives with one scan
# every 4 m, fused whole and in tiles, wall time, CPU time (user + system) and peak resident
# memory of each run, and the tiles' mesh against the whole map's (the same triangle count; the
# tests compare the triangles).
#   scripts/tiles_memory.sh CLI OUT
# Environment: DRIVES ("150:600 600:2400", scans:metres), TILE_SIZES ("100 200"), WHOLE (1: also
# fuse whole; 0 for drives too large to hold in memory). Prints the markdown table, writes OUT/*.json.
set -euo pipefail
cli=$1
out=$2
drives=${DRIVES:-150:600 600:2400}
tile_sizes=${TILE_SIZES:-100 200}
whole=${WHOLE:-1}
mkdir -p "$out"
echo "| drive | run | wall time | CPU time | peak resident | triangles |"
echo "|---|---|---|---|---|---|"
for d in $drives; do
    n=${d%%:*}
    length=${d##*:}
    seq="$out/town-$n"
    [ -f "$seq/poses.txt" ] || "$cli" simulate --scene town --frames "$n" --length "$length" --gt-beams 0 -o "$seq" -q
    runs=()
    [ "$whole" = 1 ] && runs=("whole:")
    for tile in $tile_sizes; do runs+=("tiles$tile:--tile-size $tile"); done
    for r in "${runs[@]}"; do
        name=${r%%:*}
        # shellcheck disable=SC2086
        /usr/bin/time -f "%e %U %S %M" -o "$out/time-$n-$name" "$cli" fuse "$seq" -o "$out/town-$n-$name.ply" -q --json "$out/town-$n-$name.json" ${r#*:} >/dev/null
        read -r seconds user system kib < "$out/time-$n-$name"
        triangles=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['mesh_triangles'])" "$out/town-$n-$name.json")
        label=$name
        [ "$name" != whole ] && label="tiles of ${name#tiles} m"
        cpu=$(/usr/bin/python3 -c "import sys; print(float(sys.argv[1]) + float(sys.argv[2]))" "$user" "$system")
        printf "| %s scans, %s m | %s | %.0f s | %.0f s | %.0f MiB | %s |\n" "$n" "$length" "$label" "$seconds" "$cpu" "$((kib / 1024))" "$triangles"
    done
done
