"""lidarsurf: triangle meshes from lidar scans (Roldao, de Charette, Verroust-Blondet, ITSC 2019).

numpy in, numpy out; the same Config as the C++ library and the CLI.

    import lidarsurf
    points = lidarsurf.read_points("000000.bin")
    mesh = lidarsurf.reconstruct(points, origin=(0, 0, 0))
    mesh.save("mesh.ply")
"""
import json as _json

from ._lidarsurf import (Config, Mesh, Reconstructor, __version__, points_view, read_mesh, read_points,
                         read_poses, reconstruct, set_simd_level, simd_level, simd_levels, simulate)
from ._lidarsurf import _evaluate_json

__all__ = ["Config", "Mesh", "Reconstructor", "reconstruct", "read_points", "read_mesh", "read_poses", "evaluate", "simulate", "points_view",
           "simd_level", "simd_levels", "set_simd_level", "__version__"]


def evaluate(mesh, gt_points, origin=(0.0, 0.0, 0.0), max_range=0.0, threshold=0.1, delta=0.2, seed=1):
    """Metrics of `mesh` against ground-truth points (an (N, 3) array), as a dict.

    Keys: 'paper' (AE/HD for P->GT, GT->P, sym; share within `delta`; cumulative curve; AE by range
    from `origin`) and 'surface' (accuracy, completeness, Chamfer-L1, precision/recall/F-score at
    `threshold`), as `lidarsurf evaluate --json` writes them (docs/evaluation.md).
    """
    return _json.loads(_evaluate_json(mesh, gt_points, list(origin), float(max_range), float(threshold),
                                      float(delta), int(seed)))
