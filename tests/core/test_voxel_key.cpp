// sort_zyx against std::sort with the (z, y, x) comparison: keys within the packed range, and keys
// a few steps beyond +-kMaxLatticeIndex (vertices next to the outermost voxels).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "lidarsurf/core/voxel_key.hpp"

using namespace lidarsurf;

namespace {

bool zyx_less(const VoxelKey& a, const VoxelKey& b) {
    if (a.z() != b.z()) return a.z() < b.z();
    if (a.y() != b.y()) return a.y() < b.y();
    return a.x() < b.x();
}

std::vector<VoxelKey> random_keys(std::size_t n, int lo, int hi, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> c(lo, hi), small(-3, 3);
    std::vector<VoxelKey> keys;
    for (std::size_t i = 0; i < n; ++i) keys.emplace_back(c(rng), small(rng), i % 3 ? small(rng) : c(rng));  // many ties in y and z
    return keys;
}

}  // namespace

TEST(VoxelKey, SortZyxIsTheLexicographicOrder) {
    const int reach = kMaxLatticeIndex + 40;  // beyond the 21-bit packing: the comparison fallback
    for (auto [lo, hi] : {std::pair{-50, 50}, std::pair{-kMaxLatticeIndex, kMaxLatticeIndex}, std::pair{-reach, reach}}) {
        std::vector<VoxelKey> keys = random_keys(50000, lo, hi, static_cast<unsigned>(hi));
        keys.push_back(VoxelKey(lo, lo, lo));
        keys.push_back(VoxelKey(hi, hi, hi));
        std::vector<VoxelKey> expected = keys;
        std::sort(expected.begin(), expected.end(), zyx_less);
        sort_zyx(keys);
        ASSERT_EQ(keys.size(), expected.size());
        for (std::size_t i = 0; i < keys.size(); ++i) ASSERT_EQ(keys[i], expected[i]) << "range " << hi << ", position " << i;
    }
    // Keys that vary along one axis only (no bits for the others), and all equal.
    for (int axis = 0; axis < 3; ++axis) {
        std::mt19937 rng(static_cast<unsigned>(axis));
        std::uniform_int_distribution<int> c(-kMaxLatticeIndex, kMaxLatticeIndex);
        std::vector<VoxelKey> keys(3000, VoxelKey(7, -9, 11));
        for (VoxelKey& k : keys) k[axis] = c(rng);
        std::vector<VoxelKey> expected = keys;
        std::sort(expected.begin(), expected.end(), zyx_less);
        sort_zyx(keys);
        EXPECT_EQ(keys, expected) << "axis " << axis;
    }
    std::vector<VoxelKey> same(100, VoxelKey(-3, 4, -5));
    sort_zyx(same);
    EXPECT_EQ(same, std::vector<VoxelKey>(100, VoxelKey(-3, 4, -5)));
    std::vector<VoxelKey> none;
    sort_zyx(none);
    EXPECT_TRUE(none.empty());
}

// same_key against the coordinate-by-coordinate comparison, on keys that differ in one, two or
// three coordinates (by small and by sign-crossing amounts) and on equal ones.
TEST(VoxelKey, SameKeyIsCoordinateWiseEquality) {
    const std::vector<VoxelKey> keys = random_keys(400, -kMaxLatticeIndex, kMaxLatticeIndex, 7);
    for (const VoxelKey& a : keys) {
        EXPECT_TRUE(same_key(a, a));
        for (int bits = 1; bits < 8; ++bits)
            for (int delta : {1, -1, 1 << 20, -(1 << 30)}) {
                VoxelKey b = a;
                for (int axis = 0; axis < 3; ++axis)
                    if ((bits >> axis) & 1) b[axis] += delta;
                EXPECT_EQ(same_key(a, b), a.x() == b.x() && a.y() == b.y() && a.z() == b.z()) << a.transpose() << " / " << b.transpose();
            }
    }
}
