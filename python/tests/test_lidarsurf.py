"""Tests of the Python bindings: same mesh as the CLI, numpy views, errors, Config."""
import gc
import os
import subprocess

import numpy as np
import pytest

import lidarsurf


@pytest.fixture(scope="module")
def scan():
    return lidarsurf.simulate(seed=1)


def test_config_defaults_come_from_cpp():
    c = lidarsurf.Config()
    assert (c.voxel_size, c.tau, c.n_min, c.k_max, c.mode) == (0.2, 0.2, 10, 5, "an+gc")
    c.mode = "CN"
    assert c.mode == "cn"
    c.validate()


def test_paper_config_turns_the_guards_off(scan):
    p = lidarsurf.Config.paper("an")
    assert p.mode == "an"
    assert (p.min_planarity, p.max_thickness, p.truncation_voxels) == (0.0, 0.0, 0.0)
    assert p.slab_from_level == 0
    assert not p.seeded_surface and not p.snap_to_plane
    assert (p.voxel_size, p.tau, p.n_min, p.k_max) == (0.2, 0.2, 10, 5)
    d = lidarsurf.Config()
    assert d.max_thickness > 0 and d.snap_to_plane and d.truncation_voxels > 0
    assert d.slab_from_level > 0 and d.slab_radial_extension > 0 and "slab_radial_extension=" in repr(d)
    assert d.bridge_reach > 0 and "bridge_reach=" in repr(d) and lidarsurf.Config.paper().bridge_reach == 0
    d.make_paper_literal()
    assert d.max_thickness == 0 and not d.snap_to_plane and d.slab_from_level == 0
    assert "max_thickness=0" in repr(d) and "slab_from_level=0" in repr(d)
    # Both configurations mesh a part of the scan.
    part = scan[:20000]
    assert len(lidarsurf.reconstruct(part, config=p).triangles) > 0
    assert len(lidarsurf.reconstruct(part).triangles) > 0


@pytest.mark.parametrize("field,value,message", [
    ("voxel_size", -1.0, "voxel size"),
    ("voxel_size", float("nan"), "voxel size"),
    ("tau", 0.0, "tau"),
    ("k_max", 0, "k_max"),
    ("n_min", 0, "n_min"),
    ("max_memory_mb", 0.0, "max memory"),
    ("max_thickness", -1.0, "max thickness"),
    ("min_component_triangles", -1, "min component"),
    ("slab_from_level", 1, "slab fallback"),
    ("slab_radial_extension", -1, "slab radial extension"),
    ("bridge_reach", 65, "bridge reach"),
])
def test_bad_config_raises_value_error(field, value, message, scan):
    c = lidarsurf.Config()
    setattr(c, field, value)
    with pytest.raises(ValueError, match=message):
        c.validate()
    with pytest.raises(ValueError, match=message):
        lidarsurf.reconstruct(scan[:1000], config=c)


def test_bad_mode_raises_value_error():
    c = lidarsurf.Config()
    with pytest.raises(ValueError, match="unknown mode"):
        c.mode = "fast"
    with pytest.raises(ValueError, match="unknown mode"):
        lidarsurf.reconstruct(np.zeros((10, 3)), method="poisson")


def test_same_mesh_as_the_cli(scan, tmp_path):
    cli = os.environ.get("LIDARSURF_CLI")
    if not cli:
        pytest.skip("LIDARSURF_CLI not set (run through ctest)")
    mesh_path = tmp_path / "mesh.ply"
    # The same points for both: text with 17 significant digits round-trips float64 exactly.
    np.savetxt(tmp_path / "scan.xyz", scan, fmt="%.17g")
    subprocess.run([cli, "reconstruct", str(tmp_path / "scan.xyz"), "-o", str(mesh_path), "--mode", "an", "--kmax", "4"],
                   check=True, capture_output=True)
    c = lidarsurf.Config()
    c.mode, c.k_max = "an", 4
    ours = lidarsurf.reconstruct(scan, origin=(0, 0, 0), config=c)
    theirs = lidarsurf.read_mesh(str(mesh_path))
    assert ours.triangles.shape[0] > 1000
    np.testing.assert_array_equal(ours.triangles, theirs.triangles)
    np.testing.assert_allclose(ours.vertices, theirs.vertices, rtol=0, atol=1e-6)


def test_float64_c_contiguous_input_is_not_copied(scan):
    assert lidarsurf.points_view(scan) is scan or np.shares_memory(lidarsurf.points_view(scan), scan)
    f32 = scan.astype(np.float32)
    assert not np.shares_memory(lidarsurf.points_view(f32), f32)  # converted once
    strided = np.asfortranarray(scan)
    assert not np.shares_memory(lidarsurf.points_view(strided), strided)


def test_float32_gives_a_mesh_close_to_float64(scan):
    a = lidarsurf.reconstruct(scan)
    b = lidarsurf.reconstruct(scan.astype(np.float32))
    assert abs(a.triangles.shape[0] - b.triangles.shape[0]) < 0.02 * a.triangles.shape[0]


@pytest.mark.parametrize("points,message", [
    (np.zeros((10, 2)), r"shape \(N, 3\)"),
    (np.zeros((10,)), r"shape \(N, 3\)"),
    (np.zeros((10, 3), dtype=np.int32), "float32 or float64"),
    (np.array([[0.0, 0.0, np.nan]] * 5), "non-finite"),
    (np.array([[np.inf, 0.0, 0.0]] * 5), "non-finite"),
    ("not points", "array"),
])
def test_bad_points_raise_value_error(points, message):
    with pytest.raises(ValueError, match=message):
        lidarsurf.reconstruct(points)


def test_memory_budget_raises_memory_error(scan):
    c = lidarsurf.Config()
    assert c.max_memory_mb == 4096
    c.max_memory_mb = 2
    with pytest.raises(MemoryError, match="above the memory budget of 2 MiB"):
        lidarsurf.reconstruct(scan, config=c)


@pytest.mark.parametrize("dtype", [np.longdouble, np.float16, np.complex128, np.int32, np.uint8, object])
def test_dtypes_not_read_are_refused(scan, dtype):
    with pytest.raises(ValueError, match="float32 or float64"):
        lidarsurf.reconstruct(scan[:100].astype(dtype))
    with pytest.raises(ValueError, match="float32 or float64"):
        lidarsurf.Reconstructor().integrate(scan[:100].astype(dtype))


def test_a_refused_batch_leaves_the_reconstructor_usable(scan):
    # The oracle: the same good batches, without the refused one in between.
    oracle = lidarsurf.Reconstructor()
    oracle.integrate(scan[0::2])
    oracle.integrate(scan[1::2])
    expected = oracle.extract_mesh()
    c = lidarsurf.Config()
    c.max_memory_mb = 64
    rec = lidarsurf.Reconstructor(c)
    rec.integrate(scan[0::2])
    scattered = np.random.default_rng(3).uniform(-500, 500, (300_000, 3))
    with pytest.raises(MemoryError, match="nothing of this chunk was integrated"):
        rec.integrate(scattered)
    bad = scan[1::2].copy()
    bad[7] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        rec.integrate(bad)
    rec.integrate(scan[1::2])
    mesh = rec.extract_mesh()
    assert np.array_equal(mesh.triangles, expected.triangles)
    assert np.array_equal(mesh.vertices, expected.vertices)


def test_one_reconstructor_shared_by_threads(scan):
    # Calls from several threads run one at a time: every point counted, the mesh of all of them.
    import threading

    rec = lidarsurf.Reconstructor()
    parts = [scan[i::4] for i in range(4)]
    errors = []

    def work(part):
        try:
            for _ in range(3):
                rec.integrate(part)
                rec.extract_mesh()
                rec.summary
                repr(rec)
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=work, args=(p,)) for p in parts]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert rec.summary["points_read"] == 3 * len(scan)
    assert len(rec.extract_mesh().triangles) > 0


def test_mesh_arrays_are_read_only(scan):
    mesh = lidarsurf.reconstruct(scan)
    for name in ("vertices", "triangles", "normals", "levels", "confidence"):
        a = getattr(mesh, name)
        assert not a.flags.writeable, name
        with pytest.raises(ValueError, match="read-only"):
            a[0] = 0
    copy = np.array(mesh.vertices)
    copy[0] = 0  # a copy is the user's


def test_method_names_are_the_clis(scan):
    default = lidarsurf.reconstruct(scan)
    assert np.array_equal(lidarsurf.reconstruct(scan, method="default").triangles, default.triangles)
    paper = lidarsurf.reconstruct(scan, method="paper")  # the paper as written, as --method paper
    assert np.array_equal(paper.triangles, lidarsurf.reconstruct(scan, config=lidarsurf.Config.paper()).triangles)
    assert len(paper.triangles) != len(default.triangles)


def test_empty_cloud_raises_value_error():
    with pytest.raises(ValueError, match="no points"):
        lidarsurf.reconstruct(np.zeros((0, 3)))


def test_mesh_arrays_are_views_kept_alive(scan):
    mesh = lidarsurf.reconstruct(scan)
    v = mesh.vertices
    assert v.shape[1] == 3 and v.dtype == np.float64
    del mesh
    assert np.isfinite(v).all()  # the array keeps the mesh alive
    mesh = lidarsurf.reconstruct(scan)
    assert mesh.levels.shape == (mesh.vertices.shape[0],)
    assert mesh.confidence.dtype == np.float32
    assert mesh.triangles.max() < mesh.vertices.shape[0]


def test_save_read_points_and_os_errors(scan, tmp_path):
    mesh = lidarsurf.reconstruct(scan)
    mesh.save(str(tmp_path / "m.obj"))
    back = lidarsurf.read_mesh(str(tmp_path / "m.obj"))
    assert back.triangles.shape == mesh.triangles.shape
    mesh.save(str(tmp_path / "m.glb"))  # binary glTF by its extension (tests/io/test_glb_writer.cpp reads it)
    assert (tmp_path / "m.glb").read_bytes()[:4] == b"glTF"
    with pytest.raises(ValueError, match="glb-draco"):
        mesh.save(str(tmp_path / "m.glb"), format="gltf")
    with pytest.raises(OSError, match="cannot"):
        mesh.save(str(tmp_path / "missing_dir" / "m.ply"))
    with pytest.raises(OSError, match="cannot open"):
        lidarsurf.read_points(str(tmp_path / "nothing.bin"))
    (tmp_path / "bad.bin").write_bytes(b"abc")
    with pytest.raises(ValueError, match="multiple"):
        lidarsurf.read_points(str(tmp_path / "bad.bin"))
    scan.astype(np.float32).tofile(tmp_path / "raw.bin")  # 3 floats per point
    pts = lidarsurf.read_points(str(tmp_path / "raw.bin"), bin_fields=3)
    np.testing.assert_allclose(pts, scan.astype(np.float32), rtol=0, atol=0)


def test_evaluate_returns_the_metrics(scan):
    gt = lidarsurf.simulate(ground_truth=True)
    ours = lidarsurf.reconstruct(scan)
    imls = lidarsurf.reconstruct(scan, method="imls")
    a, b = lidarsurf.evaluate(ours, gt), lidarsurf.evaluate(imls, gt)
    assert a["paper"]["p_to_gt"]["mean"] < 0.6 * b["paper"]["p_to_gt"]["mean"]
    assert 0 <= a["surface"]["fscore"] <= 1
    # Known answer: a square at z = 0 against points 0.1 m above its vertices.
    xs, ys = np.meshgrid(np.arange(11) * 0.1, np.arange(11) * 0.1)
    verts = np.c_[xs.ravel(), ys.ravel(), np.zeros(121)]
    idx = lambda i, j: j * 11 + i
    tris = [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)] for j in range(10) for i in range(10)]
    tris += [[idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)] for j in range(10) for i in range(10)]
    square = lidarsurf.Mesh(verts, np.array(tris))
    m = lidarsurf.evaluate(square, verts + [0, 0, 0.1])
    assert m["paper"]["ae_sym"] == pytest.approx(0.1, abs=1e-9)
    with pytest.raises(ValueError, match="refers to vertex"):
        lidarsurf.Mesh(verts, np.array([[0, 1, 500]]))
    # Indices are integers: a float array is refused, not truncated (0.9 would be vertex 0).
    with pytest.raises(ValueError, match="integer vertex indices"):
        lidarsurf.Mesh(verts, np.array(tris, dtype=np.float64) + 0.9)
    assert len(lidarsurf.Mesh(verts, np.array(tris, dtype=np.uint32)).triangles) == len(tris)
    assert len(lidarsurf.Mesh(verts, np.zeros((0, 3))).triangles) == 0


def test_ring_holdout_on_a_scan_stored_ring_after_ring(scan, tmp_path):
    # The simulator writes column after column; each point's beam follows from its elevation (the
    # hdl64 preset: 64 beams evenly from +2 to -24.8 degrees), so the scan can be stored ring after
    # ring, as KITTI stores it, with the rings known.
    beams = np.linspace(2.0, -24.8, 64)
    elevation = np.degrees(np.arctan2(scan[:, 2], np.hypot(scan[:, 0], scan[:, 1])))
    beam = np.abs(elevation[:, None] - beams[None, :]).argmin(axis=1)
    azimuth = np.arctan2(scan[:, 1], scan[:, 0]) % (2 * np.pi)
    order = np.lexsort((azimuth, beam))
    ordered, beam = scan[order], beam[order]
    rings = lidarsurf.rings_from_order(ordered)
    assert rings.dtype == np.uint16
    np.testing.assert_array_equal(rings, beam)  # every beam hits the demo world: ring = beam
    with pytest.raises(ValueError, match="ring after ring"):
        lidarsurf.rings_from_order(scan)
    by_order = lidarsurf.ring_holdout(ordered)
    given = lidarsurf.ring_holdout(ordered, rings=beam)
    assert by_order == given
    assert by_order["rings"] == 64 and by_order["reconstructed"] == int((beam % 2 == 0).sum())
    held = ordered[beam % 2 == 1]
    assert by_order["all"]["count"] == int((np.linalg.norm(held, axis=1) <= 30).sum())
    assert [b["hi"] for b in by_order["by_range"]] == [10, 20, 30]
    assert 0.5 < by_order["all"]["within"][0] <= by_order["all"]["within"][1] <= 1
    # The rings as nuScenes stores them: a fifth value per point.
    records = np.c_[ordered, np.zeros(len(ordered)), beam].astype(np.float32)
    records.tofile(tmp_path / "rings.bin")
    np.testing.assert_array_equal(lidarsurf.read_rings(str(tmp_path / "rings.bin")), beam)
    with pytest.raises(ValueError, match="entries"):
        lidarsurf.ring_holdout(ordered, rings=beam[:-1])
    with pytest.raises(ValueError, match="whole numbers"):
        lidarsurf.ring_holdout(ordered, rings=beam + 0.5)


def test_reconstructor_meshes_incrementally_with_the_mesh_of_one_extraction(scan):
    # A revolution in two halves (by azimuth), a mesh after each: the second mesh is the mesh of
    # the whole scan, and its extraction took vertices from the first.
    azimuth = np.arctan2(scan[:, 1], scan[:, 0])
    first, second = scan[azimuth < 0], scan[azimuth >= 0]
    rec = lidarsurf.Reconstructor(origin=(0, 0, 0))
    rec.integrate(first)
    half = rec.extract_mesh()
    assert len(half.triangles) > 0 and rec.summary["vertices_reused"] == 0
    rec.integrate(second)
    mesh = rec.extract_mesh()
    s = rec.summary
    assert s["points_read"] == len(scan) and s["vertices_reused"] > 0 and s["vertices_evaluated"] > 0
    phases = s["seconds_tsdf_phases"]
    assert set(phases) == {"setup", "seed_wave", "later_waves", "serial", "field"}
    assert min(phases.values()) >= 0 and sum(phases.values()) <= s["seconds_tsdf"]
    whole = lidarsurf.reconstruct(np.concatenate([first, second]))
    np.testing.assert_array_equal(mesh.vertices, whole.vertices)
    np.testing.assert_array_equal(mesh.triangles, whole.triangles)
    assert "Reconstructor(" in repr(rec)
    with pytest.raises(ValueError, match="no points"):
        lidarsurf.Reconstructor().extract_mesh()
    with pytest.raises(ValueError):
        lidarsurf.Reconstructor(config=lidarsurf.Config.paper("an"), origin=(0, 0))


def test_reconstructor_fuses_scans_seen_from_several_positions(scan):
    # The scan, then the same scan moved 200 m along x and integrated with its moved viewpoint
    # (beyond the first one's reach): the first copy's part of the fused mesh is the first mesh,
    # its vertices were all reused, and the second copy is about as large.
    shift = np.array([200.0, 0.0, 0.0])
    rec = lidarsurf.Reconstructor()
    rec.integrate_from(scan, (0, 0, 0))
    one = rec.extract_mesh()
    evaluated_first = rec.summary["vertices_evaluated"]
    rec.integrate_from(scan + shift, shift)
    both = rec.extract_mesh()
    assert rec.summary["vertices_reused"] >= evaluated_first
    near = both.vertices[both.vertices[:, 0] < 100.0]
    np.testing.assert_array_equal(np.unique(near, axis=0), np.unique(one.vertices, axis=0))
    assert abs(len(both.vertices) - 2 * len(one.vertices)) < 0.02 * len(one.vertices)
    with pytest.raises(ValueError, match="viewpoint"):
        rec.integrate_from(scan, (0, 0))


def test_a_batch_refused_for_its_span_leaves_no_lattice_origin(scan):
    # A first point 1e7 m away: the batch spans too far and is refused; the next batch is taken as
    # if it came first (the same mesh as a reconstructor that never saw the refused one).
    far = scan.copy()
    far[0] = (1e7, 0, 0)
    rec = lidarsurf.Reconstructor()
    with pytest.raises(ValueError, match="voxels"):
        rec.integrate(far)
    rec.integrate(scan)
    expected = lidarsurf.Reconstructor()
    expected.integrate(scan)
    assert np.array_equal(rec.extract_mesh().vertices, expected.extract_mesh().vertices)
    assert rec.summary["points_read"] == len(scan)


def test_live_mesh_deltas_applied_in_order_give_the_live_mesh(scan):
    # A drive of three copies of the scan seen from three places; the client keeps {key: Mesh}.
    rec = lidarsurf.Reconstructor()
    client = {}
    for x in (0.0, 6.0, 12.0):
        shift = np.array([x, 0.0, 0.0])
        rec.integrate_from(scan + shift, shift)
        delta = rec.update_mesh(budget_ms=20)
        assert isinstance(delta, lidarsurf.MeshDelta) and delta.seconds >= 0
        for key in delta.removed:
            del client[key]
        for key, mesh in delta.changed:
            assert isinstance(key, tuple) and len(key) == 3 and len(mesh.triangles) > 0
            client[key] = mesh
    rest = rec.update_mesh()  # no budget: everything due
    assert rest.pending == 0
    removed, changed = rest.removed, rest.changed
    del rest  # the delta's meshes are views that outlive the delta object
    gc.collect()
    for key in removed:
        del client[key]
    for key, mesh in changed:
        client[key] = mesh
    live = rec.live_mesh()
    assert sum(len(m.triangles) for m in client.values()) == len(live.triangles)
    ours = np.sort(np.concatenate([m.vertices[m.triangles].reshape(-1, 9) for m in client.values()]), axis=0)
    theirs = np.sort(live.vertices[live.triangles].reshape(-1, 9), axis=0)
    np.testing.assert_array_equal(ours, theirs)
    # The live mesh lies on the exact mesh (its vertices are the exact mesh's, block by block).
    exact = rec.extract_mesh()
    assert len(live.triangles) > 0.9 * len(exact.triangles)
    c = lidarsurf.Config()
    c.live_growth = 0.5
    assert "live_growth=0.5" in repr(c)
    with pytest.raises(ValueError, match="seeded surface"):
        paper = lidarsurf.Reconstructor(lidarsurf.Config.paper())
        paper.integrate(scan)
        paper.update_mesh()


def test_fuse_live_yields_what_the_live_view_streams(scan, tmp_path):
    # A sequence written by hand: the scan seen from three places along x.
    os.makedirs(tmp_path / "velodyne")
    with open(tmp_path / "poses.txt", "w") as poses:
        for i, x in enumerate((0.0, 5.0, 10.0)):
            np.hstack([scan, np.zeros((len(scan), 1))]).astype(np.float32).tofile(tmp_path / "velodyne" / f"{i:06d}.bin")
            poses.write(f"1 0 0 {x} 0 1 0 0 0 0 1 0\n")
    rec = lidarsurf.Reconstructor()
    client = {}
    updates = list(lidarsurf.fuse_live(str(tmp_path), budget_ms=0, reconstructor=rec))
    assert [u.scan for u in updates] == [0, 1, 2]
    assert [u.pose[0, 3] for u in updates] == [0.0, 5.0, 10.0]
    for u in updates:
        for key in u.delta.removed:
            del client[key]
        for key, mesh in u.delta.changed:
            client[key] = mesh
    live = rec.live_mesh()
    assert sum(len(m.triangles) for m in client.values()) == len(live.triangles) > 1000
    assert [u.scan for u in lidarsurf.fuse_live(str(tmp_path), step=2)] == [0, 2]
    assert [u.scan for u in lidarsurf.fuse_live(str(tmp_path), first=1, frames=1)] == [1]
    # The same drive as a ROS 1 bag (ROS's own writer) with the poses and their times: the same map.
    bag, times = tmp_path / "drive.bag", tmp_path / "times.txt"
    writer = os.path.join(os.path.dirname(__file__), "..", "..", "tests", "io", "kitti_to_ros1_bag.py")
    if subprocess.run(["/usr/bin/python3", writer, str(tmp_path), str(bag), str(times)], capture_output=True).returncode != 0:
        pytest.skip("python3-rosbag is absent")
    try:
        next(iter(lidarsurf.read_recording(str(bag))))
    except ValueError:
        pytest.skip("this build reads no ROS 1 bags")
    from_bag = lidarsurf.Reconstructor()
    assert [u.scan for u in lidarsurf.fuse_live(str(bag), budget_ms=0, reconstructor=from_bag, poses=str(tmp_path / "poses.txt"),
                                                times=str(times))] == [0, 1, 2]
    a, b = rec.extract_mesh(), from_bag.extract_mesh()
    np.testing.assert_array_equal(a.vertices, b.vertices)
    np.testing.assert_array_equal(a.triangles, b.triangles)
    assert [u.scan for u in lidarsurf.fuse_live(str(bag), step=2, poses=str(tmp_path / "poses.txt"), times=str(times))] == [0, 2]
    assert [u.scan for u in lidarsurf.fuse_live(str(bag), first=1, frames=1, poses=str(tmp_path / "poses.txt"), times=str(times))] == [1]
    with pytest.raises(ValueError, match="no /tf, /tf_static or pose topic"):
        next(lidarsurf.fuse_live(str(bag)))
    # The poses in the bag's own /tf (odom -> base_link, and base_link -> velodyne in /tf_static):
    # chained, they are poses.txt's.
    tf_writer = os.path.join(os.path.dirname(writer), "write_tf_bag.py")
    if subprocess.run(["/usr/bin/python3", tf_writer, str(tmp_path), str(tmp_path)], capture_output=True).returncode != 0:
        pytest.skip("python3-tf2-msgs or python3-nav-msgs is absent")
    poses = [pose for (_, _, _, pose) in lidarsurf.read_recording(str(tmp_path / "tf.bag"), poses="recording")]
    assert len(poses) == 3
    for x, pose in zip((0.0, 5.0, 10.0), poses):
        np.testing.assert_allclose(pose, [[1, 0, 0, x], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], atol=1e-9)
    updates = list(lidarsurf.fuse_live(str(tmp_path / "tf.bag"), budget_ms=0))
    assert [u.scan for u in updates] == [0, 1, 2]
    np.testing.assert_allclose([u.pose[0, 3] for u in updates], [0.0, 5.0, 10.0], atol=1e-9)
    with pytest.raises(ValueError, match="no frame 'nowhere'"):
        lidarsurf.read_recording(str(tmp_path / "tf.bag"), poses="recording", fixed_frame="nowhere")


def test_live_messages_have_the_documented_layout_and_read_back():
    import struct
    origin = (1000.0, 2000.0, 10.0)
    pose = np.array([[1, 0, 0, 1003.0], [0, 1, 0, 2004.0], [0, 0, 1, 10.5], [0, 0, 0, 1]])
    tri = lidarsurf.Mesh([[1000, 2000, 10], [1001, 2000, 10], [1000, 2001, 10.5]], [[0, 1, 2]])
    data = lidarsurf.encode_live_message(7, origin, pose, [[1003.0, 2004.0, 10.5]], [(-1, 2, -3)], [((5, 6, -7), tri)],
                                         reset=True, final=True)
    # The header and the block's fields as docs/live_view.md lays them out.
    assert data[:4] == b"LSLV" and struct.unpack_from("<III", data, 4) == (3, 1 | 2, 7)
    assert struct.unpack_from("<3d", data, 16) == origin
    assert struct.unpack_from("<12f", data, 40)[3::4] == (3.0, 4.0, 0.5)  # translation relative to the origin
    assert struct.unpack_from("<III", data, 88) == (1, 1, 1)
    assert struct.unpack_from("<3f", data, 112) == (3.0, 4.0, 0.5)
    assert struct.unpack_from("<3i", data, 124) == (-1, 2, -3)
    key, counts, corner = struct.unpack_from("<3i", data, 136), struct.unpack_from("<II", data, 148), struct.unpack_from("<3f", data, 156)
    assert key == (5, 6, -7) and counts == (3, 1) and corner == (0.0, 0.0, 0.0)
    step, cstep = struct.unpack_from("<2f", data, 168)
    assert step == pytest.approx(0.5e-3) and cstep == 0  # the finest step (1 m needs no more); no confidence
    assert struct.unpack_from("<2f", data, 176) == (0.0, -1.0)  # no intensity
    vertex_bytes, index_bytes = struct.unpack_from("<II", data, 184)
    assert len(data) == 192 + (vertex_bytes + 3) // 4 * 4 + (index_bytes + 3) // 4 * 4

    m = lidarsurf.decode_live_message(data)
    assert (m["scans"], m["reset"], m["final"], m["more"]) == (7, True, True, False)
    assert m["origin"] == origin
    np.testing.assert_allclose(m["pose"], pose, atol=1e-5)
    np.testing.assert_allclose(m["trajectory"], [[1003.0, 2004.0, 10.5]])
    assert m["removed"] == [(-1, 2, -3)]
    (key, mesh), = m["changed"]
    assert key == (5, 6, -7)
    # The stream's order: the triangle's corners in cyclic order are the mesh's, within a step.
    corners = mesh.vertices[mesh.triangles[0]]
    first = int(np.argmin(np.linalg.norm(corners - tri.vertices[0], axis=1)))
    np.testing.assert_allclose(np.roll(corners, -first, axis=0), tri.vertices, atol=0.26e-3)
    with pytest.raises(ValueError, match="live stream"):
        lidarsurf.decode_live_message(data[:150])  # truncated


def test_read_poses_and_the_calibration(tmp_path):
    # Two lidar poses L, a velodyne-to-camera Tr; the file holds KITTI's camera poses Tr L Tr^-1.
    def rot_z(a, t):
        m = np.eye(4)
        m[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
        m[:3, 3] = t
        return m
    tr = np.array([[0, -1, 0, 0.1], [0, 0, -1, -0.05], [1, 0, 0, -0.3], [0, 0, 0, 1.0]])
    lidar = [rot_z(0.0, (0, 0, 0)), rot_z(0.3, (5.0, 1.0, 0.2))]
    camera = [tr @ l @ np.linalg.inv(tr) for l in lidar]
    np.savetxt(tmp_path / "poses.txt", np.array([c[:3].reshape(-1) for c in camera]), fmt="%.17g")
    (tmp_path / "calib.txt").write_text("P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: " + " ".join("%.17g" % x for x in tr[:3].reshape(-1)) + "\n")
    raw = lidarsurf.read_poses(str(tmp_path / "poses.txt"))
    assert raw.shape == (2, 4, 4)
    np.testing.assert_allclose(raw, camera, atol=1e-12)
    np.testing.assert_allclose(lidarsurf.read_poses(str(tmp_path / "poses.txt"), calib=str(tmp_path / "calib.txt")), lidar,
                               atol=1e-12)
    with pytest.raises(OSError):
        lidarsurf.read_poses(str(tmp_path / "missing.txt"))
    (tmp_path / "bad.txt").write_text("P0: 1 0 0 0 0 1 0 0 0 0 1 0\n")
    with pytest.raises(ValueError, match="Tr:"):
        lidarsurf.read_poses(str(tmp_path / "poses.txt"), calib=str(tmp_path / "bad.txt"))


def test_every_simd_level_gives_the_same_mesh(scan):
    levels = lidarsurf.simd_levels()
    assert levels and lidarsurf.simd_level() == levels[-1]  # the widest by default
    meshes = []
    try:
        for level in levels:
            lidarsurf.set_simd_level(level)
            assert lidarsurf.simd_level() == level
            meshes.append(lidarsurf.reconstruct(scan))
    finally:
        lidarsurf.set_simd_level(levels[-1])
    for m in meshes[1:]:
        assert np.array_equal(m.vertices, meshes[0].vertices) and np.array_equal(m.triangles, meshes[0].triangles)
        assert np.array_equal(m.normals, meshes[0].normals) and np.array_equal(m.confidence, meshes[0].confidence)
    with pytest.raises(ValueError, match="unknown SIMD level"):
        lidarsurf.set_simd_level("avx1024")


# ---- Recordings (the real Ouster recordings of ../shared/data; skipped when absent). ----
_OUSTER = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data", "ouster")


@pytest.mark.skipif(not os.path.isdir(_OUSTER), reason="../shared/data/ouster is absent")
def test_read_recording_gives_the_scans_with_times_and_poses_from_a_trajectory(tmp_path):
    pcap = os.path.join(_OUSTER, "OS-2-128-U1_v2.3.0_1024x10.pcap")
    scans = list(lidarsurf.read_recording(pcap))
    assert len(scans) == 1
    stamp, points, times, pose = scans[0]
    assert points.shape[1] == 3 and points.shape[0] > 100000 and np.isfinite(points).all()
    assert times.shape == (points.shape[0],) and 0 <= times.min() and times.max() <= 0.1
    assert pose is None
    # A trajectory that turns the sensor by pi/4 about z and lifts it 4 m over two seconds: at the
    # stamp, halfway, the pose is pi/8 and 2 m; the points stay in the sensor frame.
    s = stamp / 1e9
    q = (0, 0, np.sin(np.pi / 8), np.cos(np.pi / 8))  # qx qy qz qw of a pi/4 turn about z
    traj = tmp_path / "traj.txt"
    traj.write_text("%.9f 0 0 0 0 0 0 1\n%.9f 0 0 4 %g %g %g %g\n" % (s - 1, s + 1, *q))
    (stamp2, points2, times2, pose2) = next(iter(lidarsurf.read_recording(pcap, poses=str(traj), deskew=False)))
    assert stamp2 == stamp
    np.testing.assert_array_equal(points2, points)
    assert pose2.shape == (4, 4)
    np.testing.assert_allclose(pose2[:3, 3], [0, 0, 2], atol=1e-6)
    yaw = np.arctan2(pose2[1, 0], pose2[0, 0])
    np.testing.assert_allclose(yaw, np.pi / 8, atol=1e-6)  # half of the pi/4 turn between the lines
    with pytest.raises(ValueError, match="returns"):
        lidarsurf.read_recording(pcap, returns="third")
    with pytest.raises(ValueError):
        list(lidarsurf.read_recording(pcap, metadata=os.path.join(_OUSTER, "OS-0-32-U1_v2.2.0_1024x10.json")))


def test_intensity_reaches_the_mesh(scan, tmp_path):
    # Stripes 8 m wide along x, bright (0.8) and dark (0.1): every vertex reads a mean of the two,
    # and one far from a border reads its stripe's value.
    bright = (np.floor(scan[:, 0] / 8.0) % 2 == 0)
    intensity = np.where(bright, 0.8, 0.1).astype(np.float32)
    rec = lidarsurf.Reconstructor()
    rec.integrate(scan, intensity=intensity)
    mesh = rec.extract_mesh()
    assert mesh.intensity.shape == (len(mesh.vertices),)
    assert np.all((mesh.intensity >= 0.1 - 1e-6) & (mesh.intensity <= 0.8 + 1e-6))
    x = mesh.vertices[:, 0]
    frac = x / 8.0 - np.floor(x / 8.0)
    # Farther than H^5 and a voxel from a border, and not bridged (a bridge takes a wider box).
    inner = (np.minimum(frac, 1 - frac) * 8.0 > 1.5) & (mesh.confidence >= lidarsurf.Config().tau)
    expected = np.where(np.floor(x / 8.0) % 2 == 0, 0.8, 0.1)
    assert inner.sum() > 1000
    assert np.mean(np.abs(mesh.intensity[inner] - expected[inner]) < 1e-5) > 0.995
    mesh.save(str(tmp_path / "m.ply"))
    assert b"property float intensity" in (tmp_path / "m.ply").read_bytes()[:600]
    with pytest.raises(ValueError, match="one per point"):
        rec.integrate(scan[:10], intensity=intensity[:9])
    plain = lidarsurf.Reconstructor()
    plain.integrate(scan)
    assert plain.extract_mesh().intensity.shape == (0,)
