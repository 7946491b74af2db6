// radix_sort against std::stable_sort: the same order, equal keys kept in input order, for key
// widths that need one, several and a partial last digit.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <utility>

#include "lidarsurf/core/radix_sort.hpp"

using namespace lidarsurf;

TEST(RadixSort, IsAStableSortByKey) {
    for (int bits : {1, 11, 12, 30, 64}) {
        std::mt19937_64 rng(static_cast<unsigned>(bits));
        const std::uint64_t mask = bits == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
        std::vector<std::pair<std::uint64_t, int>> items;  // (key, input position)
        for (int i = 0; i < 20000; ++i) items.emplace_back(rng() & mask & (i % 4 ? ~std::uint64_t{0} : std::uint64_t{0x7}), i);  // many ties
        std::vector<std::pair<std::uint64_t, int>> expected = items, scratch;
        std::stable_sort(expected.begin(), expected.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        radix_sort(items, scratch, bits, [](const std::pair<std::uint64_t, int>& p) { return p.first; });
        EXPECT_EQ(items, expected) << bits << " bits";
    }
    std::vector<int> none, scratch;
    radix_sort(none, scratch, 8, [](int v) { return static_cast<unsigned>(v); });
    EXPECT_TRUE(none.empty());
}
