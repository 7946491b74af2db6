#!/usr/bin/env bash
# `lidarsurf view` without a browser: the page is one self-contained file (nothing loaded from
# elsewhere), its data block decodes to the mesh's own vertices, triangles, levels and points, and
# bad arguments get their exit codes. (The page in a real browser: scripts/viewer_check.sh.)
set -u
cli="$1"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
source "$(dirname "$0")/../cli/expect.sh"
"$cli" simulate --scene demo -o "$dir/scan.bin" >/dev/null
"$cli" reconstruct "$dir/scan.bin" -o "$dir/mesh.ply" >/dev/null
expect 0 "triangles, [0-9]+ points -> .*mesh.html" -- "$cli" view "$dir/mesh.ply" --points "$dir/scan.bin" --max-points 5000
check "default output name" -- test -s "$dir/mesh.html"
check "self-contained: no src= or href=, no import" -- bash -c "! grep -qiE '<script[^>]* src=|<link |import\\(' '$dir/mesh.html'"
check "three.js inlined" -- grep -q "THREE" "$dir/mesh.html"
/usr/bin/python3 - "$dir" <<'PY' || { echo "FAIL: the page's data does not match the mesh"; fail=$((fail + 1)); }
import base64, json, re, struct, sys
d = sys.argv[1]
page = open(d + "/mesh.html", encoding="ascii").read()
data = json.loads(re.search(r'<script type="application/json" id="lidarsurf-data">(.*?)</script>', page, re.S).group(1))
raw = open(d + "/mesh.ply", "rb").read()
head = raw[:raw.index(b"end_header\n")].decode()
nv = int(re.search(r"element vertex (\d+)", head).group(1))
nt = int(re.search(r"element face (\d+)", head).group(1))
assert len(base64.b64decode(data["vertices"])) == 12 * nv, "vertices"
assert len(base64.b64decode(data["triangles"])) == 12 * nt, "triangles"
assert len(base64.b64decode(data["levels"])) == nv, "levels"
assert len(base64.b64decode(data["confidence"])) == 4 * nv, "confidence"
pts = len(base64.b64decode(data["points"])) // 12
assert 4000 <= pts <= 5000, pts
# The first vertex, about the centre, is the PLY's first vertex (float32 x, y, z first in its records).
first = struct.unpack_from("<3f", raw, len(head) + len("end_header\n"))
v0 = struct.unpack_from("<3f", base64.b64decode(data["vertices"]), 0)
assert all(abs(v0[a] + data["centre"][a] - first[a]) < 1e-3 for a in range(3)), (v0, first)
PY
expect 2 "\.html" -- "$cli" view "$dir/mesh.ply" -o "$dir/mesh.png"
expect 2 "colour" -- "$cli" view "$dir/mesh.ply" --colour rainbow
expect 0 "triangles" -- "$cli" view "$dir/mesh.ply" -o "$dir/normal.html" --colour normal   # every colouring the page has
grep -q '"colour":"normal"' "$dir/normal.html" || { echo "FAIL: --colour normal not in the page"; fail=$((fail + 1)); }
# The mesh's tau reaches the page (its confidence colouring marks the vertices below it); 0 is refused.
expect 0 "triangles" -- "$cli" view "$dir/mesh.ply" -o "$dir/tau.html" --colour confidence --tau 0.3
grep -q '"tau":0.3' "$dir/tau.html" || { echo "FAIL: --tau not in the page"; fail=$((fail + 1)); }
expect 2 "tau" -- "$cli" view "$dir/mesh.ply" -o "$dir/tau0.html" --tau 0
ln -s "$dir/mesh.ply" "$dir/alias.html"
expect 2 "is the input" -- "$cli" view "$dir/mesh.ply" -o "$dir/alias.html"
printf 'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n' > "$dir/points.ply"
expect 3 "no triangle" -- "$cli" view "$dir/points.ply"
echo "view: $passed passed, $fail failed"
[ "$fail" -eq 0 ]
