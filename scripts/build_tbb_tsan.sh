#!/usr/bin/env bash
# Builds Debian's own oneTBB source (the version of the installed libtbb-dev) with ThreadSanitizer
# into PREFIX, for `make tsan`. Debian's libtbb.so is not instrumented: TSan cannot see its task
# hand-offs and reports every parallel_for result as a race. The tarball comes from the Debian
# archive and is checked against the SHA-256 in Debian's Sources index. Skips if PREFIX is built.
# Usage: build_tbb_tsan.sh PREFIX
set -euo pipefail
prefix=$(realpath -m "$1")
[ -f "$prefix/lib/cmake/TBB/TBBConfig.cmake" ] && { echo "tbb-tsan: present in $prefix"; exit 0; }
upstream=$(dpkg-query -W -f='${Version}' libtbb-dev | sed 's/-[^-]*$//')
mirror=http://deb.debian.org/debian
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
tarball=onetbb_${upstream}.orig.tar.xz
echo "tbb-tsan: fetching $tarball from the Debian archive"
curl -sSf "$mirror/dists/bookworm/main/source/Sources.xz" | xz -d |
    awk '/^Package: onetbb$/,/^$/' | awk -v f="$tarball" '$3 == f && length($1) == 64 {print $1 "  " f}' > "$work/sha256"
[ -s "$work/sha256" ] || { echo "tbb-tsan: $tarball not in Debian's Sources index" >&2; exit 1; }
(cd "$work" && curl -sSfO "$mirror/pool/main/o/onetbb/$tarball" && sha256sum -c sha256 >/dev/null)
tar -C "$work" -xf "$work/$tarball"
cmake -S "$work"/oneTBB-* -B "$work/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DTBB_SANITIZE=thread -DTBB_TEST=OFF \
    -DTBB_EXAMPLES=OFF -DTBBMALLOC_BUILD=OFF -DTBB_STRICT=OFF -DCMAKE_INSTALL_PREFIX="$prefix" >/dev/null
cmake --build "$work/build" -j "$(nproc)" >"$work/build.log" 2>&1 || { tail -30 "$work/build.log"; exit 1; }
cmake --install "$work/build" >/dev/null
echo "tbb-tsan: installed in $prefix"
