#!/usr/bin/env python3
"""Compares two binary PLY meshes lidarsurf wrote, vertex by vertex both ways: each vertex's
distance to the nearest vertex of the other mesh. At most a share SHARE (default 0) of either
mesh's vertices may lie farther than TOL metres, and at most FAR_SHARE (default 0) farther than
FAR (default TOL). Exit 1 otherwise. Vertices found bit for bit in the other mesh are at 0; the
distance of the others is computed by brute force.

Usage: compare_meshes.py A.ply B.ply TOL [SHARE [FAR FAR_SHARE]]"""
import sys

import numpy as np

VERTEX = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("nx", "<f4"), ("ny", "<f4"), ("nz", "<f4"), ("level", "u1"), ("confidence", "<f4")])


def read(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode()
    if "property float confidence" not in header or "binary_little_endian" not in header:
        sys.exit("%s: not the binary PLY layout lidarsurf writes" % path)
    nv = int(header.split("element vertex ")[1].split()[0])
    v = np.frombuffer(data, VERTEX, nv, end)
    return np.ascontiguousarray(np.stack([v["x"], v["y"], v["z"]], axis=1))


def distances(a, b):
    """For each vertex of a, the distance to the nearest vertex of b."""
    key = lambda p: p.view(np.dtype((np.void, 12))).ravel()
    d = np.zeros(len(a))
    missing = np.flatnonzero(~np.isin(key(a), key(b)))
    b64 = b.astype(np.float64)
    for i in missing:
        d[i] = np.sqrt(((b64 - a[i].astype(np.float64)) ** 2).sum(axis=1).min())
    return d


def main():
    a, b = read(sys.argv[1]), read(sys.argv[2])
    tol = float(sys.argv[3])
    share = float(sys.argv[4]) if len(sys.argv) > 4 else 0.0
    far = float(sys.argv[5]) if len(sys.argv) > 5 else tol
    far_share = float(sys.argv[6]) if len(sys.argv) > 6 else 0.0
    ok = True
    for name, d in (("first", distances(a, b)), ("second", distances(b, a))):
        beyond = float(np.mean(d > tol)) if len(d) else 0.0
        far_beyond = float(np.mean(d > far)) if len(d) else 0.0
        print("%s mesh: %d vertices; %.4f%% farther than %.3g m from the other's (at most %.4f%%), %.4f%% farther than %.3g m "
              "(at most %.4f%%); the farthest %.3g m" % (name, len(d), 100 * beyond, tol, 100 * share, 100 * far_beyond, far,
                                                         100 * far_share, float(d.max()) if len(d) else 0.0))
        ok = ok and beyond <= share and far_beyond <= far_share
    print("alike" if ok else "different")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
