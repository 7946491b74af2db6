#!/usr/bin/env bash
# The live view end to end (make viewer-check): `lidarsurf fuse --serve` replays a short drive
# while headless Chromium (tests/viewer/live_view.mjs) watches it: a screenshot mid-drive must show
# the mesh, a later one must show it grown, and the mesh the page holds at the end must be fuse's
# output, triangle for triangle. Then Ctrl-C (SIGINT) must end the server with 0 and close the port.
# Usage: live_view_check.sh LIDARSURF_CLI [WORK_DIR]
set -euo pipefail
cli=$(realpath "$1")
work=${2:-$(mktemp -d)}
here=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$work" && mkdir -p "$work"
[ -d "$here/tests/viewer/node_modules/playwright-core" ] || { echo "live-view-check: no playwright-core (scripts/setup.sh viewer)"; exit 1; }
"$cli" simulate --frames 30 --length 80 --gt-beams 0 -o "$work/drive" --quiet >/dev/null
# --live-budget-ms 0: each scan's update meshes every block due, so the map the page shows grows
# with the drive however loaded the machine is (the budget's own behaviour is LiveMesh's tests').
"$cli" fuse "$work/drive" -o "$work/map.obj" --serve 0 --rate 2 --live-budget-ms 0 --quiet >"$work/fuse.out" 2>"$work/fuse.log" &
fuse=$!
trap 'kill $fuse 2>/dev/null || true' EXIT
url=""
for _ in $(seq 100); do
  url=$(grep -o 'http://[^ ]*/' "$work/fuse.log" | head -1 || true)
  [ -n "$url" ] && break
  sleep 0.1
done
[ -n "$url" ] || { cat "$work/fuse.log"; echo "live-view-check: fuse did not say where it serves"; exit 1; }
sleep 2  # the page opens mid-drive: it must catch up
node "$here/tests/viewer/live_view.mjs" "$url" "$work" 8 20
grep -q "written; the final map" "$work/fuse.log" || { cat "$work/fuse.log"; exit 1; }
kill -INT $fuse
status=0
wait $fuse || status=$?
trap - EXIT
[ "$status" -eq 0 ] || { cat "$work/fuse.log"; echo "live-view-check: fuse ended with $status after Ctrl-C, not 0"; exit 1; }
port=${url##*:}; port=${port%/}
if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then echo "live-view-check: port $port still open after the end"; exit 1; fi
/usr/bin/python3 "$here/scripts/live_view_compare.py" "$work"
