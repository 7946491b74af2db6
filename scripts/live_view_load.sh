#!/usr/bin/env bash
# What serving the live view costs fusion, and what several clients, one of them stalled, get
# (docs/benchmarks.md, "Live view"): the same drive fused with --live, then with --serve and
# READERS reading clients plus STALLED ones that never read (scripts/live_view_load.mjs), ROUNDS
# times alternated; prints each run's update median / p90 (ms) from fuse's --json report, the
# server's own share (serve_ms), and what every client got.
# Usage: live_view_load.sh LIDARSURF_CLI DRIVE_DIR [WORK_DIR] (READERS=4 STALLED=1 ROUNDS=2)
set -euo pipefail
cli=$(realpath "$1") drive=$2 work=${3:-$(mktemp -d)}
readers=${READERS:-4} stalled=${STALLED:-1} rounds=${ROUNDS:-2}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work"
summary() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import json, statistics, sys
j = json.load(open(sys.argv[2]))
rows = j["per_frame"]
def med(key):
    v = sorted(r[key] for r in rows if key in r)
    return (statistics.median(v), v[int(0.9 * (len(v) - 1))]) if v else (float("nan"), float("nan"))
u, s = med("update_ms"), med("serve_ms")
print(f"{sys.argv[1]:<22} update median {u[0]:6.1f} p90 {u[1]:6.1f} ms; serve median {s[0]:.3f} p90 {s[1]:.3f} ms; "
      f"peak {j['peak_resident_mib']:.0f} MiB")
if "serve" in j:
    v = j["serve"]
    print(f"  server at the end of the drive: {v['clients_accepted']} clients accepted, {v['clients_dropped']} dropped, "
          f"{v['clients_now']} connected, {v['messages']} messages, {v['bytes'] / 1e9:.2f} GB, {v.get('wire_bytes', 0) / 1e9:.2f} GB on the wire")
PY
}
for round in $(seq "$rounds"); do
  "$cli" fuse "$drive" -o "$work/live.ply" --live --quiet --json "$work/live_$round.json" >/dev/null
  summary "live, round $round" "$work/live_$round.json"
  "$cli" fuse "$drive" -o "$work/served.ply" --serve 0 --quiet --json "$work/served_$round.json" >/dev/null 2>"$work/serve.log" &
  fuse=$!
  url=""
  for _ in $(seq 100); do url=$(grep -o 'http://[^ ]*/' "$work/serve.log" | head -1 || true); [ -n "$url" ] && break; sleep 0.1; done
  node --experimental-websocket --no-warnings "$here/live_view_load.mjs" "$url" "$readers" "$stalled" "$work/clients_$round.json" >/dev/null
  for _ in $(seq 600); do grep -q "until Ctrl-C" "$work/serve.log" && break; sleep 0.1; done
  kill -INT $fuse; wait $fuse
  summary "served, round $round" "$work/served_$round.json"
  /usr/bin/python3 -c "
import json, sys
for c in json.load(open(sys.argv[1])):
    if c['kind'] == 'reader':
        print(f\"  reader {c['id']}: {c['messages']} messages, {c['mb']} MB, scans {c['scans']}, final {c['final']} at {c.get('final_s', 0):.1f} s\")
    else:
        print(f\"  stalled {c['id']}: handshake {c['handshake']} (it reads nothing more, so it cannot see the server close it)\")
" "$work/clients_$round.json"
done
