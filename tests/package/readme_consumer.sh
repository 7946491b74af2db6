#!/usr/bin/env bash
# The README's CMake and C++ snippets as a user's project against the installed package
# (BUILD/pkg-prefix, from `make package-check`): configured, built (timed) and run on a scan.
# Usage: readme_consumer.sh BUILD_DIR
set -euo pipefail
build=$(cd "$1" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
app="$build/pkg-readme"
rm -rf "$app"
mkdir -p "$app"
{
  echo "cmake_minimum_required(VERSION 3.20)"
  echo "project(readme_app CXX)"
  echo "set(CMAKE_CXX_STANDARD 20)"
  echo "add_executable(app main.cpp)"
  /usr/bin/python3 "$root/scripts/readme_snippets.py" cmake "$root/README.md"
} > "$app/CMakeLists.txt"
/usr/bin/python3 "$root/scripts/readme_snippets.py" cpp "$root/README.md" > "$app/main.cpp"
t0=$(date +%s%N)
cmake -S "$app" -B "$app/build" -DCMAKE_PREFIX_PATH="$build/pkg-prefix" > "$app/configure.log"
cmake --build "$app/build" > "$app/build.log"
t1=$(date +%s%N)
ms=$(( (t1 - t0) / 1000000 ))
echo "package-check: the README's C++ example configured and built in $((ms / 1000)).$(( (ms % 1000) / 100 )) s"
"$build/bin/lidarsurf" simulate --scene demo -o "$app/scan.bin" > /dev/null
"$app/build/app" "$app/scan.bin" "$app/mesh.ply"
[ "$(head -c 3 "$app/mesh.ply")" = ply ] || { echo "FAIL: the README's C++ example wrote no mesh"; exit 1; }
echo "package-check: the README's C++ example meshed a scan"
