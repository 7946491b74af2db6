#!/usr/bin/env bash
# Exit codes and messages of the CLI: 0 ok, 2 bad arguments, 3 bad data, 4 file system (the bad-input
# matrix is tests/cli/test_bad_input.sh).
set -u
cli="$1"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
source "$(dirname "$0")/expect.sh"
"$cli" simulate --scene demo -o "$dir/scan.bin" --gt "$dir/gt.bin" --gt-beams 48 >/dev/null || { echo "simulate failed"; exit 1; }
expect 0 "triangles" -- "$cli" reconstruct "$dir/scan.bin" -o "$dir/mesh.ply"
[ -s "$dir/mesh.ply" ] || { echo "FAIL: no mesh written"; fail=$((fail + 1)); }
# Every SIMD level this build and CPU have gives the very same mesh file (core/simd.hpp: the AVX2 and
# AVX-512 code does the baseline's operations, without FMA); the levels it lacks are refused.
simd_levels=0
for level in portable sse2 avx2 avx512; do
    if "$cli" reconstruct "$dir/scan.bin" -o "$dir/simd.ply" --simd "$level" >/dev/null 2>"$dir/simd.err"; then
        cmp -s "$dir/mesh.ply" "$dir/simd.ply" || { echo "FAIL: --simd $level changed the mesh"; fail=$((fail + 1)); }
        simd_levels=$((simd_levels + 1))
    elif ! grep -q "not available here" "$dir/simd.err"; then
        echo "FAIL: --simd $level: $(cat "$dir/simd.err")"; fail=$((fail + 1))
    fi
done
[ "$simd_levels" -ge 1 ] || { echo "FAIL: no SIMD level ran"; fail=$((fail + 1)); }
expect 2 "unknown SIMD level" -- "$cli" reconstruct "$dir/scan.bin" -o "$dir/x.ply" --simd avx1024
# A scan from a pipe (no size to read it by): the same mesh.
bash -c "cat '$dir/scan.bin' | '$cli' reconstruct /dev/stdin --format bin -o '$dir/pipe.ply'" >/dev/null 2>&1
check "a scan read from a pipe gives the same mesh" -- cmp -s "$dir/mesh.ply" "$dir/pipe.ply"
expect 0 "mode cn" -- "$cli" reconstruct "$dir/scan.bin" -o "$dir/mesh.obj" --mode cn --k 3
head -c 1 "$dir/mesh.obj" | grep -q '#' || { echo "FAIL: obj not written"; fail=$((fail + 1)); }
expect 0 "Examples" -- "$cli" reconstruct --help
expect 2 "required|argument" -- "$cli" reconstruct "$dir/scan.bin"
# Bad inputs, parameters and outputs of reconstruct: tests/cli/test_bad_input.sh.
# IMLS and evaluation.
expect 0 "imls.*triangles" -- "$cli" reconstruct "$dir/scan.bin" -o "$dir/imls.ply" --method imls
expect 2 "unknown method" -- "$cli" reconstruct "$dir/scan.bin" -o "$dir/x.ply" --method poisson
expect 2 "imls: radius" -- "$cli" reconstruct "$dir/scan.bin" -o "$dir/x.ply" --method imls --imls-radius -1
expect 0 "F-score" -- "$cli" evaluate "$dir/mesh.ply" "$dir/gt.bin" --json "$dir/m.json" --max-range 30
grep -q '"ae_sym"' "$dir/m.json" || { echo "FAIL: evaluate --json wrote no metrics"; fail=$((fail + 1)); }
expect 0 "hold-out 0.5.*held out" -- "$cli" evaluate --holdout 0.5 "$dir/scan.bin" --seed 3 --mesh-out "$dir/ho.ply"
expect 2 "mesh-out writes the mesh of the kept points" -- "$cli" evaluate "$dir/mesh.ply" "$dir/gt.bin" --mesh-out "$dir/ho2.ply"
[ ! -e "$dir/ho2.ply" ] || { echo "FAIL: evaluate --mesh-out without --holdout wrote a file"; fail=$((fail + 1)); }
[ -s "$dir/ho.ply" ] || { echo "FAIL: --mesh-out not written"; fail=$((fail + 1)); }
# The ring hold-out: the simulator writes column after column, so the scan is stored again ring
# after ring (as KITTI does), and once more with each point's ring as a fifth value (as nuScenes does).
python3 - "$dir/scan.bin" "$dir/rings.bin" "$dir/rings5.bin" <<'PY'
import math, struct, sys
data = open(sys.argv[1], "rb").read()
pts = [struct.unpack_from("<4f", data, i) for i in range(0, len(data), 16)]
beams = [2.0 + (-24.8 - 2.0) * i / 63 for i in range(64)]  # the hdl64 preset
def beam(p):
    el = math.degrees(math.atan2(p[2], math.hypot(p[0], p[1])))
    return min(range(64), key=lambda b: abs(beams[b] - el))
rows = sorted(((beam(p), math.atan2(p[1], p[0]) % (2 * math.pi), p) for p in pts), key=lambda r: (r[0], r[1]))
open(sys.argv[2], "wb").write(b"".join(struct.pack("<4f", *p) for _, _, p in rows))
open(sys.argv[3], "wb").write(b"".join(struct.pack("<5f", *p, b) for b, _, p in rows))
PY
expect 0 "64 rings \(point order\).*held out" -- "$cli" evaluate --holdout-rings "$dir/rings.bin" --json "$dir/rings.json"
grep -q '"ring_holdout": {"rings": 64' "$dir/rings.json" || { echo "FAIL: evaluate --holdout-rings --json"; fail=$((fail + 1)); }
expect 0 "64 rings \(ring field\)" -- "$cli" evaluate --holdout-rings "$dir/rings5.bin" --bin-fields 5
expect 0 "64 rings \(point order\)" -- "$cli" evaluate --holdout-rings "$dir/rings5.bin" --bin-fields 5 --ring-field order
expect 3 "not stored ring after ring" -- "$cli" evaluate --holdout-rings "$dir/scan.bin"
expect 2 "ring field must be" -- "$cli" evaluate --holdout-rings "$dir/rings5.bin" --bin-fields 5 --ring-field 5
expect 2 "auto, order" -- "$cli" evaluate --holdout-rings "$dir/rings.bin" --ring-field top
expect 2 "not both" -- "$cli" evaluate --holdout-rings --holdout 0.5 "$dir/rings.bin"
expect 2 "ring-field is for --holdout-rings" -- "$cli" evaluate --holdout 0.5 "$dir/rings.bin" --ring-field order
expect 2 "takes MESH GT" -- "$cli" evaluate "$dir/mesh.ply"
expect 2 "one scan" -- "$cli" evaluate --holdout 0.5 "$dir/scan.bin" "$dir/gt.bin"
expect 2 "fraction" -- "$cli" evaluate --holdout 1.5 "$dir/scan.bin"
expect 2 "threshold" -- "$cli" evaluate "$dir/mesh.ply" "$dir/gt.bin" --threshold 0
expect 3 "not a PLY" -- "$cli" evaluate "$dir/gt.bin" "$dir/gt.bin"
expect 4 "cannot open" -- "$cli" evaluate "$dir/mesh.ply" "$dir/nothere.bin"
expect 2 "refusing" -- "$cli" evaluate "$dir/mesh.ply" "$dir/gt.bin" --json "$dir/gt.bin"
# The speed bench on a given scan: its table, and the machine it ran on (CPU, caches, stolen time).
expect 0 "machine: .*stolen by the hypervisor" -- "$cli" bench "$dir/scan.bin" --repeat 1 --no-reference --no-imls --no-scaling --json "$dir/bench.json"
# The caches come from sysfs, which some virtual machines do not have.
if [ -d /sys/devices/system/cpu/cpu0/cache ]; then
    grep -q '"machine": ".*L[23]' "$dir/bench.json" || { echo "FAIL: bench --json lacks the machine's caches"; fail=$((fail + 1)); }
else
    grep -q '"machine": ".*MHz' "$dir/bench.json" || { echo "FAIL: bench --json lacks the machine"; fail=$((fail + 1)); }
fi
expect 2 "" -- "$cli" bench "$dir/scan.bin" --repeat 0
# Simulator, renderer and benchmark.
seq="$dir/seq"
expect 0 "simulated 2 frames" -- "$cli" simulate --scene town --sensor vlp16 --frames 2 --length 100 --gt-beams 48 -o "$seq"
for f in velodyne/000000.bin velodyne/000001.bin gt/000000.bin gt/000001.bin objects/000001.ply scene.ply sensor.json; do
    [ -s "$seq/$f" ] || { echo "FAIL: simulate did not write $f"; fail=$((fail + 1)); }
done
[ "$(wc -l < "$seq/poses.txt")" -eq 2 ] || { echo "FAIL: poses.txt should have 2 lines"; fail=$((fail + 1)); }
[ "$(wc -w < "$seq/poses.txt")" -eq 24 ] || { echo "FAIL: poses.txt should hold 2 x 12 numbers"; fail=$((fail + 1)); }
# Fusing the sequence with its poses: a mesh after each frame (the second reusing the first's
# vertices), the world-frame mesh written; bad poses, ranges and methods refused.
expect 0 "frame 000001: .*reused [1-9]" -- "$cli" fuse "$seq" -o "$dir/fused.ply" --remesh-every 1
[ -s "$dir/fused.ply" ] || { echo "FAIL: fuse wrote no mesh"; fail=$((fail + 1)); }
expect 0 "1 frames fused" -- "$cli" fuse "$seq" -o "$dir/fused1.obj" --first 1 --frames 1
printf 'P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 1 0 0 0 0 1 0 0 0 0 1 0\n' > "$dir/calib.txt"
expect 0 "2 frames fused" -- "$cli" fuse "$seq" -o "$dir/fused_calib.ply" --calib "$dir/calib.txt"
"$cli" fuse "$seq" -o "$dir/fused_plain.ply" > /dev/null
check "fuse --calib with an identity Tr gives the same mesh" -- cmp -s "$dir/fused_calib.ply" "$dir/fused_plain.ply"
printf 'P0: 1 0 0 0 0 1 0 0 0 0 1 0\n' > "$dir/calib_bad.txt"
expect 3 "no 'Tr:' line" -- "$cli" fuse "$seq" -o "$dir/x.ply" --calib "$dir/calib_bad.txt"
expect 2 "first 5: the sequence .* has 2 scans" -- "$cli" fuse "$seq" -o "$dir/x.ply" --first 5
expect 2 "step" -- "$cli" fuse "$seq" -o "$dir/x.ply" --step 0
expect 2 "IMLS" -- "$cli" fuse "$seq" -o "$dir/x.ply" --method imls
# The live mesh: per-frame update times, delta and live triangle counts and the staleness check in
# the report; the output is the exact mesh, byte for byte the one fuse writes without --live.
expect 0 "2 frames fused" -- "$cli" fuse "$seq" -o "$dir/fused_live.ply" --live --live-budget-ms 5 --live-check-every 1 --json "$dir/live.json"
check "fuse --live writes the exact mesh" -- cmp -s "$dir/fused_live.ply" "$dir/fused_plain.ply"
for key in update_ms delta_triangles live_triangles pending_blocks covered_share update_ms_p90 staleness_median; do
  grep -q "\"$key\"" "$dir/live.json" || { echo "FAIL: fuse --live --json has no $key"; fail=$((fail + 1)); }
done
expect 2 "seeded surface" -- "$cli" fuse "$seq" -o "$dir/x.ply" --live --method paper
expect 2 "add --live" -- "$cli" fuse "$seq" -o "$dir/x.ply" --live-check-every 5
expect 2 "live growth" -- "$cli" fuse "$seq" -o "$dir/x.ply" --live --live-growth -1
expect 4 "velodyne|cannot|no such" -- "$cli" fuse "$dir/nothere" -o "$dir/x.ply"
# fuse --tile-size: the map in tiles, written tile by tile, is the whole map's mesh (the same
# counts here; tests/tiles/test_tiles.cpp and python/tests/test_tiles.py compare the triangles),
# and leaves no temporary behind.
expect 0 "frames fused in [0-9]+ tiles of 20 m" -- "$cli" fuse "$seq" -o "$dir/tiled.ply" --tile-size 20 --json "$dir/tiled.json"
check "fuse --tile-size writes the whole map's vertex and face counts" -- \
  test "$(head -c 600 "$dir/tiled.ply" | grep -a '^element')" = "$(head -c 600 "$dir/fused_plain.ply" | grep -a '^element')"
expect 0 "frames fused in" -- "$cli" fuse "$seq" -o "$dir/tiled.obj" --tile-size 20
check "fuse --tile-size writes OBJ too" -- test "$(grep -c '^f ' "$dir/tiled.obj")" -gt 1000
check "fuse --tile-size leaves no temporary" -- test -z "$(ls -a "$dir" | grep -E 'parts|\.tmp\.')"
grep -q '"per_tile"' "$dir/tiled.json" || { echo "FAIL: fuse --tile-size --json has no per_tile"; fail=$((fail + 1)); }
expect 0 "frames fused in [0-9]+ tiles of 20 m" -- "$cli" fuse "$seq" -o "$dir/tiled1.ply" --tile-size 20 --tile-group 1
check "fuse --tile-size in groups of one tile writes the same counts" -- \
  test "$(head -c 600 "$dir/tiled1.ply" | grep -a '^element')" = "$(head -c 600 "$dir/fused_plain.ply" | grep -a '^element')"
expect 5 "memory budget" -- "$cli" fuse "$seq" -o "$dir/budget.ply" --tile-size 20 --max-memory 17
check "a map in tiles over the memory budget writes nothing" -- test ! -e "$dir/budget.ply"
expect 2 "tile_size" -- "$cli" fuse "$seq" -o "$dir/x.ply" --tile-size 0.5
expect 2 "group" -- "$cli" fuse "$seq" -o "$dir/x.ply" --tile-size 20 --tile-group 0
expect 2 "not with --live" -- "$cli" fuse "$seq" -o "$dir/x.ply" --tile-size 50 --live
expect 2 "seeded surface" -- "$cli" fuse "$seq" -o "$dir/x.ply" --tile-size 50 --method paper
# The live view (fuse --serve): the mesh written is fuse's; after the drive the final map stays
# served until SIGINT, which then ends it with 0; a second server on the same port is exit 4 before
# any work; the server's options are checked.
"$cli" fuse "$seq" -o "$dir/served.ply" --serve 0 --quiet >/dev/null 2>"$dir/serve.log" &
served=$!
for _ in $(seq 200); do grep -q "until Ctrl-C" "$dir/serve.log" && break; sleep 0.05; done
port=$(grep -o '127.0.0.1:[0-9]*' "$dir/serve.log" | head -1 | cut -d: -f2)
check "fuse --serve says where it serves" -- test -n "$port"
expect 4 "port is in use" -- "$cli" fuse "$seq" -o "$dir/x.ply" --serve "${port:-1}"
check "a refused server writes nothing" -- test ! -e "$dir/x.ply"
kill -INT "$served"; wait "$served"; rc=$?
check "SIGINT after the drive ends fuse --serve with 0 (got $rc)" -- test "$rc" -eq 0
check "fuse --serve writes the mesh fuse writes" -- cmp -s "$dir/served.ply" "$dir/fused_plain.ply"
expect 2 "add --serve" -- "$cli" fuse "$seq" -o "$dir/x.ply" --bind 0.0.0.0
expect 2 "not an IP address" -- "$cli" fuse "$seq" -o "$dir/x.ply" --serve 0 --bind nowhere
expect 2 "serve takes a port" -- "$cli" fuse "$seq" -o "$dir/x.ply" --serve 70000
expect 2 "rate" -- "$cli" fuse "$seq" -o "$dir/x.ply" --rate -1
expect 2 "seeded surface" -- "$cli" fuse "$seq" -o "$dir/x.ply" --serve 0 --method paper
mkdir -p "$dir/short/velodyne" && cp "$seq"/velodyne/*.bin "$dir/short/velodyne/" && head -1 "$seq/poses.txt" > "$dir/short/poses.txt"
expect 3 "1 poses for 2 scans" -- "$cli" fuse "$dir/short" -o "$dir/x.ply"
rm "$dir/short/poses.txt"
expect 4 "no poses \\(looked for" -- "$cli" fuse "$dir/short" -o "$dir/x.ply"
[ ! -e "$dir/x.ply" ] || { echo "FAIL: a failed fuse left a mesh"; fail=$((fail + 1)); }
# The KITTI odometry layout as downloaded: dataset/sequences/07 with calib.txt, dataset/poses/07.txt
# (the camera's); --poses for a pose file from elsewhere (the lidar's). Identity Tr: the same mesh.
mkdir -p "$dir/dataset/sequences/07/velodyne" "$dir/dataset/poses"
cp "$seq"/velodyne/*.bin "$dir/dataset/sequences/07/velodyne/" && cp "$seq/poses.txt" "$dir/dataset/poses/07.txt"
expect 4 "calib.txt is missing" -- "$cli" fuse "$dir/dataset/sequences/07" -o "$dir/x.ply"
cp "$dir/calib.txt" "$dir/dataset/sequences/07/calib.txt"
expect 0 "poses from KITTI odometry" -- "$cli" fuse "$dir/dataset/sequences/07" -o "$dir/fused_kitti.ply"
check "the KITTI layout gives the sequence's mesh" -- cmp -s "$dir/fused_kitti.ply" "$dir/fused_plain.ply"
expect 0 "poses from --poses" -- "$cli" fuse "$dir/short" -o "$dir/fused_flag.ply" --poses "$seq/poses.txt" --json "$dir/fuse.json"
check "fuse --poses gives the sequence's mesh" -- cmp -s "$dir/fused_flag.ply" "$dir/fused_plain.ply"
check "fuse --json reports each frame" -- grep -q '"integrate_ms"' "$dir/fuse.json"
# The benchmark's plumbing on a sparse 16-ring frame (a quarter of the VLP-16's columns) with two
# rows: quick under the sanitizers (every row, IMLS's too, is listed by Benchmark.TableOneRows).
bseq="$dir/bseq"
printf '{"beams": 16, "elevation_max_deg": 15, "elevation_min_deg": -15, "azimuth_step_deg": 0.8}' > "$dir/sparse.json"
"$cli" simulate --scene town --sensor "$dir/sparse.json" --frames 1 --length 100 --gt-beams 48 -o "$bseq" --quiet >/dev/null
expect 0 "against the true scene triangles" -- "$cli" benchmark "$bseq" --frames 1 --no-plots --methods 'default,AN+GC kmax=5'
[ "$(wc -l < "$bseq/benchmark/results.csv")" -eq 3 ] || { echo "FAIL: results.csv should have a header and 2 rows"; fail=$((fail + 1)); }
grep -q '"by_range"' "$bseq/benchmark/results.json" || { echo "FAIL: results.json lacks the range bins"; fail=$((fail + 1)); }
grep -q '"truth": {' "$bseq/benchmark/results.json" || { echo "FAIL: results.json lacks the true-surface metrics"; fail=$((fail + 1)); }
# Another tool's meshes (--peers): a copy of our own frame-0 mesh must score exactly as "default".
mkdir -p "$dir/peers/copy"
"$cli" reconstruct "$bseq/velodyne/000000.bin" -o "$dir/peers/copy/000000.ply" > /dev/null
printf '0 1.5\n' > "$dir/peers/copy/times.txt"
expect 0 "copy .* 1.500" -- "$cli" benchmark "$bseq" --frames 1 --methods default --peers "$dir/peers" --no-plots --out "$dir/bench_peers"
# (the PLY stores float32 vertices: equal to 1e-4 m / 1e-4 in every true-surface column)
row() { grep "^\"$1\"" "$dir/bench_peers/results.csv" | cut -d, -f22-31; }
same=$(paste -d, <(row default | tr , '\n') <(row copy | tr , '\n') | awk -F, 'NF == 2 && $1 != "" { n++; d = $1 - $2; if (d < 0) d = -d; if (d > 1e-4) bad++ } END { print (n == 10 && !bad) ? "yes" : "no" }')
[ "$same" = yes ] || { echo "FAIL: a copied mesh should score as the original: '$(row default)' vs '$(row copy)'"; fail=$((fail + 1)); }
expect 2 "excludes" -- "$cli" reconstruct "$seq/velodyne/000000.bin" -o "$dir/lit.ply" --literal --snap 0
if /usr/bin/python3 -c 'import matplotlib' 2>/dev/null; then
    expect 0 "AN\+GC kmax=5" -- "$cli" benchmark "$bseq" --frames 1 --methods 'default,AN+GC kmax=5' --out "$dir/bench1"
    [ -s "$dir/bench1/fig6a_range.png" ] && [ -s "$dir/bench1/fig6b_delta.png" ] || { echo "FAIL: figures not drawn"; fail=$((fail + 1)); }
fi
expect 0 "rendered" -- "$cli" render "$dir/mesh.ply" -o "$dir/mesh.png" --colour level --width 160 --height 120
head -c 4 "$dir/mesh.png" | grep -q "PNG" || { echo "FAIL: render wrote no PNG"; fail=$((fail + 1)); }
expect 0 "simulated .* points" -- "$cli" simulate --scene offroad --sensor vlp16 --length 100 -o "$dir/off.bin" --gt "$dir/off_gt.bin" --gt-beams 32
printf '{"beams": 8, "elevation_max_deg": 5, "elevation_min_deg": -20, "azimuth_step_deg": 1}' > "$dir/s.json"
expect 0 "simulated 1 frames" -- "$cli" simulate --scene town --sensor "$dir/s.json" --frames 1 --length 100 -o "$dir/seq_json"
# A view that sees nothing (nothing within 1.2 m of a sensor 1.73 m above the ground): refused, no file.
printf '{"beams": 8, "elevation_max_deg": 5, "elevation_min_deg": -20, "azimuth_step_deg": 1, "max_range": 1.2}' > "$dir/blind.json"
expect 3 "sees nothing" -- "$cli" simulate --scene demo --sensor "$dir/blind.json" -o "$dir/blind.bin"
expect 3 "sees nothing" -- "$cli" simulate --scene town --sensor "$dir/blind.json" --length 100 -o "$dir/blind.bin"
[ ! -e "$dir/blind.bin" ] || { echo "FAIL: simulate wrote a scan of a view that sees nothing"; fail=$((fail + 1)); }
expect 2 "unknown scene" -- "$cli" simulate --scene city -o "$dir/x"
expect 2 "unknown sensor" -- "$cli" simulate --sensor hdl65 -o "$dir/x"
printf '{"beams": 8' > "$dir/bad.json"
expect 3 "sensor JSON" -- "$cli" simulate --sensor "$dir/bad.json" -o "$dir/x"
expect 2 "frames" -- "$cli" simulate --frames 0 -o "$dir/x"
expect 2 "needs --from" -- "$cli" simulate --scene "$seq/scene.ply" -o "$dir/x"
expect 4 "not a sequence" -- "$cli" benchmark "$dir/nothere"
expect 2 "unknown benchmark method" -- "$cli" benchmark "$seq" --methods 'AN+GC kmax=7'
expect 2 "PNG" -- "$cli" render "$dir/mesh.ply" -o "$dir/x.jpg"
expect 3 "not a PLY|no triangle" -- "$cli" render "$dir/gt.bin" -o "$dir/x.png"
# bench: a user's scan, fast vs reference, table and JSON (the simulated default is exercised by
# docs/benchmarks.md's command, too slow for this script under the sanitizers).
expect 0 "reference" -- "$cli" bench "$dir/scan.bin" --repeat 2 --slow-repeat 1 --no-imls --no-scaling --json "$dir/bench.json"
[ "$(grep -c '"path"' "$dir/bench.json")" -eq 2 ] || { echo "FAIL: bench JSON rows"; fail=$((fail + 1)); }
grep -q '"total_runs_ms"' "$dir/bench.json" || { echo "FAIL: bench JSON lacks run times"; fail=$((fail + 1)); }
# The fast row's untimed first run (its memory faulted in again after the previous row), not the reference's.
check "bench: one warm-up run, the fast row's" -- [ "$(grep -c '"warmup_total_ms"' "$dir/bench.json")" -eq 1 ]
# bench's size scaling on a user's scan: every 4th and every 2nd of its points, then the scan (the
# counts from the file's size: 16 bytes a KITTI point); on a 5-field (nuScenes) copy read with
# --bin-fields 5, since the subsampled copies the bench writes are read as its own KITTI files.
perl -e 'local $/ = \16; while (<STDIN>) { print $_, pack("f", 0) }' <"$dir/scan.bin" >"$dir/scan5.bin"
n=$(($(stat -c %s "$dir/scan.bin") / 16))
"$cli" bench "$dir/scan5.bin" --bin-fields 5 --repeat 1 --slow-repeat 1 --no-reference --no-imls >"$dir/sizes.txt" 2>&1
sizes=$(awk '$1 == "scan5.bin" && ($2 == "1/4" || $2 == "1/2") { printf "%s %s ", $2, $3 }' "$dir/sizes.txt")
check "bench: size rows of n/4 and n/2 points (n = $n): got '$sizes'" -- [ "$sizes" = "1/4 $(((n + 3) / 4)) 1/2 $(((n + 1) / 2)) " ]
expect 2 "describe the scans you pass" -- "$cli" bench --bin-fields 5
expect 2 "repeat" -- "$cli" bench "$dir/scan.bin" --repeat 0
expect 2 "voxel size" -- "$cli" bench "$dir/scan.bin" --voxel 0
expect 4 "cannot read" -- "$cli" bench "$dir/missing.bin"
# One vocabulary: the options carry the ReconstructionConfig field names (kebab-case); the earlier
# spellings are hidden aliases with the same effect; "paper" is the paper as written everywhere.
"$cli" reconstruct "$dir/scan.bin" -o "$dir/v_new.ply" --voxel-size 0.25 --n-min 12 --k-max 4 --slab-from-level 4 --truncation-voxels 1.2 >/dev/null
"$cli" reconstruct "$dir/scan.bin" -o "$dir/v_old.ply" --voxel 0.25 --nmin 12 --kmax 4 --slab 4 --truncation 1.2 >/dev/null
check "the old spellings give the same mesh" -- cmp -s "$dir/v_new.ply" "$dir/v_old.ply"
check "the old spellings are not in --help" -- bash -c "! '$cli' reconstruct --help | grep -qE -- '--(voxel|nmin|kmax|slab|truncation|snap|seeded|min-component|max-memory) '"
check "--help names the field names" -- bash -c "'$cli' reconstruct --help | grep -q -- '--slab-radial-extension'"
"$cli" reconstruct "$dir/scan.bin" -o "$dir/m_paper.ply" --method paper >/dev/null
"$cli" reconstruct "$dir/scan.bin" -o "$dir/m_literal.ply" --literal >/dev/null
"$cli" reconstruct "$dir/scan.bin" -o "$dir/m_default.ply" --method default >/dev/null
"$cli" reconstruct "$dir/scan.bin" -o "$dir/m_plain.ply" >/dev/null
check "--method paper is the paper as written (--literal)" -- cmp -s "$dir/m_paper.ply" "$dir/m_literal.ply"
check "--method default is the default" -- cmp -s "$dir/m_default.ply" "$dir/m_plain.ply"
check "and the two differ" -- bash -c "! cmp -s '$dir/m_paper.ply' '$dir/m_default.ply'"
expect 2 "unknown method" -- "$cli" reconstruct "$dir/scan.bin" -o "$dir/x.ply" --method tsdf
# Progress on stderr: plain lines when it is not a terminal, a bar redrawn in place on one (a
# pseudo-terminal from script(1)), nothing with --quiet; stdout keeps the report alone.
"$cli" fuse "$seq" -o "$dir/p.ply" >"$dir/p.out" 2>"$dir/p.err"
check "fuse: plain progress lines off a terminal" -- grep -qE '^fuse: [0-9]+/[0-9]+ frames \(100 %\)' "$dir/p.err"
check "fuse: no progress on stdout" -- bash -c "! grep -q 'fuse: ' '$dir/p.out'"
"$cli" fuse "$seq" -o "$dir/p.ply" --quiet >/dev/null 2>"$dir/q.err"
check "fuse --quiet: nothing on stderr" -- test ! -s "$dir/q.err"
if command -v script >/dev/null; then
  TERM=xterm script -qec "'$cli' fuse '$seq' -o '$dir/t.ply' >/dev/null" /dev/null >"$dir/t.err" 2>&1
  check "fuse on a terminal: a bar redrawn in place" -- bash -c "grep -aq \$'\r' '$dir/t.err' && grep -aq '\[#' '$dir/t.err'"
fi
echo "cli: $passed passed, $fail failed"
[ "$fail" -eq 0 ]
