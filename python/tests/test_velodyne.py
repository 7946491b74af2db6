"""Velodyne pcaps read by lidarsurf.read_recording, checked against Foxglove's decoder
(@foxglove/velodyne-cloud, the one Foxglove Studio turns velodyne_msgs/VelodyneScan into points with;
tests/io/ros2/velodyne_points.mjs), on packets written here from the manuals' layout, with the
ROS velodyne driver's calibrations of ../shared/data and lidarsurf's built-in factory angles.

Foxglove's decoder places every laser of a block at the block's azimuth; lidarsurf advances each
laser's azimuth by the time it fired after the block's first (the manuals' precise azimuth), so a
point of lidarsurf's is Foxglove's turned about z by that advance, which the test computes from
the manuals' firing times."""
import json
import os
import shutil
import struct
import subprocess
import sys

import numpy as np
import pytest
import yaml

import lidarsurf

_ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
sys.path.insert(0, os.path.join(_ROOT, "tests", "io"))
from velodyne_pcap import MODELS as _MODELS, packet as _packet, write_pcap as _pcap  # noqa: E402
_WRITERS = os.path.join(_ROOT, "tests", "io", "ros2")
_CALIBRATIONS = os.path.join(_ROOT, "..", "shared", "data", "sensors", "velodyne_ros_drivers")
_REAL = os.path.join(_ROOT, "..", "shared", "data", "ouster", "VLP-16-one-packet.pcap")
_HAVE_FOXGLOVE = shutil.which("node") and os.path.isdir(os.path.join(_WRITERS, "node_modules", "@foxglove", "velodyne-cloud"))

def _foxglove(tmp_path, model, packets, calibration):
    # The ROS driver's defaults for what a calibration leaves out (Foxglove's decoder has none).
    for laser in calibration["lasers"]:
        for key in ("dist_correction", "dist_correction_x", "dist_correction_y", "vert_offset_correction", "horiz_offset_correction",
                    "focal_distance", "focal_slope"):
            laser.setdefault(key, 0.0)
    (tmp_path / "packets.bin").write_bytes(b"".join(packets))
    (tmp_path / "calibration.json").write_text(json.dumps(calibration))
    subprocess.run(["node", os.path.join(_WRITERS, "velodyne_points.mjs"), str(tmp_path / "packets.bin"), model,
                    str(tmp_path / "calibration.json"), str(tmp_path / "fox.bin")], check=True)
    return np.fromfile(tmp_path / "fox.bin").reshape(-1, 5)


def _raw(k, blk, j):
    return 0 if (3 * k + blk + j) % 11 == 5 else 1500 + (97 * k + 31 * blk + 7 * j) % 20000  # 3 to 43 m, some empty


def _advance(model, packets):
    """Per point of lidarsurf's order (packet, block, channel, returns only): the azimuth advance in
    hundredths of a degree, from the block's azimuth step and the manuals' firing times."""
    _, lasers, block_us, fires = _MODELS[model]
    out = []
    for k, p in enumerate(packets):
        az = [struct.unpack_from("<H", p, 100 * b + 2)[0] for b in range(12)]
        for blk in range(12):
            step = (az[blk + 1] - az[blk]) % 36000 if blk < 11 else (az[11] - az[10]) % 36000
            for j in range(32):
                if struct.unpack_from("<H", p, 100 * blk + 4 + 3 * j)[0]:
                    out.append(0.0 if lasers == 64 else step * fires(j) / block_us)
    return np.array(out)


def _turned(points, hundredths):
    """Points turned clockwise about z (Velodyne's sense of azimuth) by hundredths of a degree."""
    a = -np.radians(hundredths / 100)
    c, s = np.cos(a), np.sin(a)
    return np.stack([c * points[:, 0] - s * points[:, 1], s * points[:, 0] + c * points[:, 1], points[:, 2]], axis=1)


@pytest.mark.skipif(not _HAVE_FOXGLOVE, reason="node or tests/io/ros2/node_modules (scripts/setup.sh) is absent")
@pytest.mark.skipif(not os.path.isdir(_CALIBRATIONS), reason="../shared/data is absent")
@pytest.mark.parametrize("model,calibration", [("VLP16", "VLP16db.yaml"), ("VLP32C", "VeloView-VLP-32C.yaml"), ("HDL32E", "32db.yaml"),
                                               ("HDL64E", "64e_s3-xiesc.yaml"), ("HDL64E", "64e_utexas.yaml")])
def test_points_are_foxgloves_at_the_precise_azimuth(tmp_path, model, calibration):
    packets = [_packet(model, k, _raw) for k in range(4)]
    _pcap(tmp_path / "drive.pcap", packets)
    shutil.copy(os.path.join(_CALIBRATIONS, calibration), tmp_path / "drive.yaml")  # beside the pcap, as X.yaml
    scans = list(lidarsurf.read_recording(str(tmp_path / "drive.pcap")))
    assert len(scans) == 1
    ours = scans[0][1]
    with open(tmp_path / "drive.yaml") as f:
        fox = _foxglove(tmp_path, model, packets, yaml.safe_load(f))
    assert ours.shape[0] == fox.shape[0] == sum(1 for p in packets for b in range(12) for j in range(32)
                                                if struct.unpack_from("<H", p, 100 * b + 4 + 3 * j)[0])
    expected = _turned(fox[:, :3], _advance(model, packets))
    # Foxglove's points are float32: 1e-5 m at these ranges.
    np.testing.assert_allclose(ours, expected, rtol=0, atol=2e-5)


@pytest.mark.skipif(not os.path.isdir(_CALIBRATIONS), reason="../shared/data is absent")
@pytest.mark.parametrize("model,calibration", [("VLP16", "VLP16db.yaml"), ("VLP32C", "VeloView-VLP-32C.yaml"), ("HDL32E", "32db.yaml")])
def test_the_built_in_factory_angles_are_the_ros_drivers(tmp_path, model, calibration):
    # The same packets without a calibration beside them take the built-in angles of the model the
    # product byte names: the points of the ROS driver's calibration, to its 0.001 degree.
    packets = [_packet(model, k, _raw) for k in range(2)]
    _pcap(tmp_path / "builtin.pcap", packets)
    _pcap(tmp_path / "given.pcap", packets)
    builtin = next(iter(lidarsurf.read_recording(str(tmp_path / "builtin.pcap"))))[1]
    given = next(iter(lidarsurf.read_recording(str(tmp_path / "given.pcap"), metadata=os.path.join(_CALIBRATIONS, calibration))))[1]
    ranges = np.linalg.norm(given, axis=1)
    assert np.all(np.linalg.norm(builtin - given, axis=1) <= ranges * np.radians(0.0011))


@pytest.mark.skipif(not os.path.exists(_REAL), reason="../shared/data is absent")
def test_the_real_packet_of_another_layout_is_refused_naming_it():
    # The SDK's one-packet capture has 1212-byte datagrams (six bytes more than a data packet, product
    # byte 0x10): refused, saying what it holds, not decoded as a VLP-16.
    with pytest.raises(ValueError, match="1212-byte datagrams to port 2368 with Velodyne block flags"):
        list(lidarsurf.read_recording(_REAL))


def test_a_velodyne_pcap_gives_its_sweeps_and_times(tmp_path):
    packets = [_packet("VLP16", k, _raw, first=35000) for k in range(75)]  # 10 degrees, then the wrap and 350
    _pcap(tmp_path / "vlp.pcap", packets)
    scans = list(lidarsurf.read_recording(str(tmp_path / "vlp.pcap")))
    assert len(scans) == 2
    stamp, points, times, pose = scans[1]
    assert pose is None and points.shape[1] == 3 and times.shape == (points.shape[0],)
    assert 0 <= times.min() and times.max() < 0.1
    np.testing.assert_array_less(np.linalg.norm(points, axis=1), 45)
