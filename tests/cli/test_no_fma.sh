#!/usr/bin/env bash
# The portable build's AVX2 and AVX-512 code (core/simd.hpp) must not fuse multiply-adds: every
# SIMD level does the baseline's operations, so the meshes do not depend on the CPU. Samples are
# stored as floats, so a fused multiply-add would rarely show in a mesh; this checks the code.
set -u
cli="$1"
command -v objdump >/dev/null || { echo "objdump not found: skipped"; exit 0; }
fused=$(objdump -d --no-show-raw-insn "$cli" | grep -cE '\svfn?m(add|sub)[0-9]')
echo "fused multiply-add instructions in $cli: $fused"
[ "$fused" -eq 0 ]
