#!/usr/bin/env bash
# The Python package as a user installs it, offline: one wheel built by `pip wheel` from the
# source tree (pyproject.toml + setup.py, CMake underneath), then installed (1) into a fresh
# `python3 -m venv --system-site-packages` and (2) for Debian's system Python (into a scratch
# --target, to leave the machine's site-packages alone). Each install imports lidarsurf, runs the
# README's Python lines and checks that the mesh arrays are read-only views. The check is of the
# packaging, so the wheel is built at -O1 without LTO (LIDARSURF_CMAKE_ARGS, setup.py), which
# compiles faster; PIP_CHECK_CMAKE_ARGS= builds it as a user's pip does.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-$root/build/pip-check}
rm -rf "$work"
mkdir -p "$work"
cd "$work"
python=/usr/bin/python3
t0=$(date +%s)
export LIDARSURF_CMAKE_ARGS=${PIP_CHECK_CMAKE_ARGS-"-DLIDARSURF_LTO=OFF -DCMAKE_CXX_FLAGS_RELEASE='-O1 -DNDEBUG'"}
"$python" -m pip wheel --no-build-isolation --no-deps -w wheels "$root" >pip-wheel.log 2>&1 || { tail -40 pip-wheel.log; exit 1; }
wheel=$(ls wheels/lidarsurf-*.whl)
echo "pip-check: built $(basename "$wheel") in $(( $(date +%s) - t0 )) s"

"$python" -m venv --system-site-packages venv
venv/bin/python -m pip install --no-build-isolation --no-index "$wheel" >pip-venv.log 2>&1 || { cat pip-venv.log; exit 1; }
"$python" -m pip install --no-build-isolation --no-index --no-deps --target system-target "$wheel" >pip-system.log 2>&1 ||
  { cat pip-system.log; exit 1; }

smoke='
import os, sys
import numpy as np
import lidarsurf
assert os.path.realpath(lidarsurf.__file__).startswith(os.path.realpath(sys.argv[1])), lidarsurf.__file__
exec(open(sys.argv[2]).read())          # the README snippet, as written
assert len(mesh.triangles) > 0
for a in (mesh.vertices, mesh.triangles, mesh.normals, mesh.levels, mesh.confidence):
    assert not a.flags.writeable, "a mesh array is writable"
assert callable(lidarsurf.fuse_tiles) and lidarsurf.TileConfig(tile_size=50).tile_size == 50  # tiles.py is in the package
print("pip-check:", sys.argv[1], lidarsurf.__version__, mesh)
'
cd "$work"
/usr/bin/python3 "$root/scripts/readme_snippets.py" python "$root/README.md" > snippet.py
venv/bin/python -c "$smoke" "$work/venv" snippet.py
PYTHONPATH="$work/system-target" "$python" -c "$smoke" "$work/system-target" snippet.py
