"""`lidarsurf fuse` meshes its map square by square and writes each square as it comes: the file holds
the mesh of the same scans fused and meshed in memory (one Reconstructor, one extract_mesh), the same
triangles, each vertex on a seam written once."""
import json
import os
import subprocess
import types

import numpy as np

import lidarsurf


def test_the_written_map_is_the_map_meshed_in_memory(cli, tmp_path, triangle_rows):
    seq = tmp_path / "drive"
    # 200 m of street: the map spans several 64 m squares.
    subprocess.run([cli, "simulate", "--scene", "town", "--frames", "8", "--length", "200", "--gt-beams", "0", "-o", str(seq), "-q"],
                   check=True)
    subprocess.run([cli, "fuse", str(seq), "-o", str(tmp_path / "map.ply"), "-q"], check=True)
    written = lidarsurf.read_mesh(str(tmp_path / "map.ply"))

    rec = lidarsurf.Reconstructor()
    poses = lidarsurf.read_poses(str(seq / "poses.txt"))
    sensor = json.loads((seq / "sensor.json").read_text())  # fuse takes the rays that returned nothing from it
    for i, name in enumerate(sorted(os.listdir(seq / "velodyne"))):
        points = lidarsurf.read_points(str(seq / "velodyne" / name))
        rays = lidarsurf.empty_rays(points, sensor["elevations_deg"], sensor["azimuth_step_deg"])
        assert 0 < len(rays) < 0.6 * len(points)  # the sky, beyond the range; 2 % dropouts
        rec.integrate_from(points @ poses[i][:3, :3].T + poses[i][:3, 3], poses[i][:3, 3], no_return=rays @ poses[i][:3, :3].T)
    in_memory = rec.extract_mesh()

    assert len(written.triangles) == len(in_memory.triangles) > 10000
    # The file's coordinates are float32 (a map within 10 km of its origin).
    as_written = types.SimpleNamespace(vertices=np.asarray(in_memory.vertices).astype(np.float32), triangles=in_memory.triangles)
    assert triangle_rows(written) == triangle_rows(as_written), "the same triangles, none lost, none twice"
    assert len(written.vertices) == len(in_memory.vertices), "each vertex on a seam written once"
