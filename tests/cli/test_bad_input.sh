#!/usr/bin/env bash
# The bad-input matrix of docs/reliability.md through the CLI: each row is one input and the exit
# code and message it must give (0 ok, 2 bad arguments, 3 bad data, 4 file system, 5 memory
# budget). Then "nothing lost": a failed run keeps the previous output, leaves no temporary and
# never writes over its input.
set -u
cli="$1"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
source "$(dirname "$0")/expect.sh"
r() { "$cli" reconstruct "$@"; }
"$cli" simulate --scene demo -o "$dir/scan.bin" >/dev/null || { echo "simulate failed"; exit 1; }
out="$dir/out.ply"

# --- Files (exit 3: the data; 4: the file system).
: > "$dir/empty.bin"; : > "$dir/empty.ply"; : > "$dir/empty.pcd"; : > "$dir/empty.xyz"
for f in empty.bin empty.ply empty.pcd empty.xyz; do expect 3 "empty" -- r "$dir/$f" -o "$out"; done
head -c 1000003 "$dir/scan.bin" > "$dir/trunc.bin"
expect 3 "not a multiple of 16" -- r "$dir/trunc.bin" -o "$out"
hdr='ply\nformat binary_little_endian 1.0\nelement vertex %s\nproperty float x\nproperty float y\nproperty float z\nend_header\n'
{ printf "$hdr" 1000; head -c 5000 /dev/zero; } > "$dir/trunc.ply"
expect 3 "truncated|at most" -- r "$dir/trunc.ply" -o "$out"
printf 'plyx\nformat ascii 1.0\nend_header\n' > "$dir/magic.ply"
expect 3 "not a PLY" -- r "$dir/magic.ply" -o "$out"
printf 'VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2\n' > "$dir/noz.pcd"
expect 3 "PCD" -- r "$dir/noz.pcd" -o "$out"
printf 'ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n' > "$dir/short.ply"
expect 3 "PLY" -- r "$dir/short.ply" -o "$out"
{ printf "$hdr" 4000000000; head -c 1200 /dev/zero; } > "$dir/billions.ply"
expect 3 "claims 4000000000 .* at most 100" -- r "$dir/billions.ply" -o "$out"
printf '1 2 3\n4 5 six\n' > "$dir/word.xyz"
expect 3 "line 2" -- r "$dir/word.xyz" -o "$out"
expect 4 "cannot open" -- r "$dir/missing.bin" -o "$out"
expect 2 "unknown|format|extension" -- r "$dir/scan.bin" -o "$out" --format las

# --- Clouds (exit 0 with a count, or 3 with the reason).
printf 'nan nan nan\ninf 0 0\n' > "$dir/nan.xyz"
expect 3 "no finite point" -- r "$dir/nan.xyz" -o "$out"
printf '5 5 1\n' > "$dir/one.xyz"
expect 3 "no triangle" -- r "$dir/one.xyz" -o "$out"
for i in $(seq 300); do echo "1 2 3"; done > "$dir/same.xyz"
expect 3 "no triangle" -- r "$dir/same.xyz" -o "$out"
for i in $(seq 300); do echo "$i $((2 * i)) 0.5"; done | awk '{print $1 * 0.01, $2 * 0.01, $3}' > "$dir/line.xyz"
expect 3 "no triangle" -- r "$dir/line.xyz" -o "$out"
# NaN/Inf among good points: dropped, counted in the summary. Coordinates at 1e7 m (a UTM
# northing, text in double precision): the same mesh as at the origin.
python3 - "$dir" <<'PY'
import struct, sys
d = sys.argv[1]
data = open(d + "/scan.bin", "rb").read()
pts = [struct.unpack_from("<3f", data, i) for i in range(0, len(data), 16)]
with open(d + "/near.xyz", "w") as near, open(d + "/far.xyz", "w") as far, open(d + "/mixed.xyz", "w") as mixed:
    for i, (x, y, z) in enumerate(pts):
        near.write("%r %r %r\n" % (x, y, z))
        far.write("%.9f %.9f %.9f\n" % (x + 1.0e7, y - 1.0e7, z + 250.0))
        mixed.write("%r %r %r\n" % (x, y, z))
        if i % 1000 == 0:
            mixed.write("nan 1 2\n1 inf 2\n")
PY
nbad=$(grep -c nan "$dir/mixed.xyz"); nbad=$((2 * nbad))
expect 0 "dropped $nbad non-finite" -- r "$dir/mixed.xyz" -o "$out"
tri_near=$(r "$dir/near.xyz" -o "$dir/near.ply" 2>&1 | grep -oE '[0-9]+ triangles' | head -1)
tri_far=$(r "$dir/far.xyz" -o "$dir/far.ply" --origin 10000000,-10000000,250 2>&1 | grep -oE '[0-9]+ triangles' | head -1)
check "1e7 m: same triangle count ($tri_near vs $tri_far)" -- test -n "$tri_near" -a "$tri_near" = "$tri_far"
check "1e7 m: PLY in double precision" -- grep -aq "property double x" "$dir/far.ply"

# --- Parameters (exit 2).
expect 2 "voxel size" -- r "$dir/scan.bin" -o "$out" --voxel 0
expect 2 "voxel size" -- r "$dir/scan.bin" -o "$out" --voxel -1
expect 2 "voxel size" -- r "$dir/scan.bin" -o "$out" --voxel nan
expect 2 "tau" -- r "$dir/scan.bin" -o "$out" --tau 0
expect 2 "tau" -- r "$dir/scan.bin" -o "$out" --tau -3
expect 2 "k_max" -- r "$dir/scan.bin" -o "$out" --kmax 0
expect 2 "k_max" -- r "$dir/scan.bin" -o "$out" --kmax 100000
expect 2 "n_min" -- r "$dir/scan.bin" -o "$out" --nmin 0
expect 2 "max memory" -- r "$dir/scan.bin" -o "$out" --max-memory 0
expect 2 "origin" -- r "$dir/scan.bin" -o "$out" --origin 1,2
expect 2 "unknown mode" -- r "$dir/scan.bin" -o "$out" --mode fast

# --- Memory budget (exit 5, with the estimate).
expect 5 "would need about [0-9]+ MiB, above the memory budget of 2 MiB.*--max-memory" -- r "$dir/scan.bin" -o "$out" --max-memory 2
expect 5 "voxel grid would need about" -- r "$dir/scan.bin" -o "$out" --voxel 0.0001 --max-memory 16
expect 0 "triangles" -- r "$dir/scan.bin" -o "$out" --max-memory 400

# --- Outputs (exit 4: not writable; 2: would overwrite the input).
expect 4 "cannot write" -- r "$dir/scan.bin" -o "$dir/nodir/x.ply"
expect 4 "cannot write|directory" -- r "$dir/scan.bin" -o "$dir"
# The output is checked before the input is read: an unwritable output wins over bad data.
expect 4 "cannot write" -- r "$dir/nan.xyz" -o "$dir/nodir/x.ply"
expect 2 "refusing" -- r "$dir/scan.bin" -o "$dir/scan.bin"
ln -s "$dir/scan.bin" "$dir/link.ply"
expect 2 "refusing" -- r "$dir/scan.bin" -o "$dir/link.ply"
check "the input is intact after the refusals" -- test "$(stat -c %s "$dir/scan.bin")" -gt 1000000

# --- Nothing lost: failures after the output exists keep it byte for byte, leave no temporary.
cp "$out" "$dir/keep.ply"
expect 3 "no finite point" -- r "$dir/nan.xyz" -o "$out"
expect 5 "memory budget" -- r "$dir/scan.bin" -o "$out" --max-memory 2
expect 2 "tau" -- r "$dir/scan.bin" -o "$out" --tau -3
check "previous output intact" -- cmp -s "$out" "$dir/keep.ply"
check "no temporary left" -- test -z "$(ls -a "$dir" | grep '\.tmp\.')"
echo "bad input: $passed passed, $fail failed"
[ "$fail" -eq 0 ]
