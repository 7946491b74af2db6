#!/usr/bin/env bash
# Alternated A/B of two lidarsurf binaries (docs/benchmarks.md): on a shared, noisy host only
# variants measured in the same run, alternated, compare. Each round runs
#   BINARY bench [SCAN...] --no-reference --no-imls --no-scaling --repeat 7 [ARGS...]
# for A and B (A first in odd rounds, B first in even ones); the table gives, per scan and
# binary, the median over rounds of each round's median (ms), and B's total relative to A's.
#
# Usage: scripts/ab_bench.sh A_BINARY B_BINARY [ROUNDS] [-- BENCH_ARGS...]
#   scripts/ab_bench.sh /tmp/lidarsurf_before build/bin/lidarsurf 5
#   scripts/ab_bench.sh /tmp/before build/bin/lidarsurf 7 -- scan.bin --threads 1
set -euo pipefail
if [ $# -lt 2 ]; then
    awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"
    exit 2
fi
a=$1 b=$2
shift 2
rounds=5
if [ $# -gt 0 ] && [ "$1" != "--" ]; then rounds=$1; shift; fi
[ $# -gt 0 ] && [ "$1" = "--" ] && shift
for bin in "$a" "$b"; do [ -x "$bin" ] || { echo "ab_bench: $bin is not an executable" >&2; exit 2; }; done
case $rounds in '' | *[!0-9]* | 0) echo "ab_bench: ROUNDS must be a positive integer" >&2; exit 2 ;; esac

# The table keys rows by the scan's file name: two scans with the same name (e.g. frame 000000 of
# two sequences) would be merged into one row, so refuse them.
# (`if`, not `&&`: a last argument that is not a file, e.g. a thread count, must not fail the
# loop under `set -e -o pipefail`.)
dups=$(for arg in "$@"; do case $arg in -*) ;; *) if [ -f "$arg" ]; then basename -- "$arg"; fi ;; esac; done | sort | uniq -d)
if [ -n "$dups" ]; then
    echo "ab_bench: scans with the same file name would share a row: $(echo $dups) (copy them under distinct names)" >&2
    exit 2
fi

out=$(mktemp)
trap 'rm -f "$out"' EXIT
for ((r = 1; r <= rounds; ++r)); do
    # A then B in odd rounds, B then A in even ones: the second run of a round is often slower (or
    # faster) than the first on this host (a binary against itself gave 0.91-1.00 with a fixed
    # order), and alternating the order cancels that bias.
    order="A B"
    ((r % 2 == 0)) && order="B A"
    for tag in $order; do
        bin=$a
        [ $tag = B ] && bin=$b
        # Table rows: scan label (may hold spaces), points, path, thr, read, insert, tsdf, mesh, total, min, ...
        "$bin" bench "$@" --no-reference --no-imls --no-scaling --repeat 7 2>/dev/null |
            awk -v tag=$tag '$0 ~ / fast +[0-9]+ / { for (i = 1; i <= NF; ++i) if ($i == "fast") break;
                 label = $1; for (j = 2; j < i - 1; ++j) label = label "_" $j;
                 print tag, label, $(i + 2), $(i + 3), $(i + 4), $(i + 5), $(i + 6), $(i + 7) }' >> "$out"
    done
    echo "ab_bench: round $r of $rounds done" >&2
done
echo "A = $a"
echo "B = $b"
echo "medians over $rounds rounds (A first in odd ones, B first in even ones) of each round's median (ms)"
sort -k2,2 -k1,1 "$out" | awk '
    function median(list,   n, v, i, j, t) {
        n = split(list, v, " ")
        for (i = 2; i <= n; ++i) for (j = i; j > 1 && v[j - 1] + 0 > v[j] + 0; --j) { t = v[j]; v[j] = v[j - 1]; v[j - 1] = t }
        return n % 2 ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2
    }
    { key = $2 SUBSEP $1; if (!(key in seen)) { seen[key] = 1; order[++k] = key }
      for (c = 3; c <= 8; ++c) col[key, c] = col[key, c] " " $c }
    END {
        printf "%-20s %s %7s %7s %7s %7s %8s %8s %8s\n", "scan", "bin", "read", "insert", "tsdf", "mesh", "total", "min", "B/A"
        for (i = 1; i <= k; ++i) {
            split(order[i], p, SUBSEP)
            for (c = 3; c <= 8; ++c) m[c] = median(col[order[i], c])
            total[p[1], p[2]] = m[7]
            ratio = (p[2] == "B" && total[p[1], "A"] > 0) ? sprintf("%8.3f", m[7] / total[p[1], "A"]) : ""
            printf "%-20s %s %7.1f %7.1f %7.1f %7.1f %8.1f %8.1f %s\n", p[1], p[2], m[3], m[4], m[5], m[6], m[7], m[8], ratio
        }
    }'
