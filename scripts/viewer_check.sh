#!/usr/bin/env bash
# The page `lidarsurf view` writes, in a real browser: headless Chromium (Debian's chromium, WebGL
# through SwiftShader) takes screenshots of a demo mesh coloured by height and by level; the mesh
# must cover a good part of the picture, and switching the colouring must change it. Then a VLP-16
# frame of the town coloured by confidence: both the measured surface (the ramp) and the surface
# bridged between its rings (magenta, confidence below tau) must show; coloured by intensity, it is
# grey (its materials' reflectivity), from dark to light.
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
# A sparse lidar: its rings are bridged, at a confidence below tau.
"$cli" simulate --scene town --sensor vlp16 --frames 1 -o "$work/vlp16.bin" >/dev/null
"$cli" reconstruct "$work/vlp16.bin" -o "$work/vlp16.ply" >/dev/null
"$cli" view "$work/vlp16.ply" -o "$work/vlp16.html" >/dev/null
timeout 120 "$browser" --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --hide-scrollbars \
  --window-size=900,600 --virtual-time-budget=10000 --screenshot="$work/confidence.png" "file://$work/vlp16.html#colour=confidence" \
  >"$work/chromium-confidence.log" 2>&1 || { cat "$work/chromium-confidence.log"; exit 1; }
timeout 120 "$browser" --headless=new --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader --hide-scrollbars \
  --window-size=900,600 --virtual-time-budget=10000 --screenshot="$work/intensity.png" "file://$work/vlp16.html#colour=intensity" \
  >"$work/chromium-intensity.log" 2>&1 || { cat "$work/chromium-intensity.log"; exit 1; }
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
# Confidence: magenta (red and blue well above green; no colour of the ramp is) is inferred surface.
conf = pixels(work + "/confidence.png")
mesh = [p for row in conf for p in row if max(abs(p[i] - BACKGROUND[i]) for i in range(3)) > 12]
magenta = sum(1 for p in mesh if p[0] > p[1] + 40 and p[2] > p[1] + 40)
print(f"viewer-check: the VLP-16 mesh covers {100 * len(mesh) / total:.1f} %; magenta (inferred) {100 * magenta / max(1, len(mesh)):.1f} % of it")
assert len(mesh) > 0.05 * total, "the VLP-16 mesh is not visible"
assert 0.02 * len(mesh) < magenta < 0.9 * len(mesh), "the confidence colouring does not tell inferred from measured surface"
# Intensity: the mesh's pixels are grey (lit, so r = g = b within rounding), dark and light ones both.
inten = pixels(work + "/intensity.png")
shown = [p for row in inten for p in row if max(abs(p[i] - BACKGROUND[i]) for i in range(3)) > 12]
greys = sorted(p[0] for p in shown if max(p) - min(p) <= 3)
print(f"viewer-check: by intensity, {100 * len(greys) / max(1, len(shown)):.1f} % of the mesh's pixels grey, "
      f"5th-95th percentile {greys[len(greys) // 20] if greys else 0}-{greys[19 * len(greys) // 20] if greys else 0}")
assert len(shown) > 0.05 * total and len(greys) > 0.95 * len(shown), "the intensity colouring is not grey"
assert greys[19 * len(greys) // 20] - greys[len(greys) // 20] > 40, "the intensity colouring shows one grey"
PY
