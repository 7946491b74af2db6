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
/usr/bin/python3 - "$work" <<'PY'
import struct, sys, zlib

def pixels(path):
    """RGB rows of a PNG (8-bit RGB or RGBA, non-interlaced), by the standard library alone."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and colour in (2, 6), (depth, colour)
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride, rows, prev = zlib.decompress(idat), width * channels, [], bytearray(width * channels)
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - channels] if x >= channels else 0
            b, c = prev[x], prev[x - channels] if x >= channels else 0
            if kind == 1: line[x] = (line[x] + a) & 255
            elif kind == 2: line[x] = (line[x] + b) & 255
            elif kind == 3: line[x] = (line[x] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x:x + 3]) for x in range(0, stride, channels)])
        prev = line
    return rows

work = sys.argv[1]
height, level = pixels(work + "/height.png"), pixels(work + "/level.png")
background = (242, 244, 247)
total = len(height) * len(height[0])
covered = sum(1 for row in height for p in row if max(abs(p[i] - background[i]) for i in range(3)) > 12)
changed = sum(1 for r1, r2 in zip(height, level) for p, q in zip(r1, r2) if max(abs(p[i] - q[i]) for i in range(3)) > 24)
print(f"viewer-check: the mesh covers {100 * covered / total:.1f} % of the picture; height -> level changes {100 * changed / total:.1f} %")
assert covered > 0.10 * total, "the mesh is not visible"
assert changed > 0.03 * total, "switching the colouring changed nothing"
PY
