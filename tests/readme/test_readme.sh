#!/usr/bin/env bash
# The README's command-line and Python snippets, run as written in a scratch directory (the C++
# and CMake ones are built by `make package-check`): each must succeed and leave the files it
# names. Usage: test_readme.sh BUILD_DIR
set -eu
build=$(cd "$1" && pwd)
root=$(cd "$(dirname "$0")/../.." && pwd)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir"
/usr/bin/python3 "$root/scripts/readme_snippets.py" cli "$root/README.md" > cli.sh
/usr/bin/python3 "$root/scripts/readme_snippets.py" python "$root/README.md" > snippet.py
PATH="$build/bin:$PATH" bash -eu cli.sh > cli.log 2>&1 || { cat cli.log; echo "FAIL: the README's command-line snippet"; exit 1; }
for f in scan.bin mesh.ply map.ply mesh.html; do
  [ -s "$f" ] || { echo "FAIL: the command-line snippet left no $f"; exit 1; }
done
PYTHONPATH="$build/python" /usr/bin/python3 snippet.py > python.log 2>&1 || { cat python.log; echo "FAIL: the README's Python snippet"; exit 1; }
[ "$(head -c 3 mesh.ply)" = ply ] || { echo "FAIL: the Python snippet wrote no mesh.ply"; exit 1; }
grep -q "Mesh(" python.log || { cat python.log; echo "FAIL: the Python snippet printed no mesh"; exit 1; }
echo "readme: 2 passed, 0 failed"
