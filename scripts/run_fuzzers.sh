#!/usr/bin/env bash
# Runs every libFuzzer harness in DIR for SECONDS each, starting from its seed corpus
# (fuzz/corpus/<name>/, read only) plus a scratch corpus in DIR/corpus/<name>/ that grows over runs.
# Fails on the first finding: a crash, a sanitizer report, a leak, an uncaught non-lidarsurf
# exception, an input slower than 10 s or an allocation above 2 GB. The reproducer is left in
# DIR/artifacts/; turn it into a regression test (tests/io/test_fuzz_regressions.cpp).
# Usage: run_fuzzers.sh DIR SECONDS [NAME...]
set -uo pipefail
dir=$1 seconds=$2; shift 2
src=$(cd "$(dirname "$0")/.." && pwd)
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(fuzz_kitti_bin fuzz_ply_points fuzz_pcd_points fuzz_text_points fuzz_poses
                                 fuzz_mesh_reader fuzz_sensor_json fuzz_reconstruct fuzz_live_stream
                                 fuzz_ouster_pcap fuzz_velodyne_pcap fuzz_point_cloud2 fuzz_cdr_point_cloud2 fuzz_mcap fuzz_tf)
mkdir -p "$dir/artifacts" "$dir/logs"
status=0
printf '%-18s %8s %12s %10s %8s  %s\n' harness seconds executions exec/s corpus result
for name in "${names[@]}"; do
    mkdir -p "$dir/corpus/$name"
    log="$dir/logs/$name.log"
    ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        "$dir/$name" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
        -print_final_stats=1 -artifact_prefix="$dir/artifacts/$name-" \
        "$dir/corpus/$name" "$src/fuzz/corpus/$name" >"$log" 2>&1
    rc=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    corpus=$(ls "$dir/corpus/$name" | wc -l)
    result=ok
    if [ "$rc" -ne 0 ]; then
        result="FAILED (exit $rc, log $log)"
        status=1
    fi
    printf '%-18s %8s %12s %10s %8s  %s\n' "$name" "$seconds" "${execs:-?}" "${rate:-?}" "$corpus" "$result"
    if [ "$rc" -ne 0 ]; then grep -m 20 -E "ERROR|SUMMARY|invariant|terminate|what\(\)|Test unit written" "$log"; fi
done
exit $status
