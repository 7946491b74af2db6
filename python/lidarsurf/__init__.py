"""lidarsurf: triangle meshes from lidar scans (Roldao, de Charette, Verroust-Blondet, ITSC 2019).

numpy in, numpy out; the same Config as the C++ library and the CLI.

    import lidarsurf
    points = lidarsurf.read_points("000000.bin")
    mesh = lidarsurf.reconstruct(points, origin=(0, 0, 0))
    mesh.save("mesh.ply")
"""
import json as _json

import collections as _collections
import os as _os

from ._lidarsurf import (Config, Mesh, MeshDelta, Reconstructor, TileConfig, TilePlan, __version__, decode_live_message, encode_live_message,
                         empty_rays,
                         RecordingScans, fuse_tile, fuse_tile_group, points_view, read_mesh, read_points, read_poses, read_recording, read_rings, reconstruct,
                         rings_from_order,
                         sequence_frames, sequence_reaches, set_simd_level, simd_level, simd_levels, simulate)
from ._lidarsurf import _evaluate_json, _ring_holdout_json

__all__ = ["Config", "Mesh", "MeshDelta", "Reconstructor", "reconstruct", "read_points", "read_mesh", "read_poses", "read_rings", "evaluate",
           "ring_holdout", "rings_from_order", "simulate", "points_view", "simd_level", "simd_levels", "set_simd_level",
           "LiveUpdate", "fuse_live", "decode_live_message", "encode_live_message", "TileConfig", "TilePlan", "sequence_frames", "sequence_reaches", "fuse_tile", "fuse_tile_group", "fuse_tiles",
           "TileResult", "read_recording", "RecordingScans", "empty_rays", "__version__"]


# A Config travels to other processes (Dask workers) as its fields.
_CONFIG_FIELDS = sorted(name for name in dir(Config) if isinstance(getattr(Config, name), property))


def _config_from(fields):
    c = Config()
    for name, value in fields.items():
        setattr(c, name, value)
    return c


Config.__reduce__ = lambda self: (_config_from, ({name: getattr(self, name) for name in _CONFIG_FIELDS},))



def __getattr__(name):
    # fuse_tiles and TileResult live in lidarsurf.tiles, imported on first use: `python3 -m
    # lidarsurf.tiles` then runs a module the package has not imported yet.
    if name in ("fuse_tiles", "TileResult"):
        from . import tiles
        return getattr(tiles, name)
    raise AttributeError(f"module 'lidarsurf' has no attribute '{name}'")

LiveUpdate = _collections.namedtuple("LiveUpdate", ["scan", "pose", "delta"])
LiveUpdate.__doc__ = """One scan of fuse_live(): its index in the sequence, the sensor's (4, 4) pose, and the MeshDelta."""


def _is_recording(path):
    ext = _os.path.splitext(path)[1].lower()
    return ext in (".pcap", ".pcapng", ".bag", ".db3", ".mcap") or _os.path.isfile(_os.path.join(path, "metadata.yaml"))


def fuse_live(sequence, budget_ms=30.0, reconstructor=None, first=0, frames=0, step=1, poses=None, times=None, topic=None):
    """Fuse a sequence (KITTI layout: velodyne/NNNNNN.bin and poses.txt, as `lidarsurf simulate` writes
    it) scan by scan, yielding a LiveUpdate after each: what `lidarsurf fuse --serve` streams to its
    page, for a viewer or planner of your own. Apply each delta's `removed`, then its `changed`, to a
    dict {key: Mesh} to hold the live mesh. Pass a Reconstructor (with your Config) to keep it: its
    extract_mesh() gives the exact mesh at the end: the triangles `fuse` writes.

    `sequence` may be a recording (pcap, ROS 1 bag, ROS 2 bag) with `poses`, the sensor's trajectory
    (TUM, or KITTI poses with their `times`), as read_recording takes them; without `poses`, a bag's
    own /tf (poses="recording"). Its scans within the trajectory's span come de-skewed, each from the
    sensor's position at its stamp; `first`, `frames` and `step` count those scans.
    """
    rec = reconstructor if reconstructor is not None else Reconstructor()
    if _is_recording(sequence):
        scans = read_recording(sequence, topic=topic, poses="recording" if poses is None else poses, times=times)
        last = first + frames * step if frames else None
        for i, (_, points, _, pose) in enumerate(scans):
            if last is not None and i >= last:
                break
            if i < first or (i - first) % step:
                continue
            rec.integrate_from(points @ pose[:3, :3].T + pose[:3, 3], pose[:3, 3])
            yield LiveUpdate(i, pose, rec.update_mesh(budget_ms=budget_ms))
        return
    poses = read_poses(_os.path.join(sequence, "poses.txt"))
    scans = sorted(f for f in _os.listdir(_os.path.join(sequence, "velodyne")) if f.endswith(".bin"))
    if len(poses) < len(scans):
        raise ValueError(f"{sequence}: {len(poses)} poses for {len(scans)} scans")
    indices = list(range(first, len(scans), step))
    if frames:
        indices = indices[:frames]
    for i in indices:
        pose = poses[i]
        points = read_points(_os.path.join(sequence, "velodyne", scans[i]))
        rec.integrate_from(points @ pose[:3, :3].T + pose[:3, 3], pose[:3, 3])
        yield LiveUpdate(i, pose, rec.update_mesh(budget_ms=budget_ms))


def evaluate(mesh, gt_points, origin=(0.0, 0.0, 0.0), max_range=0.0, threshold=0.1, delta=0.2, seed=1):
    """Metrics of `mesh` against ground-truth points (an (N, 3) array), as a dict.

    Keys: 'paper' (AE/HD for P->GT, GT->P, sym; share within `delta`; cumulative curve; AE by range
    from `origin`) and 'surface' (accuracy, completeness, Chamfer-L1, precision/recall/F-score at
    `threshold`), as `lidarsurf evaluate --json` writes them (docs/evaluation.md).
    """
    return _json.loads(_evaluate_json(mesh, gt_points, list(origin), float(max_range), float(threshold),
                                      float(delta), int(seed)))


def ring_holdout(points, rings=None, origin=(0.0, 0.0, 0.0), config=None, method=None, max_range=30.0, range_bin=10.0):
    """The ring hold-out of a scan, as a dict: the even rings are meshed (with `config` and `method`, as
    reconstruct() takes them) and the odd-ring points within `max_range` of `origin` are measured against
    the mesh: 'all' and 'by_range' (bins of `range_bin` metres) give the count, the shares 'within' 0.05
    and 0.1 m, 'mean', 'median' and 'p90' (metres), as `lidarsurf evaluate --holdout-rings --json` writes
    them (docs/evaluation.md). `rings`: one ring number per point (read_rings), or None for a scan stored
    ring after ring (rings_from_order).
    """
    return _json.loads(_ring_holdout_json(points, rings, list(origin), config, method, float(max_range),
                                          float(range_bin)))["ring_holdout"]
