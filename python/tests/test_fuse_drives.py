"""`lidarsurf fuse A B`: two drives of one street, poses in one world frame, fused into one map. The
oracle is the simulator's: the cars that parked during drive A (A's last objects/ mesh) are gone in
drive B, so the map of A then B carves them, while B then A keeps them (they stand at the end)."""
import subprocess

import numpy as np
import pytest

import lidarsurf


def car_boxes(objects):
    """The boxes of the parked cars' pieces (connected components of the objects' mesh)."""
    v, t = np.asarray(objects.vertices), np.asarray(objects.triangles)
    parent = np.arange(len(v))

    def root(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b, c in t:
        parent[root(a)] = root(b)
        parent[root(b)] = root(c)
    roots = np.array([root(i) for i in range(len(v))])
    return [(v[roots == r].min(0), v[roots == r].max(0)) for r in np.unique(roots)]


def triangles_on_cars(mesh, boxes):
    """Mesh triangles whose centroid lies in a car piece's box (0.1 m around it), above 0.3 m: the
    street and the curb below them are no car."""
    c = np.asarray(mesh.vertices)[np.asarray(mesh.triangles)].mean(axis=1)
    return sum(int(((c > lo + [-0.1, -0.1, 0.3]) & (c < hi + 0.1)).all(axis=1).sum()) for lo, hi in boxes)


@pytest.fixture(scope="module")
def drives(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("drives")
    common = ["simulate", "--scene", "town", "--frames", "16", "--length", "120", "--gt-beams", "0", "--moving-cars", "0", "-q"]
    subprocess.run([cli, *common, "--parking-cars", "3", "-o", str(d / "a")], check=True)
    subprocess.run([cli, *common, "-o", str(d / "b")], check=True)
    return cli, d


def fuse(cli, d, name, *args):
    out = d / f"{name}.ply"
    subprocess.run([cli, "fuse", *[str(d / a) for a in args if not a.startswith("-")], "-o", str(out), "-q",
                    *[a for a in args if a.startswith("-")]], check=True)
    return lidarsurf.read_mesh(str(out))


def test_a_car_parked_in_one_drive_and_gone_in_the_next_is_carved(drives):
    cli, d = drives
    assert (d / "a" / "poses.txt").read_text() == (d / "b" / "poses.txt").read_text(), "one street, one world frame"
    boxes = car_boxes(lidarsurf.read_mesh(str(d / "a" / "objects" / "000015.ply")))
    alone = triangles_on_cars(fuse(cli, d, "a", "a"), boxes)
    assert alone > 500, "drive A alone keeps the cars it saw parked"
    assert triangles_on_cars(fuse(cli, d, "ab", "a", "b"), boxes) < alone / 50, "B saw the street empty: carved"
    assert triangles_on_cars(fuse(cli, d, "ba", "b", "a"), boxes) > alone / 2, "B then A: the cars stand at the end"


def test_several_drives_in_tiles_are_the_same_map(drives, triangle_rows):
    cli, d = drives
    whole = fuse(cli, d, "ab_whole", "a", "b")
    tiled = fuse(cli, d, "ab_tiles", "a", "b", "--tile-size=30")
    assert len(tiled.vertices) == len(whole.vertices), "the seams' vertices written once"
    assert triangle_rows(tiled) == triangle_rows(whole)
    bad = subprocess.run([cli, "fuse", str(d / "a"), str(d / "b"), "-o", str(d / "x.ply"), "--poses", str(d / "a" / "poses.txt")],
                         capture_output=True, text=True)
    assert bad.returncode == 2 and "one drive" in bad.stderr


def test_several_drives_on_dask_are_the_same_map(drives, triangle_rows, tmp_path):
    pytest.importorskip("distributed")
    cli, d = drives
    whole = fuse(cli, d, "ab_whole", "a", "b")
    result = lidarsurf.fuse_tiles([str(d / "a"), str(d / "b")], str(tmp_path / "tiles"), tile_size=30)  # a local cluster
    tiles = sorted(row for p in result.paths for row in triangle_rows(lidarsurf.read_mesh(p)))
    assert tiles == triangle_rows(whole), "drive A then drive B, each triangle of their one map in one tile"
    with pytest.raises(ValueError, match="one entry per drive"):
        lidarsurf.fuse_tiles([str(d / "a"), str(d / "b")], str(tmp_path / "no"), poses=str(d / "a" / "poses.txt"))
