#!/usr/bin/env bash
# A test binary built from part of the test files (the TSan build: tests/CMakeLists.txt,
# LIDARSURF_TSAN_TEST_SOURCES) must hold every test that FILTER selects in the full suite:
#   scripts/check_test_subset.sh FULL_BINARY PART_BINARY FILTER
# Exit 1, with the missing tests, when it does not; without FULL_BINARY (no Release build beside
# it) it says so and exits 0.
set -euo pipefail
full=$1 part=$2 filter=$3
if [ ! -x "$full" ]; then
    echo "check_test_subset: no $full (build the full suite first): the test list is not checked"
    exit 0
fi
names() {  # Suite.Test per line, sorted, from --gtest_list_tests
    "$1" --gtest_list_tests --gtest_filter="$filter" |
        awk '/^[^ ]/ { suite = $1 } /^  / { print suite $1 }' | sort
}
missing=$(comm -23 <(names "$full") <(names "$part"))
if [ -n "$missing" ]; then
    echo "check_test_subset: $part lacks tests the filter selects in the full suite; add their files to"
    echo "LIDARSURF_TSAN_TEST_SOURCES in tests/CMakeLists.txt:"
    echo "$missing"
    exit 1
fi
echo "check_test_subset: $(names "$part" | wc -l) tests, the same as the full suite selects"
