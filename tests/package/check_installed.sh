#!/usr/bin/env bash
# What a consumer of the installed package gets (make package-check), checked on the install in
# PREFIX: the reconstruction's targets name only Eigen and TBB (no Embree, no libpng: those are the
# sim/viz components'), no exported file names an absolute library path or this build tree, and
# the archives hold machine code only (no LTO bytecode for the consumer's link to optimise).
# Usage: check_installed.sh PREFIX BUILD_DIR
set -euo pipefail
prefix=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
cmakedir=$(dirname "$(find "$prefix" -name lidarsurfConfig.cmake | head -1)")
fail=0
core="$cmakedir/lidarsurfTargets.cmake"
if grep -qiE 'embree|png' "$core"; then echo "FAIL: lidarsurf::lidarsurf needs Embree or libpng"; fail=1; fi
if grep -hE 'INTERFACE_LINK_LIBRARIES|IMPORTED_LINK' "$cmakedir"/lidarsurf*Targets*.cmake | grep -qE '"/|;/'; then
  echo "FAIL: an exported target names an absolute path:"; grep -hE 'INTERFACE_LINK_LIBRARIES' "$cmakedir"/lidarsurf*Targets*.cmake; fail=1
fi
if grep -rq "$build" "$cmakedir"; then echo "FAIL: the exported files name the build tree $build"; fail=1; fi
for a in "$prefix"/lib*/liblidarsurf*.a; do
  if objdump -h "$a" | grep -q '\.gnu\.lto_'; then echo "FAIL: $a holds LTO bytecode"; fail=1; fi
done
echo "package-check: exported targets and archives checked ($(ls "$prefix"/lib*/liblidarsurf*.a | wc -l) archives)"
exit $fail
