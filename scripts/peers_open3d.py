#!/usr/bin/env python3
"""Runs the meshers users already have (Open3D, Debian's python3-open3d) on a simulated sequence,
so that `lidarsurf benchmark SEQ --peers SEQ/peers` scores them beside lidarsurf on the same
frames, against the same true surface (docs/benchmarks.md, "Accuracy against peers").

For every selected frame SEQ/velodyne/NNNNNN.bin (sensor frame, sensor at the origin) it writes
OUT/<method>/NNNNNN.ply and appends "frame seconds" to OUT/<method>/times.txt. Methods:
  poisson-d9, poisson-d10  screened Poisson (Kazhdan & Hoppe 2013), normals from a hybrid
                           kNN/radius PCA oriented toward the sensor, then the 5 % of vertices of
                           lowest density removed (the usual trim of unsupported surface)
  alpha-0.5                alpha shape, alpha = 0.5 m
  bpa                      ball pivoting, radii 0.1, 0.2, 0.4 m, same normals. Not in the default
                           list: on a 120k-point HDL-64 frame it did not finish one frame in
                           5 minutes on 2 cores (with radii up to 0.8 m either)
Times are wall seconds per frame, normal estimation included where the method needs normals.

Usage: peers_open3d.py SEQ [--out DIR] [--frames N] [--stride S] [--methods a,b]
"""
import argparse
import os
import sys
import time

import numpy as np

try:
    import open3d as o3d
except ImportError:
    sys.exit("peers_open3d.py: Open3D is missing; install Debian's python3-open3d (scripts/setup.sh peers)")

METHODS = ("poisson-d9", "poisson-d10", "alpha-0.5", "bpa")
DEFAULT_METHODS = ("poisson-d9", "poisson-d10", "alpha-0.5")


def read_kitti_bin(path):
    data = np.fromfile(path, dtype=np.float32)
    if data.size == 0 or data.size % 4 != 0:
        raise ValueError(f"{path}: not a KITTI scan (float32 x, y, z, intensity records)")
    pts = data.reshape(-1, 4)[:, :3].astype(np.float64)
    return pts[np.isfinite(pts).all(axis=1)]


def point_cloud(points, with_normals):
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    if with_normals:
        # 30 neighbours within 1 m (alpha * k_max of the paper, the support lidarsurf uses).
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=1.0, max_nn=30))
        pcd.orient_normals_towards_camera_location(np.zeros(3))
    return pcd


def poisson(points, depth):
    pcd = point_cloud(points, True)
    mesh, density = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(pcd, depth=depth)
    density = np.asarray(density)
    mesh.remove_vertices_by_mask(density < np.quantile(density, 0.05))
    return mesh


def alpha_shape(points, alpha):
    return o3d.geometry.TriangleMesh.create_from_point_cloud_alpha_shape(point_cloud(points, False), alpha)


def ball_pivoting(points):
    pcd = point_cloud(points, True)
    radii = o3d.utility.DoubleVector([0.1, 0.2, 0.4])
    return o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(pcd, radii)


def run(method, points):
    if method == "poisson-d9":
        return poisson(points, 9)
    if method == "poisson-d10":
        return poisson(points, 10)
    if method == "alpha-0.5":
        return alpha_shape(points, 0.5)
    if method == "bpa":
        return ball_pivoting(points)
    raise ValueError(method)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("seq", help="sequence directory (lidarsurf simulate -o SEQ)")
    ap.add_argument("--out", help="output directory (default SEQ/peers)")
    ap.add_argument("--frames", type=int, default=0, help="use only the first N selected frames (0 = all)")
    ap.add_argument("--stride", type=int, default=1, help="use every S-th frame")
    ap.add_argument("--methods", default=",".join(DEFAULT_METHODS), help="comma-separated, of: " + ", ".join(METHODS))
    args = ap.parse_args()
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    for m in methods:
        if m not in METHODS:
            sys.exit(f"peers_open3d.py: unknown method '{m}' (known: {', '.join(METHODS)})")
    if args.frames < 0 or args.stride < 1:
        sys.exit("peers_open3d.py: --frames must be >= 0 and --stride >= 1")
    velodyne = os.path.join(args.seq, "velodyne")
    if not os.path.isdir(velodyne):
        sys.exit(f"peers_open3d.py: {velodyne}: no such directory")
    count = 0
    while os.path.exists(os.path.join(velodyne, f"{count:06d}.bin")):
        count += 1
    frames = list(range(0, count, args.stride))
    if args.frames:
        frames = frames[: args.frames]
    if not frames:
        sys.exit(f"peers_open3d.py: {velodyne}: no scan")
    out = args.out or os.path.join(args.seq, "peers")
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    for m in methods:
        os.makedirs(os.path.join(out, m), exist_ok=True)
        open(os.path.join(out, m, "times.txt"), "w").close()
    for f in frames:
        points = read_kitti_bin(os.path.join(velodyne, f"{f:06d}.bin"))
        for m in methods:
            t0 = time.perf_counter()
            mesh = run(m, points)
            seconds = time.perf_counter() - t0
            target = os.path.join(out, m, f"{f:06d}.ply")
            tmp = target + ".tmp.ply"
            if not o3d.io.write_triangle_mesh(tmp, mesh, write_ascii=False, compressed=False,
                                              write_vertex_normals=False, write_vertex_colors=False):
                sys.exit(f"peers_open3d.py: cannot write {tmp}")
            os.replace(tmp, target)
            with open(os.path.join(out, m, "times.txt"), "a") as t:
                t.write(f"{f} {seconds:.4f}\n")
            print(f"peers: frame {f} {m}: {len(mesh.triangles)} triangles, {seconds:.2f} s", flush=True)
    print(f"peers: {len(frames)} frames x {len(methods)} methods -> {out}")


if __name__ == "__main__":
    main()
