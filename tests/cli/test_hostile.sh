#!/usr/bin/env bash
# Hostile inputs through the CLI, by class (docs/reliability.md, "Nothing lost, nothing crashes"):
# outputs that are links, pipes, devices or inputs; rows that would shift; sequences with gaps or
# mirrored poses; headers whose sizes wrap; streams without end; options that were accepted in
# error; messages carrying terminal escapes; and signals in the middle of a run. Each case
# states the exit code and what must hold on disk afterwards.
set -u
cli="$1"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
source "$(dirname "$0")/expect.sh"
cd "$dir"
r() { "$cli" reconstruct "$@"; }
sum() { md5sum "$1" | cut -d' ' -f1; }
"$cli" simulate --scene demo -o scan.bin >/dev/null || { echo "simulate failed"; exit 1; }
r scan.bin -o mesh.ply >/dev/null || { echo "reconstruct failed"; exit 1; }
scan_sum=$(sum scan.bin)

# --- Outputs that are not plain new files.
echo old > real.ply; ln -s real.ply link.ply
expect 0 "triangles" -- r scan.bin -o link.ply
check "a symbolic link output stays a link" -- test -L link.ply
check "its target gets the mesh" -- test "$(head -c 3 real.ply)" = ply
mkfifo pipe.ply; (cat pipe.ply > from_pipe.bin) & reader=$!
expect 0 "triangles" -- r scan.bin -o pipe.ply
wait $reader
check "a FIFO output stays a FIFO" -- test -p pipe.ply
check "the reader got the mesh" -- test "$(head -c 3 from_pipe.bin)" = ply
expect 0 "" -- r scan.bin -o /dev/null --mesh-format ply
check "/dev/null is still a device" -- test -c /dev/null
check "-o /dev/stdout: the mesh alone on stdout" -- test "$(r scan.bin -o /dev/stdout --mesh-format ply 2>/dev/null | head -c 3)" = ply
r scan.bin -o /dev/stdout --mesh-format ply 2>/dev/null > stdout.ply
check "-o /dev/stdout: the report not inside the mesh" -- test "$(tail -c 300 stdout.ply | grep -ac triangles)" = 0

# --- An output that is an input: refused before any work, for every command and output flag.
ln scan.bin hard.bin
"$cli" simulate --frames 2 -o seq >/dev/null 2>&1
seq_sum=$(sum seq/velodyne/000000.bin)
expect 2 "is the input" -- r scan.bin -o hard.bin
expect 2 "is the input" -- r scan.bin -o "$dir/./scan.bin"
expect 2 "is the input" -- "$cli" fuse seq -o seq/velodyne/000000.bin
expect 2 "is the input" -- "$cli" fuse seq -o seq/poses.txt --mesh-format ply
expect 2 "is the input" -- "$cli" bench scan.bin --json scan.bin --repeat 1
expect 2 "is the input" -- "$cli" simulate --scene mesh.ply --from 0,0,0 -o mesh.ply
expect 2 "same file" -- "$cli" simulate --scene demo -o a.bin --gt a.bin
expect 2 "same file" -- "$cli" simulate --scene demo -o a.bin --gt ./a.bin
expect 2 "holds the input" -- "$cli" simulate --frames 2 -o seq --scene seq/scene.ply --from 0,0,0
expect 2 "is the input" -- "$cli" evaluate mesh.ply scan.bin --json mesh.ply
expect 2 "is the input" -- "$cli" evaluate --holdout 0.5 scan.bin --mesh-out hard.bin
ln -s mesh.ply mesh_link.png
expect 2 "is the input" -- "$cli" render mesh.ply -o mesh_link.png
mkdir mine; echo notes > mine/notes.txt
expect 2 "did not write" -- "$cli" simulate --frames 2 -o mine
check "inputs unchanged" -- test "$(sum scan.bin)" = "$scan_sum" -a "$(sum seq/velodyne/000000.bin)" = "$seq_sum"
check "mesh.ply unchanged" -- test "$(head -c 3 mesh.ply)" = ply
check "a folder lidarsurf did not write is kept" -- test -f mine/notes.txt

# --- Output names whose format lidarsurf does not write: refused before any work, not written as PLY.
expect 2 "unknown mesh extension '.stl'" -- r scan.bin -o x.stl
expect 2 "unknown mesh extension" -- r scan.bin -o /dev/stdout
expect 2 "unknown mesh extension" -- "$cli" fuse seq -o map.vtk
expect 2 "unknown mesh extension" -- "$cli" evaluate --holdout 0.5 scan.bin --mesh-out held.stl
expect 2 "unknown point-file extension" -- "$cli" simulate --scene demo -o s.bin --gt gt.las
expect 0 "triangles" -- r scan.bin -o upper.PLY
check "no x.stl written" -- test ! -e x.stl

# --- Rows that would shift every later point, numbers in another locale.
hdr='ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n'
printf "${hdr}1 2 3\n4 5\n6 7 8 9\n" > short_row.ply
expect 3 "line 9: fewer values" -- r short_row.ply -o out.ply
printf "${hdr}1 2 3 4\n5 6 7\n8 9 10\n" > long_row.ply
expect 3 "line 8: more values" -- r long_row.ply -o out.ply
/usr/bin/python3 - <<'PY'
import struct
data = open("scan.bin", "rb").read()
pts = [struct.unpack_from("<3f", data, i) for i in range(0, len(data), 16)]
with open("comma.csv", "w") as c, open("dot.xyz", "w") as d, open("bom.csv", "w", encoding="utf-8-sig") as b:
    c.write("x;y;z\n"); b.write('"x","y","z"\n')
    for x, y, z in pts:
        c.write(("%r;%r;%r\n" % (x, y, z)).replace(".", ","))
        d.write("%r %r %r\n" % (x, y, z)); b.write("%r,%r,%r\n" % (x, y, z))
PY
tri_dot=$(r dot.xyz -o dot.ply 2>&1 | grep -oE '[0-9]+ triangles')
check "decimal-comma CSV: the same mesh as the plain text ($tri_dot)" -- test -n "$tri_dot" -a "$(r comma.csv -o comma.ply 2>&1 | grep -oE '[0-9]+ triangles')" = "$tri_dot"
check "byte-order mark and quoted header: the same mesh" -- test "$(r bom.csv -o bom.ply 2>&1 | grep -oE '[0-9]+ triangles')" = "$tri_dot"

# --- Sequences: a gap in the numbering, a mirrored pose or calibration.
cp -r seq gap; mv gap/velodyne/000001.bin gap/velodyne/000004.bin
expect 3 "000001.bin is missing" -- "$cli" fuse gap -o gap.ply
cp -r seq mirrored; awk 'NR==1 {$1 = -$1; $5 = -$5; $9 = -$9} {print}' seq/poses.txt > mirrored/poses.txt
expect 3 "reflection" -- "$cli" fuse mirrored -o m.ply
printf 'P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 1 0 0 0 0 1 0 0 0 0 -1 0\n' > mirrored_calib.txt
expect 3 "reflection" -- "$cli" fuse seq -o m.ply --calib mirrored_calib.txt

# --- Sizes that wrap, coordinates that overflow a ray tracer.
{ printf 'VERSION 0.7\nFIELDS x y z pad\nSIZE 8 8 8 8\nTYPE F F F F\nCOUNT 1 1 1 65533\nWIDTH 35184372088833\nHEIGHT 1\nPOINTS 35184372088833\nDATA binary_compressed\n'
  printf '\x70\x17\x00\x00\x00\x00\x08\x00'; head -c 6000 /dev/urandom; } > wrap.pcd
expect 3 "PCD" -- r wrap.pcd -o out.ply
expect 2 "within 1e7 m" -- "$cli" render mesh.ply -o far.png --eye 1e20,0,0
expect 2 "must differ" -- "$cli" render mesh.ply -o same.png --eye 1,2,3 --target 1,2,3

# --- Exit codes: the budget, options accepted in error, names, messages.
expect 5 "memory budget of 100 MiB" -- bash -c "head -c 300000000 /dev/zero | '$cli' reconstruct /dev/stdin --format bin --max-memory 100 -o z.ply"
expect 5 "memory budget" -- r scan.bin -o z.ply --max-memory 1
expect 2 "3 values|three numbers" -- r scan.bin -o out.ply --origin 1,2,3,4
expect 2 "three numbers" -- r scan.bin -o out.ply --origin 1,2,3,
expect 0 "triangles|no triangle" -- r scan.bin -o out.ply --nmin 1001
nmin_out=$(r scan.bin -o out.ply --nmin 1001 2>&1)
check "--nmin 1001 with the default method names no IMLS limit" -- test -z "$(grep -i imls <<<"$nmin_out")"
expect 2 "empty" -- r missing.bin -o ""
expect 2 "empty" -- "$cli" bench scan.bin --json ""
long=$(printf 'a%.0s' $(seq 251)).ply
expect 0 "triangles" -- r scan.bin -o "$long"
check "a 255-byte output name is written" -- test -f "$long"
expect 2 "1e-09" -- r scan.bin -o out.ply --voxel 1e-9
printf '1 2 3\n4 5 \x1b[2J\x1b]0;pwned\x07\r6\n' > escape.xyz
msg=$(r escape.xyz -o out.ply 2>&1)
check "messages carry no raw escape byte" -- test -z "$(printf '%s' "$msg" | tr -d '\n' | tr -d '[:print:]')"
check "and show it escaped" -- grep -q 'x1b' <<<"$msg"
printf '0 0 0\n0.1 0 0\n0 0.1 0\n1e12 5 5\n3e12 0 0\n' > outlier.xyz
expect 3 "#3 \(1e\+12, 5, 5\)" -- r outlier.xyz -o out.ply

# --- Signals: exit 128 + N, no temporary, earlier outputs untouched.
"$cli" simulate --frames 2 -o sig_seq >/dev/null 2>&1
before=$(sum sig_seq/poses.txt)
"$cli" simulate --frames 60 -o sig_seq >/dev/null 2>&1 & pid=$!
for i in $(seq 100); do ls -d sig_seq.tmp.* >/dev/null 2>&1 && break; sleep 0.1; done
sleep 0.5; kill -INT $pid; wait $pid; rc=$?
check "SIGINT during simulate exits 130 (got $rc)" -- test "$rc" -eq 130
check "the previous sequence is intact" -- test "$(sum sig_seq/poses.txt)" = "$before" -a "$(ls sig_seq/velodyne | wc -l)" -eq 2
check "no half-written sequence" -- test -z "$(ls -d sig_seq.tmp.* 2>/dev/null)"
"$cli" bench scan.bin --repeat 200 --no-reference --no-imls >/dev/null 2>&1 & pid=$!
sleep 2; kill -TERM $pid; wait $pid; rc=$?
check "SIGTERM during bench exits 143 (got $rc)" -- test "$rc" -eq 143
check "bench's scratch files are removed" -- test -z "$(ls -d /tmp/lidarsurf-bench.tmp.$pid.* 2>/dev/null)"
mkfifo slow_input.bin
"$cli" reconstruct slow_input.bin -o mesh.ply --format bin >/dev/null 2>hup.txt & pid=$!
exec 3<>slow_input.bin; timeout 20 head -c 160000 scan.bin >&3  # read-write open and a time limit: no hang if the reader is gone
sleep 0.5; kill -HUP $pid; wait $pid; rc=$?; exec 3>&-
check "SIGHUP while reading exits 129 (got $rc)" -- test "$rc" -eq 129
check "and says so" -- grep -q "interrupted by HUP" hup.txt
check "the previous mesh is intact" -- test "$(head -c 3 mesh.ply)" = ply
check "no temporary left anywhere" -- test -z "$(ls "$dir" | grep '\.tmp\.')"

echo "hostile: $passed passed, $fail failed"
[ "$fail" -eq 0 ]
