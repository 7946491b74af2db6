"""Fixtures shared by the Python tests."""
import os

import numpy as np
import pytest


@pytest.fixture(scope="session")
def cli():
    """The lidarsurf CLI that ctest names (LIDARSURF_CLI); the test is skipped without it."""
    path = os.environ.get("LIDARSURF_CLI")
    if not path:
        pytest.skip("LIDARSURF_CLI not set (run through ctest)")
    return path


@pytest.fixture(scope="session")
def triangle_rows():
    """A function giving a mesh's triangles as sorted rows of their 9 coordinates, each rotated to
    start at its smallest corner: the same whatever the vertex numbering."""
    def rows(mesh):
        out = []
        for tri in np.asarray(mesh.vertices)[np.asarray(mesh.triangles)]:
            corners = [tuple(c) for c in tri]
            k = corners.index(min(corners))
            out.append(sum(corners[k:] + corners[:k], ()))
        return sorted(out)
    return rows
