#!/usr/bin/env bash
# The long-drive table (docs/benchmarks.md, "Long drives in tiles"): town drives with one scan
# every 4 m, fused whole and in tiles, peak resident memory and wall time of each run, and the
# tiles' mesh against the whole map's (the same triangle count; the tests compare the triangles).
#   scripts/tiles_memory.sh CLI OUT
# Environment: DRIVES ("150:600 600:2400", scans:metres), TILE_SIZE (100), WHOLE (1: also fuse
# whole; 0 for drives too large to hold in memory). Prints the markdown table, writes OUT/*.json.
set -euo pipefail
cli=$1
out=$2
drives=${DRIVES:-150:600 600:2400}
tile=${TILE_SIZE:-100}
whole=${WHOLE:-1}
mkdir -p "$out"
echo "| drive | run | wall time | peak resident | triangles |"
echo "|---|---|---|---|---|"
for d in $drives; do
    n=${d%%:*}
    length=${d##*:}
    seq="$out/town-$n"
    [ -f "$seq/poses.txt" ] || "$cli" simulate --scene town --frames "$n" --length "$length" --gt-beams 0 -o "$seq" -q
    runs=("tiles:--tile-size $tile")
    [ "$whole" = 1 ] && runs=("whole:" "${runs[@]}")
    for r in "${runs[@]}"; do
        name=${r%%:*}
        # shellcheck disable=SC2086
        /usr/bin/time -f "%e %M" -o "$out/time-$n-$name" "$cli" fuse "$seq" -o "$out/town-$n-$name.ply" -q --json "$out/town-$n-$name.json" ${r#*:}
        read -r seconds kib < "$out/time-$n-$name"
        triangles=$(/usr/bin/python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['mesh_triangles'])" "$out/town-$n-$name.json")
        label=$name
        [ "$name" = tiles ] && label="tiles of $tile m"
        printf "| %s scans, %s m | %s | %.0f s | %.0f MiB | %s |\n" "$n" "$length" "$label" "$seconds" "$((kib / 1024))" "$triangles"
    done
done
