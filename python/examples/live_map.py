"""A live map: a simulated drive (`lidarsurf simulate --frames N -o DIR`) fused scan by scan, the
live mesh kept by applying each update's MeshDelta, as a viewer or planner would; at scan
`--stop` the live mesh is saved, and beside it the exact mesh of that moment.

usage: python live_map.py DIR --stop 500 --budget-ms 30 -o live.ply [--exact exact.ply]
"""
import argparse

import numpy as np

import lidarsurf


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("sequence")
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--stop", type=int, default=0, help="last scan (0: all)")
    p.add_argument("--budget-ms", type=float, default=30.0)
    p.add_argument("--exact")
    a = p.parse_args()
    rec = lidarsurf.Reconstructor()
    live = {}  # block key -> Mesh: the client's copy of the live mesh
    for update in lidarsurf.fuse_live(a.sequence, budget_ms=a.budget_ms, reconstructor=rec, frames=a.stop):
        for key in update.delta.removed:
            del live[key]
        for key, mesh in update.delta.changed:
            live[key] = mesh
    stop = update.scan + 1
    # The client's blocks as one mesh (the same triangles as rec.live_mesh()).
    vertices, triangles, base = [], [], 0
    for mesh in live.values():
        vertices.append(mesh.vertices)
        triangles.append(mesh.triangles.astype(np.int64) + base)
        base += len(mesh.vertices)
    lidarsurf.Mesh(np.concatenate(vertices), np.concatenate(triangles)).save(a.output)
    print(f"{stop} scans, live mesh: {sum(len(t) for t in triangles)} triangles in {len(live)} blocks -> {a.output}")
    if a.exact:
        exact = rec.extract_mesh()
        exact.save(a.exact)
        print(f"exact mesh: {len(exact.triangles)} triangles -> {a.exact}")


if __name__ == "__main__":
    main()
