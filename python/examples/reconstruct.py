"""Reconstruct a scan, print the metrics against ground truth, convert to Open3D if installed.

    PYTHONPATH=build/python /usr/bin/python3 python/examples/reconstruct.py [scan.bin]
"""
import sys

import lidarsurf

if len(sys.argv) > 1:  # a real scan: no ground truth, so measure by hold-out style self-consistency
    points, gt = lidarsurf.read_points(sys.argv[1]), None
else:  # the built-in simulated scan and its noise-free 316-beam ground truth
    points, gt = lidarsurf.simulate(seed=1), lidarsurf.simulate(seed=1, ground_truth=True)

config = lidarsurf.Config()  # the paper's defaults; the same struct the CLI fills
mesh = lidarsurf.reconstruct(points, origin=(0, 0, 0), config=config)
print(f"{points.shape[0]} points -> {mesh}")
metrics = lidarsurf.evaluate(mesh, gt if gt is not None else points)
print("AE P->GT {:.3f} m, AE sym {:.3f} m, F-score@0.1 {:.1%}".format(
    metrics["paper"]["p_to_gt"]["mean"], metrics["paper"]["ae_sym"], metrics["surface"]["fscore"]))
mesh.save("mesh.ply")

try:
    import open3d as o3d
except ImportError:
    o3d = None
if o3d is not None:
    tm = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(mesh.vertices),
                                   o3d.utility.Vector3iVector(mesh.triangles.astype("int32")))
    tm.vertex_normals = o3d.utility.Vector3dVector(mesh.normals.astype("float64"))
    print("open3d:", tm)
