"""A map fused in tiles on Dask distributed: lidarsurf.fuse_tiles, and its command line

    python3 -m lidarsurf.tiles SEQUENCE OUT_DIR --tile-size 100 --scheduler tcp://HOST:8786

Each tile is fused from the scans that reach it and meshed alone, one task per group of tiles (the
tiles of a group share one pass over the scans); together the tiles' meshes are the mesh
`lidarsurf fuse` writes for the whole map (docs/method.md, "Tiles").
"""
import argparse
import contextlib
import copy
import json
import os
import re
import sys

import numpy as np

from . import _lidarsurf as _ls

__all__ = ["fuse_tiles", "TileResult"]

_TEMPORARY = re.compile(r"^tile_-?\d+_-?\d+\.(ply|glb)\.tmp\.\d+\.\d+$")
_EXTENSIONS = {"ply": "ply", "glb": "glb", "glb-draco": "glb"}


class TileResult(tuple):
    """(paths, index): the tile meshes written, and the JSON index describing them."""
    __slots__ = ()

    def __new__(cls, paths, index):
        return super().__new__(cls, (paths, index))

    paths = property(lambda self: self[0], doc="The tile meshes (.ply or .glb), in the index's order.")
    index = property(lambda self: self[1], doc="The index file: the plan and, per tile, its key, path and counts.")


# The tasks: Python functions, which Dask sends by name (the extension's functions do not pickle).
def _reaches(sequence, frames, recording=None):
    return _ls.sequence_reaches(sequence, frames, recording)


def _group(sequence, frames, reaches, config, tiles, keys, paths, recording=None, mesh_format="auto"):
    """One task: a group of tiles (`sequence`, `frames` and `recording` are lists for several drives)."""
    counts, _ = _ls.fuse_tile_group(sequence, frames, reaches, config, tiles, [tuple(k) for k in keys], paths, recording, mesh_format)
    return counts


def _is_recording(path):
    ext = os.path.splitext(path)[1].lower()
    return ext in (".pcap", ".pcapng", ".bag", ".db3", ".mcap") or os.path.isfile(os.path.join(path, "metadata.yaml"))


@contextlib.contextmanager
def _local_client():
    """A LocalCluster of one single-threaded worker process per core, and its client."""
    import dask
    from distributed import Client, LocalCluster
    # Dask starts workers with MALLOC_TRIM_THRESHOLD_ set, which also fixes glibc's mmap threshold
    # at 128 KiB: every large buffer is then mapped and unmapped afresh, and a tile takes 2.7 times
    # as long. A 64 MiB mmap threshold restores the speed (docs/tiles.md). Kept while the cluster
    # lives: the nanny restarts a dead worker with it.
    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", {}))
    environ.setdefault("MALLOC_MMAP_THRESHOLD_", 64 << 20)
    with dask.config.set({"distributed.nanny.pre-spawn-environ": environ}):
        with LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
            with Client(cluster) as client:
                yield client


def _write_json(path, data):
    temporary = f"{path}.tmp.{os.getpid()}"
    with open(temporary, "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    os.replace(temporary, path)


def fuse_tiles(sequence, out_dir, tile_size=100.0, client=None, config=None, halo_cubes=32, first=0, frames=0, step=1,
               plan_chunk=100, retries=2, poses=None, times=None, topic=None, metadata=None, deskew=True, mesh_format="ply", group=2):
    """Fuse a sequence (KITTI layout, poses as `lidarsurf fuse` finds them) into a map cut in square
    tiles of `tile_size` metres, each square of `group` x `group` tiles a task on the dask.distributed
    `client` (a LocalCluster of this machine's cores when None; the tiles of a task share one pass over
    the scans: group 1 gives the most tasks, a larger group less CPU), and write one mesh per tile, out_dir/tile_X_Y.ply, and
    out_dir/index.json. Returns TileResult(paths, index). `mesh_format` "glb" writes binary glTF
    (tile_X_Y.glb), "glb-draco" Draco-compressed glTF; each tile's file is whole in itself.

    Together the tiles' meshes are the whole map's (`lidarsurf fuse` without tiles): each triangle in
    exactly one tile, the one whose square holds its cube. A tile reads the scans that reach it from
    the sequence directory, which every worker must see at the same path (a shared file system).
    Reading every scan once for the plan is spread over the workers too, `plan_chunk` scans a task.
    A task whose worker dies is run again (up to `retries` times); a mesh is written whole or not at
    all, and what a killed worker left half-written is removed.

    `sequence` may be a recording (pcap, ROS 1 bag, ROS 2 bag) with `poses`, the sensor's trajectory
    (TUM, or KITTI poses with their `times`; None: the bag's own /tf), `topic` and `metadata` as
    read_recording takes them: its scans within the trajectory's span, de-skewed unless `deskew` is
    False; `first`, `frames` and `step` count those scans. Each task reads the recording from its
    start (streamed) up to the scans it needs.

    `sequence` may also be a list of drives of one world frame (directories or recordings), fused
    one after the other into one map, as `lidarsurf fuse A B` fuses them; `first`, `frames` and
    `step` apply to each, and `poses` and `times`, when given, are lists with one entry per drive.
    """
    if mesh_format not in _EXTENSIONS:
        raise ValueError(f"mesh_format must be one of {', '.join(_EXTENSIONS)} (got {mesh_format!r})")
    config = config if config is not None else _ls.Config()
    tiles = _ls.TileConfig(tile_size, halo_cubes, group)
    config.validate()
    several = not isinstance(sequence, (str, os.PathLike))
    drives = [os.fspath(d) for d in sequence] if several else [os.fspath(sequence)]
    if not drives:
        raise ValueError("no drive to fuse")

    def per_drive(value):
        if value is None:
            return [None] * len(drives)
        if not several:
            return [value]
        if isinstance(value, (str, os.PathLike)) or len(value) != len(drives):
            raise ValueError("several drives: poses and times are lists with one entry per drive")
        return list(value)

    drive_poses, drive_times = per_drive(poses), per_drive(times)
    recordings = []
    for d, p, t in zip(drives, drive_poses, drive_times):
        if _is_recording(d):
            recordings.append({"poses": p, "times": t, "topic": topic, "metadata": metadata, "deskew": bool(deskew)})
        elif p is not None or t is not None or topic is not None or metadata is not None:
            raise ValueError(f"{d}: poses, times, topic and metadata go with a recording (pcap, ROS 1 or 2 bag)")
        else:
            recordings.append(None)
    drive_indices = [_ls.sequence_frames(d, first, frames, step, r) for d, r in zip(drives, recordings)]
    with contextlib.ExitStack() as stack:
        if client is None:
            client = stack.enter_context(_local_client())
            if config.threads == 0:  # one tile a core, not every core for each tile
                config = copy.copy(config)  # by its fields (lidarsurf/__init__.py)
                config.threads = 1
        chunks = [(d, r, ix[i:i + plan_chunk]) for d, r, ix in zip(drives, recordings, drive_indices) for i in range(0, len(ix), plan_chunk)]
        parts = client.gather(client.map(_reaches, [c[0] for c in chunks], [c[2] for c in chunks], [c[1] for c in chunks],
                                         retries=retries, pure=False))
        reaches = np.concatenate(parts)
        plan = _ls.TilePlan(reaches, config, tiles)
        os.makedirs(out_dir, exist_ok=True)
        shared = client.scatter(reaches, broadcast=True)
        groups = plan.groups
        keys = [key for g in groups for key in g]
        group_paths = [[os.path.join(out_dir, f"tile_{x}_{y}.{_EXTENSIONS[mesh_format]}") for x, y in g] for g in groups]
        paths = [path for p in group_paths for path in p]
        if several:
            source, indices, recording = drives, drive_indices, recordings
        else:
            source, indices, recording = drives[0], drive_indices[0], recordings[0]
        futures = [client.submit(_group, source, indices, shared, config, tiles, g, p, recording, mesh_format, retries=retries, pure=False)
                   for g, p in zip(groups, group_paths)]
        counts = [c for part in client.gather(futures) for c in part]
    for name in os.listdir(out_dir):  # what a killed worker was writing
        if _TEMPORARY.match(name):
            os.remove(os.path.join(out_dir, name))
    written = []
    entries = []
    for key, path, c in zip(keys, paths, counts):
        if c["triangles"] == 0:
            continue
        written.append(path)
        entries.append({"tile": list(key), "path": os.path.basename(path), "scans": plan.scans_of(key), **c})
    index = os.path.join(out_dir, "index.json")
    _write_json(index, {
        "sequence": [os.path.abspath(d) for d in drives] if several else os.path.abspath(drives[0]),
        "frames": sum(len(ix) for ix in drive_indices),
        "tile_size": tiles.tile_size,
        "halo_cubes": tiles.halo_cubes,
        "group": tiles.group,
        "grid_origin": plan.grid_origin,
        "ray_reach": plan.ray_reach,
        "config": repr(config),
        "mesh_format": mesh_format,
        "triangles": sum(e["triangles"] for e in entries),
        "tiles": entries,
    })
    return TileResult(written, index)


def main(argv=None):
    p = argparse.ArgumentParser(prog="python3 -m lidarsurf.tiles",
                                description="Fuse a sequence into a map cut in tiles, one Dask task per group of tiles.")
    p.add_argument("sequence", nargs="+", help="sequence directory (KITTI layout: velodyne/NNNNNN.bin, poses.txt), or a recording; "
                   "several: drives of one world frame fused into one map")
    p.add_argument("out_dir", help="where the tiles' meshes (tile_X_Y.ply or .glb) and index.json go")
    p.add_argument("--tile-size", type=float, default=100.0, help="side of the square tiles, metres (default 100)")
    p.add_argument("--tile-halo-cubes", type=int, default=32, help="cubes a tile's surface search reaches beyond it")
    p.add_argument("--tile-group", type=int, default=2, help="tiles a side of the squares fused in one task (default 2)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://HOST:8786 (default: a local cluster)")
    p.add_argument("--first", type=int, default=0)
    p.add_argument("--frames", type=int, default=0, help="frames to fuse (0: to the last)")
    p.add_argument("--step", type=int, default=1)
    p.add_argument("--poses", help="a recording's trajectory: TUM, or KITTI poses with --times (default: the bag's /tf)")
    p.add_argument("--times", help="the times of KITTI --poses")
    p.add_argument("--topic", help="a bag's topic of the scans")
    p.add_argument("--metadata", help="an Ouster metadata JSON or a Velodyne calibration YAML")
    p.add_argument("--deskew", type=int, default=1, help="0: a recording's scans as recorded, not de-skewed")
    p.add_argument("--mesh-format", default="ply", choices=sorted(_EXTENSIONS), help="the tiles' files: ply, glb (binary glTF) or glb-draco")
    a = p.parse_args(argv)
    client = None
    if a.scheduler:
        from distributed import Client
        client = Client(a.scheduler)
    try:
        sequence = a.sequence[0] if len(a.sequence) == 1 else a.sequence
        result = fuse_tiles(sequence, a.out_dir, a.tile_size, client=client, halo_cubes=a.tile_halo_cubes, first=a.first,
                            frames=a.frames, step=a.step, poses=a.poses, times=a.times, topic=a.topic, metadata=a.metadata,
                            deskew=bool(a.deskew), mesh_format=a.mesh_format, group=a.tile_group)
    except (ValueError, OSError, MemoryError) as e:
        print(f"lidarsurf.tiles: {e}", file=sys.stderr)
        return 2
    finally:
        if client is not None:
            client.close()
    with open(result.index) as f:
        total = json.load(f)["triangles"]
    print(f"{len(result.paths)} tiles, {total} triangles -> {result.index}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
