"""lidarsurf.fuse_tiles on a dask.distributed LocalCluster of 2 workers, and on a scheduler and 2
workers started by their commands: the tiles' meshes together are the mesh `lidarsurf fuse` writes
for the whole map (the oracle), and a worker killed while it meshes tiles changes nothing of the
result."""
import json
import os
import pickle
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import lidarsurf

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def drive(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("tiles")
    seq = d / "drive"
    subprocess.run([cli, "simulate", "--scene", "town", "--frames", "8", "--length", "120", "--gt-beams", "0", "-o", str(seq), "-q"],
                   check=True)
    whole = d / "whole.ply"
    subprocess.run([cli, "fuse", str(seq), "-o", str(whole), "-q"], check=True)
    return seq, lidarsurf.read_mesh(str(whole))


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def _kill_a_busy_worker(client, killed, deadline=60):
    """SIGKILL the process of a worker while it runs a group of tiles (a task of fuse_tiles)."""
    end = time.time() + deadline
    while time.time() < end and not killed:
        for worker, keys in client.processing().items():
            if any(str(k).startswith("_group") for k in keys):
                pid = client.run(os.getpid, workers=[worker])[worker]
                os.kill(pid, signal.SIGKILL)
                killed.append(worker)
                return
        time.sleep(0.02)


@pytest.fixture
def real_cluster(tmp_path):
    """A scheduler and 2 single-threaded workers started by their commands on 127.0.0.1, as a batch
    job (Slurm) starts them; yields the scheduler's address and a client of it."""
    info = tmp_path / "scheduler.json"
    # The workers import lidarsurf as this test does, and keep glibc's mmap threshold high (docs/tiles.md).
    env = dict(os.environ, MALLOC_MMAP_THRESHOLD_=str(64 << 20))
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env}
    procs = [subprocess.Popen(["dask", "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--scheduler-file", str(info)], **quiet)]
    try:
        deadline = time.time() + 60
        while not info.exists() and time.time() < deadline:
            time.sleep(0.1)
        assert info.exists(), "the scheduler wrote no scheduler file"
        time.sleep(0.2)  # written whole
        address = json.loads(info.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        for i in range(2):
            procs.append(subprocess.Popen(["dask", "worker", address, "--host", "127.0.0.1", "--nthreads", "1", "--nworkers", "1",
                                           "--no-dashboard", "--local-directory", str(tmp_path / f"worker{i}")], **quiet))
        c = distributed.Client(address)
        c.wait_for_workers(2, timeout=60)
        yield address, c
        c.close()
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in reversed(procs):
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def test_a_cluster_started_by_its_commands_meshes_the_whole_map(drive, real_cluster, tmp_path, triangle_rows):
    seq, whole = drive
    address, client = real_cluster
    out = tmp_path / "tiles"
    killed = []
    killer = threading.Thread(target=_kill_a_busy_worker, args=(client, killed))
    killer.start()
    # The command line, as a batch job runs it; one task a tile, so that tasks remain when one is killed.
    run = subprocess.run([sys.executable, "-m", "lidarsurf.tiles", str(seq), str(out), "--tile-size", "30", "--tile-group", "1",
                          "--scheduler", address], capture_output=True, text=True, timeout=600)
    killer.join()
    assert run.returncode == 0, run.stderr
    assert killed, "a worker was killed while it meshed a tile"
    with open(out / "index.json") as f:
        index = json.load(f)
    paths = [str(out / e["path"]) for e in index["tiles"]]
    assert len(paths) >= 4
    tiles = sorted(row for p in paths for row in triangle_rows(lidarsurf.read_mesh(p)))
    assert tiles == triangle_rows(whole), "the killed worker's task was run again: each triangle of the whole map in one tile"
    # Nothing half-written stays: the tiles' meshes and the index only.
    assert sorted(os.listdir(out)) == sorted([e["path"] for e in index["tiles"]] + ["index.json"])


def test_the_tiles_are_the_whole_map(drive, client, tmp_path, triangle_rows):
    seq, whole = drive
    # One task a tile, and one a group of 2 x 2 tiles sharing a pass over the scans (the default).
    for group in (1, 2):
        alone = lidarsurf.fuse_tiles(str(seq), str(tmp_path / f"group{group}"), tile_size=30, client=client, group=group)
        assert len(alone.paths) >= 4, "the drive crosses several tiles"
        tiles = sorted(row for p in alone.paths for row in triangle_rows(lidarsurf.read_mesh(p)))
        assert tiles == triangle_rows(whole), f"group {group}: each triangle of the whole map in exactly one tile"
    result = lidarsurf.fuse_tiles(str(seq), str(tmp_path / "tiles"), tile_size=30, client=client)

    with open(result.index) as f:
        index = json.load(f)
    assert index["triangles"] == len(whole.triangles) and len(index["tiles"]) == len(result.paths)
    assert sorted(os.listdir(tmp_path / "tiles")) == sorted([os.path.basename(p) for p in result.paths] + ["index.json"])


def _glb_triangles(path):
    """Triangles of a binary glTF, read from its JSON chunk as the glTF 2.0 specification lays it out."""
    with open(path, "rb") as f:
        data = f.read()
    magic, version, length = np.frombuffer(data[:12], "<u4")
    assert (magic, version, length) == (0x46546C67, 2, len(data))
    size, kind = np.frombuffer(data[12:20], "<u4")
    assert kind == 0x4E4F534A
    doc = json.loads(data[20:20 + size])
    return sum(doc["accessors"][p["indices"]]["count"] // 3 for m in doc["meshes"] for p in m["primitives"])


def test_tiles_in_gltf_hold_the_whole_maps_triangles(drive, client, tmp_path):
    seq, whole = drive
    for mesh_format in ("glb", "glb-draco"):
        result = lidarsurf.fuse_tiles(str(seq), str(tmp_path / mesh_format), tile_size=30, client=client, mesh_format=mesh_format)
        assert len(result.paths) >= 4 and all(p.endswith(".glb") for p in result.paths)
        assert sum(_glb_triangles(p) for p in result.paths) == len(whole.triangles), mesh_format
        with open(result.index) as f:
            assert json.load(f)["mesh_format"] == mesh_format
    with pytest.raises(ValueError, match="mesh_format"):
        lidarsurf.fuse_tiles(str(seq), str(tmp_path / "no"), client=client, mesh_format="stl")


def test_a_recordings_tiles_are_the_whole_map_of_its_drive(drive, cli, client, tmp_path, triangle_rows):
    # The drive written as a ROS 1 bag by ROS's own writer (python3-rosbag), fused in tiles from the
    # bag with its KITTI poses and times: the KITTI layout's whole map, triangle for triangle. The
    # bag's clouds do not say which rays returned nothing (the layout's sensor.json does): the whole
    # map it matches is the one fused without them.
    pytest.importorskip("rosbag")
    seq, _ = drive
    subprocess.run([cli, "fuse", str(seq), "-o", str(tmp_path / "whole.ply"), "--carve-empty-range", "0", "-q"], check=True)
    whole = lidarsurf.read_mesh(str(tmp_path / "whole.ply"))
    writer = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "io", "kitti_to_ros1_bag.py")
    subprocess.run(["/usr/bin/python3", writer, str(seq), str(tmp_path / "drive.bag"), str(tmp_path / "times.txt")], check=True)
    result = lidarsurf.fuse_tiles(str(tmp_path / "drive.bag"), str(tmp_path / "tiles"), tile_size=30, client=client,
                                  poses=str(seq / "poses.txt"), times=str(tmp_path / "times.txt"))
    assert len(result.paths) >= 4
    assert sorted(row for p in result.paths for row in triangle_rows(lidarsurf.read_mesh(p))) == triangle_rows(whole)
    with pytest.raises(ValueError, match="go with a recording"):
        lidarsurf.fuse_tiles(str(seq), str(tmp_path / "no"), client=client, poses=str(seq / "poses.txt"))


def test_a_worker_killed_mid_tile_changes_nothing(drive, client, tmp_path):
    seq, whole = drive
    calm = lidarsurf.fuse_tiles(str(seq), str(tmp_path / "calm"), tile_size=30, client=client)
    before = set(client.scheduler_info()["workers"])
    killed = []
    killer = threading.Thread(target=_kill_a_busy_worker, args=(client, killed))
    killer.start()
    result = lidarsurf.fuse_tiles(str(seq), str(tmp_path / "killed"), tile_size=30, client=client)
    killer.join()
    assert killed, "a worker was killed while it meshed a tile"
    client.wait_for_workers(2, timeout=60)
    assert set(client.scheduler_info()["workers"]) != before, "the nanny started a new worker"
    assert [os.path.basename(p) for p in result.paths] == [os.path.basename(p) for p in calm.paths]
    for a, b in zip(result.paths, calm.paths):
        with open(a, "rb") as fa, open(b, "rb") as fb:
            assert fa.read() == fb.read(), f"{a}: the same mesh as without the kill"
    # Nothing half-written stays: the tiles' meshes and the index only.
    assert sorted(os.listdir(tmp_path / "killed")) == sorted([os.path.basename(p) for p in result.paths] + ["index.json"])


def test_configs_travel_and_bad_plans_are_refused(tmp_path):
    c = lidarsurf.Config()
    c.carve_stale_scans = 9
    c.mode = "an"
    back = pickle.loads(pickle.dumps(c))
    assert repr(back) == repr(c)
    t = pickle.loads(pickle.dumps(lidarsurf.TileConfig(tile_size=50, halo_cubes=16, group=3)))
    assert (t.tile_size, t.halo_cubes, t.group) == (50, 16, 3)
    with pytest.raises(ValueError, match="group"):
        lidarsurf.TileConfig(group=0)
    with pytest.raises(ValueError, match="tile_size"):
        lidarsurf.TileConfig(tile_size=0.1)
    with pytest.raises(ValueError, match="halo_cubes"):
        lidarsurf.TileConfig(halo_cubes=1)
    reaches = np.zeros((1, 15))
    with pytest.raises(ValueError, match="no finite point"):
        lidarsurf.TilePlan(reaches, lidarsurf.Config(), lidarsurf.TileConfig())
    with pytest.raises(ValueError, match="paper"):
        lidarsurf.TilePlan(reaches, lidarsurf.Config.paper(), lidarsurf.TileConfig())
    with pytest.raises(OSError):
        lidarsurf.fuse_tiles(str(tmp_path / "nowhere"), str(tmp_path / "out"), client=object())
