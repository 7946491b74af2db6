#!/usr/bin/env python3
"""The ground between far rings in the ring hold-out (docs/benchmarks.md, "Real scans: ring hold-out").

Meshes the even rings of a KITTI-order scan (rings from the point order, as
`lidarsurf evaluate --holdout-rings` takes them) and reports, for the odd-ring points at 20-30 m
from the sensor below z = -1.3 m (the road and the terrain beside it), the share with no surface
within 0.3 m and the share within 0.1 m. Distances go to a dense sampling of the mesh triangles
(about 3 cm apart), so they are exact to that spacing.

Usage: PYTHONPATH=build/python python3 scripts/ring_holdout_ground.py SCAN.bin [field=value ...]
       (fields of lidarsurf.Config, e.g. bridge_reach=0)
"""
import sys

import numpy as np
from scipy.spatial import cKDTree

import lidarsurf


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    config = lidarsurf.Config()
    for arg in sys.argv[2:]:
        name, value = arg.split("=")
        setattr(config, name, type(getattr(config, name))(float(value)))
    points = np.fromfile(sys.argv[1], np.float32).reshape(-1, 4)[:, :3].astype(np.float64)
    rings = np.asarray(lidarsurf.rings_from_order(points))
    even, odd = points[rings % 2 == 0], points[rings % 2 == 1]
    mesh = lidarsurf.reconstruct(even, config=config)
    v, t = np.array(mesh.vertices), np.array(mesh.triangles)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    samples = [v]
    for u in np.linspace(0, 1, 8):
        for w in np.linspace(0, 1 - u, max(1, int(round((1 - u) * 7)) + 1)):
            samples.append(a + u * (b - a) + w * (c - a))
    r = np.hypot(odd[:, 0], odd[:, 1])
    ground = odd[(r >= 20) & (r < 30) & (odd[:, 2] < -1.3)]
    d, _ = cKDTree(np.concatenate(samples)).query(ground, distance_upper_bound=1.0)
    print(f"{sys.argv[1]}: {len(ground)} ground points at 20-30 m; no surface within 0.3 m: {100 * np.mean(d > 0.3):.1f} %; "
          f"within 0.1 m: {100 * np.mean(d < 0.1):.1f} %")


if __name__ == "__main__":
    main()
