#!/usr/bin/env bash
# The page `lidarsurf view` writes, in a real browser: headless Chromium (Debian's chromium, WebGL
# through SwiftShader) takes screenshots of a demo mesh coloured by height and by level; the mesh
# must cover a good part of the picture, and switching the colouring must change it.
# Usage: viewer_check.sh LIDARSURF_CLI [WORK_DIR]
set -euo pipefail
cli=$1
work=${2:-$(mktemp -d)}
mkdir -p "$work"
browser=$(command -v chromium || command -v chromium-browser || true)
[ -n "$browser" ] || { echo "viewer-check: no chromium (apt-get install chromium)"; exit 1; }
"$cli" simulate --scene demo -o "$work/scan.bin" >/dev/null
"$cli" reconstruct "$work/scan.bin" -o "$work/mesh.ply" >/dev/null
"$cli" view "$work/mesh.ply" -o "$work/mesh.html" --points "$work/scan.bin" >/dev/null
for colour in height level; do
  timeout 120 "$browser" --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --hide-scrollbars \
    --window-size=900,600 --virtual-time-budget=10000 --screenshot="$work/$colour.png" "file://$work/mesh.html#colour=$colour" \
    >"$work/chromium-$colour.log" 2>&1 || { cat "$work/chromium-$colour.log"; exit 1; }
done
/usr/bin/python3 - "$work" "$(dirname "$0")" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
from png_rows import BACKGROUND, pixels

work = sys.argv[1]
height, level = pixels(work + "/height.png"), pixels(work + "/level.png")
total = len(height) * len(height[0])
covered = sum(1 for row in height for p in row if max(abs(p[i] - BACKGROUND[i]) for i in range(3)) > 12)
changed = sum(1 for r1, r2 in zip(height, level) for p, q in zip(r1, r2) if max(abs(p[i] - q[i]) for i in range(3)) > 24)
print(f"viewer-check: the mesh covers {100 * covered / total:.1f} % of the picture; height -> level changes {100 * changed / total:.1f} %")
assert covered > 0.10 * total, "the mesh is not visible"
assert changed > 0.03 * total, "switching the colouring changed nothing"
PY
