#!/usr/bin/env python3
"""Compares two binary PLY meshes lidarsurf wrote: the same triangles (vertex indices), and their
vertices within TOL metres of their counterparts but for a share of at most SHARE (default 0),
which must still lie within FAR metres (default TOL). Exit 1 otherwise.

Usage: compare_meshes.py A.ply B.ply TOL [SHARE FAR]"""
import sys

import numpy as np

VERTEX = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4"), ("level", "u1"), ("confidence", "<f4")])
FACE = np.dtype([("n", "u1"), ("v", "<i4", 3)])


def read(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    if "property float confidence" not in header or "binary_little_endian" not in header:
        sys.exit("%s: not the binary PLY layout lidarsurf writes" % path)
    nv = int(header.split("element vertex ")[1].split()[0])
    nf = int(header.split("element face ")[1].split()[0])
    v = np.frombuffer(data, VERTEX, nv, end)
    f = np.frombuffer(data, FACE, nf, end + nv * VERTEX.itemsize)
    return np.stack([v["x"], v["y"], v["z"]], axis=1).astype(np.float64), f["v"]


def main():
    (va, fa), (vb, fb) = read(sys.argv[1]), read(sys.argv[2])
    tol = float(sys.argv[3])
    share = float(sys.argv[4]) if len(sys.argv) > 4 else 0.0
    far = float(sys.argv[5]) if len(sys.argv) > 5 else tol
    if va.shape != vb.shape or fa.shape != fb.shape or not np.array_equal(fa, fb):
        print("different meshes: %d/%d vertices, %d/%d triangles" % (len(va), len(vb), len(fa), len(fb)))
        sys.exit(1)
    d = np.abs(va - vb).max(axis=1) if len(va) else np.zeros(1)
    beyond = float(np.mean(d > tol))
    print("%d vertices, %d triangles alike; %.4f%% of vertices beyond %.3g m (at most %.4f%%), the farthest %.3g m (at most %.3g)"
          % (len(va), len(fa), 100 * beyond, tol, 100 * share, float(d.max()), far))
    sys.exit(0 if beyond <= share and d.max() <= far else 1)


if __name__ == "__main__":
    main()
