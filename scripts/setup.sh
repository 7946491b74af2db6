#!/usr/bin/env bash
# Installs the Debian 12 packages lidarsurf needs to build and test. Skips what is present.
# Run as root (or with sudo available). Idempotent.
set -euo pipefail

PKGS=(
  build-essential cmake pkg-config
  libeigen3-dev        # linear algebra, 3x3 eigen solver
  libtbb-dev           # oneTBB: parallel vertex evaluation
  libnanoflann-dev     # kd-tree (IMLS, evaluation)
  libcli11-dev         # command-line parsing
  liblzf-dev           # PCD binary_compressed (LZF)
  libmeshoptimizer-dev # mesh simplification (--simplify)
  libdraco-dev         # Draco compression of binary glTF (--mesh-format glb-draco)
  libtinygltf-dev      # tests: Draco's glTF decoder reads the .glb files back
  libgtest-dev         # unit tests
  libbenchmark-dev     # micro-benchmarks
  libembree-dev        # ray casting: simulator and renderer
  nlohmann-json3-dev   # sensor files (JSON), benchmark results
  libpng-dev           # PNG pictures (render, demo)
  libboost-dev         # Boost.Beast/Asio: HTTP and WebSocket of the live view (fuse --serve)
  python3-matplotlib   # benchmark plots (Fig. 6)
  python3-dev pybind11-dev   # Python bindings (Debian's /usr/bin/python3)
  python3-numpy python3-pytest
  python3-distributed  # Dask: a map fused in tiles on many workers (lidarsurf.fuse_tiles)
  libpcap-dev          # recordings: packet captures (Ouster and Velodyne pcaps)
  libyaml-dev          # recordings: Velodyne calibrations (the ROS velodyne driver's YAML)
  librosbag-storage-dev  # recordings: ROS 1's own bag reader (optional: the build reads no bags without it)
  libsqlite3-dev libzstd-dev liblz4-dev zlib1g-dev  # recordings: ROS 2 bags (.db3; MCAP chunks and their CRC)
  lz4                  # tests: LZ4 frames of the MCAP chunks the tests write
  python3-rosbag python3-sensor-msgs  # tests: ROS 1 bags written by ROS's own writer
  python3-tf2 python3-tf2-msgs python3-nav-msgs python3-geometry-msgs  # tests: poses in bags, checked by tf2's own BufferCore
)
# npm fetches three.js for the viewer (below); a machine with Node.js from elsewhere has npm already,
# and Debian's npm package would conflict with it.
if ! command -v npm >/dev/null; then PKGS+=(npm); fi
# `setup.sh fuzz`: also clang and its libFuzzer runtime (make fuzz); `setup.sh tsan`: the tools
# that fetch and check Debian's oneTBB source (make tsan, scripts/build_tbb_tsan.sh); `setup.sh
# peers`: Open3D for the accuracy benchmark's peers (make accuracy).
if [ "${1:-}" = "fuzz" ]; then PKGS+=(clang libclang-rt-14-dev); fi
if [ "${1:-}" = "tsan" ]; then PKGS+=(curl xz-utils ca-certificates); fi
# `setup.sh peers`: Open3D, the meshers users already have (make accuracy, scripts/peers_open3d.py).
if [ "${1:-}" = "peers" ]; then PKGS+=(python3-open3d); fi
# `setup.sh pcl`: PCL for tools/pcl_peer (make accuracy-pcl; about 380 packages).
if [ "${1:-}" = "pcl" ]; then PKGS+=(libpcl-dev); fi
# `setup.sh vdbfusion`: OpenVDB for tools/vdbfusion_peer (make map-peers).
if [ "${1:-}" = "vdbfusion" ]; then PKGS+=(libopenvdb-dev); fi
# `setup.sh viewer`: Chromium, which renders the viewer's pages in their tests (make viewer-check).
if [ "${1:-}" = "viewer" ]; then PKGS+=(chromium); fi

missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PKGS[@]} packages present"
else
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
# three.js for the viewer: the pinned version of viewer/package-lock.json, once, into
# viewer/node_modules (the CLI's build embeds it in every HTML file `lidarsurf view` writes).
viewer="$(cd "$(dirname "$0")/.." && pwd)/viewer"
if [ ! -f "$viewer/node_modules/three/build/three.min.js" ]; then
  echo "setup: npm ci in $viewer (three.js for lidarsurf view)"
  (cd "$viewer" && npm ci --no-audit --no-fund --loglevel=error)
fi
# The format maintainers' MCAP and CDR writers that write the ROS 2 bags of the tests, and Foxglove's
# Velodyne decoder that checks ours (the pinned versions of tests/io/ros2/package-lock.json).
ros2_writers="$(cd "$(dirname "$0")/.." && pwd)/tests/io/ros2"
if [ ! -d "$ros2_writers/node_modules/@mcap/core" ] || [ ! -d "$ros2_writers/node_modules/@foxglove/velodyne-cloud" ]; then
  echo "setup: npm ci in $ros2_writers (@mcap/core, @foxglove/cdr and @foxglove/velodyne-cloud for the recordings tests)"
  (cd "$ros2_writers" && npm ci --no-audit --no-fund --loglevel=error)
fi
# `setup.sh viewer`: playwright-core and gltf-validator (the pinned versions of
# tests/viewer/package-lock.json): the first drives Debian's Chromium through the live view and the
# glTF check in make viewer-check (it downloads no browser); the second is Khronos's glTF validator.
tests_viewer="$(cd "$(dirname "$0")/.." && pwd)/tests/viewer"
if [ "${1:-}" = "viewer" ] && { [ ! -d "$tests_viewer/node_modules/playwright-core" ] || [ ! -d "$tests_viewer/node_modules/gltf-validator" ]; }; then
  echo "setup: npm ci in $tests_viewer (playwright-core and gltf-validator for the viewer's checks)"
  (cd "$tests_viewer" && npm ci --no-audit --no-fund --loglevel=error)
fi
