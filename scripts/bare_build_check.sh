#!/usr/bin/env bash
# A clone built as a new user builds it: plain `cmake -S . -B build`, no scripts/setup.sh, so no
# three.js (viewer/node_modules is not in git). Configure must say once that the viewer is left
# out and how to add it; the CLI must build; `lidarsurf view` and `fuse --serve` must exit 2 with that message and
# write nothing; the rest of the CLI must work. The tracked files of the working tree are copied
# (what a clone of this commit holds).
# Usage: bare_build_check.sh [WORK_DIR] (JOBS in the environment: parallel build jobs)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
work=${1:-$(mktemp -d)}
rm -rf "$work/src"
mkdir -p "$work/src"
(cd "$root" && git ls-files -z | tar --null -T - -cf -) | tar -xf - -C "$work/src"
[ ! -e "$work/src/viewer/node_modules" ] || { echo "bare-check: viewer/node_modules is tracked"; exit 1; }
cd "$work/src"
cmake -S . -B build >"$work/configure.log" 2>&1 || { cat "$work/configure.log"; exit 1; }
said=$(grep -c "three.js is missing" "$work/configure.log" || true)
[ "$said" = 1 ] || { cat "$work/configure.log"; echo "bare-check: configure said 'three.js is missing' $said times, not once"; exit 1; }
grep -q "scripts/setup.sh" "$work/configure.log" || { echo "bare-check: configure does not say how to add the viewer"; exit 1; }
cmake --build build --target lidarsurf_cli -j "${JOBS:-2}" >"$work/build.log" 2>&1 || { tail -40 "$work/build.log"; exit 1; }
cli=build/bin/lidarsurf
"$cli" simulate --scene demo -o "$work/scan.bin" >/dev/null
"$cli" reconstruct "$work/scan.bin" -o "$work/mesh.ply" >/dev/null
set +e
"$cli" view "$work/mesh.ply" -o "$work/mesh.html" >"$work/view.out" 2>"$work/view.err"
code=$?
set -e
[ "$code" = 2 ] || { cat "$work/view.err"; echo "bare-check: view exited $code, not 2"; exit 1; }
grep -q "built without the viewer" "$work/view.err" && grep -q "scripts/setup.sh" "$work/view.err" ||
  { cat "$work/view.err"; echo "bare-check: view does not say the viewer is missing and how to add it"; exit 1; }
[ ! -e "$work/mesh.html" ] || { echo "bare-check: view wrote a page without the viewer"; exit 1; }
# The live view is the same page: fuse --serve exits 2 with the same message, before any work.
"$cli" simulate --frames 2 --length 80 --gt-beams 0 -o "$work/drive" --quiet >/dev/null
set +e
"$cli" fuse "$work/drive" -o "$work/map.ply" --serve 0 --quiet >"$work/serve.out" 2>"$work/serve.err"
code=$?
set -e
[ "$code" = 2 ] && grep -q "built without the viewer" "$work/serve.err" ||
  { cat "$work/serve.err"; echo "bare-check: fuse --serve exited $code, not 2 with the viewer's message"; exit 1; }
[ ! -e "$work/map.ply" ] || { echo "bare-check: fuse --serve fused without the viewer"; exit 1; }
echo "bare-check: configured with one warning, the CLI built without the viewer, view and fuse --serve exit 2 saying how to add it"
