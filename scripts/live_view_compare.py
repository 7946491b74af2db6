"""The live view's end state against fuse's output (scripts/live_view_check.sh): the screenshots
show a mesh that grew, and the mesh the page holds at the end (page_mesh.json, decoded by the
page from the stream) is the mesh fuse wrote (map.obj): every triangle of one is in the other,
within the stream's quantization (a quarter of a millimetre)."""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
from png_rows import covered_share, pixels  # noqa: E402

TOLERANCE = 0.3e-3  # metres: the stream's 0.5 mm position steps (live_stream.hpp), and float32


def read_obj(path):
    vertices, triangles = [], []
    for line in open(path):
        if line.startswith("v "):
            vertices.append(tuple(float(x) for x in line.split()[1:4]))
        elif line.startswith("f "):
            triangles.append(tuple(int(x.split("/")[0]) - 1 for x in line.split()[1:4]))
    return vertices, triangles


def corners(vertices, triangles):
    return [tuple(vertices[i] for i in t) for t in triangles]


def same(t, u):
    """Whether two triangles have the same corners in the same cyclic order (orientation kept)."""
    close = lambda p, q: all(abs(p[i] - q[i]) <= TOLERANCE for i in range(3))  # noqa: E731
    return any(all(close(t[k], u[(k + r) % 3]) for k in range(3)) for r in range(3))


def unmatched(a, b):
    """Triangles of a with no triangle of b within TOLERANCE at each corner (b used once each)."""
    centroid = lambda t: tuple(sum(p[i] for p in t) / 3 for i in range(3))  # noqa: E731
    cell = lambda c: tuple(int(x // 0.01) for x in c)  # noqa: E731 (centroids in 1 cm cells)
    grid = {}
    for j, t in enumerate(b):
        grid.setdefault(cell(centroid(t)), []).append(j)
    used, missing = set(), 0
    for t in a:
        cx, cy, cz = cell(centroid(t))
        found = next((j for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)
                      for j in grid.get((cx + dx, cy + dy, cz + dz), []) if j not in used and same(t, b[j])), None)
        if found is None:
            missing += 1
        else:
            used.add(found)
    return missing


work = sys.argv[1]
report = json.load(open(os.path.join(work, "live_view.json")))
mid, later = covered_share(pixels(os.path.join(work, "mid.png"))), covered_share(pixels(os.path.join(work, "later.png")))
print(f"live-view-check: mid-drive {report['mid']['scans']} scans, {report['mid']['triangles']} triangles, {100 * mid:.1f} % of the "
      f"picture; later {report['later']['scans']} scans, {report['later']['triangles']} triangles, {100 * later:.1f} %; "
      f"final: {report['info']}")
assert mid > 0.05, "mid-drive, the mesh is not visible"
assert later > 0.05, "later, the mesh is not visible"
assert report["later"]["scans"] > report["mid"]["scans"], "no scan came between the screenshots"
assert report["later"]["triangles"] > report["mid"]["triangles"], "the map did not grow between the screenshots"

page = json.load(open(os.path.join(work, "page_mesh.json")))
pv = [tuple(page["positions"][i:i + 3]) for i in range(0, len(page["positions"]), 3)]
pt = [tuple(page["indices"][i:i + 3]) for i in range(0, len(page["indices"]), 3)]
ov, ot = read_obj(os.path.join(work, "map.obj"))
a, b = corners(pv, pt), corners(ov, ot)
print(f"live-view-check: the page holds {len(a)} triangles, fuse wrote {len(b)}")
assert len(a) == len(b), "the page's final mesh and fuse's output differ in size"
missing = unmatched(a, b)
assert missing == 0, f"{missing} of the page's triangles are not in fuse's output"
print("live-view-check: the page's final mesh is fuse's output, triangle for triangle")
