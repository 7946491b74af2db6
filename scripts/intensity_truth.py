#!/usr/bin/env python3
"""Vertex intensity against the simulator's truth: for each vertex of MESH (a PLY with an
`intensity` property, from `reconstruct` or `fuse` of a simulated drive), the reflectivity of the
truth surface nearest to it (SCENE: the drive's scene.ply, whose `intensity` is each surface's
reflectivity). The truth is sampled every --spacing metres over its triangles; vertices farther
than --max-distance from it (surface the scene does not hold there: movers, ghosts) are left out.

Prints, per material (truth reflectivity): vertices, median and 90th percentile of |error|, and
the share within --tolerance; then the same for the vertices whose truth is one material over a
disc of --margin metres (away from material borders, where a neighbourhood mixes two).

  scripts/intensity_truth.py map.ply drive/scene.ply [--spacing 0.05] [--margin 0.5]
"""
import argparse
import sys

import numpy as np
from scipy.spatial import cKDTree

import lidarsurf


def sample_triangles(mesh, spacing, rng):
    v, t = mesh.vertices, mesh.triangles
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    counts = np.maximum(1, np.ceil(area / spacing**2)).astype(np.int64)
    tri = np.repeat(np.arange(len(t)), counts)
    u, w = rng.random(len(tri)), rng.random(len(tri))
    flip = u + w > 1
    u[flip], w[flip] = 1 - u[flip], 1 - w[flip]
    points = a[tri] + u[:, None] * (b[tri] - a[tri]) + w[:, None] * (c[tri] - a[tri])
    return points, mesh.intensity[t[tri, 0]]


def report(name, err, truth, tolerance):
    print(f"{name}:")
    print("  reflectivity  vertices  median |err|  p90 |err|  within %.2f" % tolerance)
    for r in np.unique(truth):
        e = np.abs(err[truth == r])
        if len(e) < 20:
            continue
        print(f"  {r:12.2f}  {len(e):8d}  {np.median(e):12.4f}  {np.percentile(e, 90):9.4f}  {100 * np.mean(e <= tolerance):9.1f} %")
    e = np.abs(err)
    print(f"  {'all':>12}  {len(e):8d}  {np.median(e):12.4f}  {np.percentile(e, 90):9.4f}  {100 * np.mean(e <= tolerance):9.1f} %")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mesh")
    ap.add_argument("scene")
    ap.add_argument("--spacing", type=float, default=0.05, help="truth sample spacing, m")
    ap.add_argument("--max-distance", type=float, default=0.1, help="vertices farther from the truth are left out, m")
    ap.add_argument("--margin", type=float, default=0.5, help="radius over which the truth must be one material, m")
    ap.add_argument("--tolerance", type=float, default=0.05)
    ap.add_argument("--max-vertices", type=int, default=200000, help="a random subset of this many vertices is measured")
    a = ap.parse_args()
    mesh, scene = lidarsurf.read_mesh(a.mesh), lidarsurf.read_mesh(a.scene)
    if len(mesh.intensity) != len(mesh.vertices) or len(scene.intensity) != len(scene.vertices):
        sys.exit("intensity_truth: both meshes need a per-vertex intensity")
    samples, reflectivity = sample_triangles(scene, a.spacing, np.random.default_rng(1))
    tree = cKDTree(samples)
    rng = np.random.default_rng(2)
    chosen = np.arange(len(mesh.vertices))
    if len(chosen) > a.max_vertices:
        chosen = np.sort(rng.choice(chosen, a.max_vertices, replace=False))
    vertices, intensity = mesh.vertices[chosen], mesh.intensity[chosen]
    finite = np.isfinite(intensity)
    dist, nearest = tree.query(vertices)
    on = (dist <= a.max_distance) & finite
    print(f"{len(mesh.vertices)} vertices, {len(chosen)} measured: {np.sum(~finite)} without intensity, {np.sum(on)} within "
          f"{a.max_distance} m of the truth ({len(samples)} truth samples)")
    truth = reflectivity[nearest[on]]
    err = intensity[on] - truth
    report("every vertex on the truth", err, truth, a.tolerance)
    # One material over the disc around the vertex: the truth samples within `margin` agree.
    idx = np.flatnonzero(on)
    pure = np.zeros(len(idx), dtype=bool)
    for j, near in enumerate(tree.query_ball_point(vertices[idx], a.margin)):
        r = reflectivity[near]
        pure[j] = len(r) > 0 and np.all(r == r[0])
    report(f"away from material borders (one material within {a.margin} m)", err[pure], truth[pure], a.tolerance)


if __name__ == "__main__":
    main()
