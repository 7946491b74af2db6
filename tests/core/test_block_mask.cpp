// Block masks: the dilated occupancy of each block against a brute-force oracle (every lattice
// point of the block tested against every occupied voxel), and the candidate blocks covering
// every non-empty mask.
#include <gtest/gtest.h>

#include <random>
#include <set>
#include <tuple>

#include "lidarsurf/core/block_mask.hpp"

using namespace lidarsurf;

namespace {
using Tuple = std::tuple<int, int, int>;

bool brute_force(const VoxelGrid& grid, const VoxelKey& p, int lo, int hi) {
    for (const VoxelKey& i : grid.keys())
        if ((p.array() >= i.array() + lo).all() && (p.array() <= i.array() + hi).all()) return true;
    return false;
}
}  // namespace

TEST(BlockMask, LayerMaskSetsTheRectangle) {
    const std::uint64_t m = layer_mask(2, 4, 1, 6);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            EXPECT_EQ((m >> (x + 8 * y)) & 1u, (x >= 2 && x <= 4 && y >= 1 && y <= 6) ? 1u : 0u) << x << "," << y;
    EXPECT_EQ(layer_mask(0, 7, 0, 7), ~std::uint64_t{0});
}

TEST(BlockMask, DilatedOccupancyMatchesBruteForce) {
    // Sparse random voxels around the origin, negative keys and block borders included.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-2.2, 2.2);
    VoxelGrid grid(0.2, Eigen::Vector3d::Zero());
    for (int i = 0; i < 40; ++i) grid.insert(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    for (const auto& [lo, hi] : std::vector<std::pair<int, int>>{{0, 0}, {0, 1}, {-1, 2}, {-3, 3}, {-9, 9}}) {
        const std::vector<VoxelKey> blocks = blocks_near_occupancy(grid, lo, hi);
        std::set<Tuple> listed;
        for (const VoxelKey& b : blocks) EXPECT_TRUE(listed.insert({b.x(), b.y(), b.z()}).second) << "listed twice";
        // Every block that can hold a dilated point, and one more on each side.
        VoxelKey kmin = grid.keys()[0], kmax = kmin;
        for (const VoxelKey& k : grid.keys()) kmin = kmin.cwiseMin(k), kmax = kmax.cwiseMax(k);
        const VoxelKey blo = BlockMap<int>::block_of(kmin.array() + lo).array() - 1;
        const VoxelKey bhi = BlockMap<int>::block_of(kmax.array() + hi).array() + 1;
        int marked = 0;
        for (int bz = blo.z(); bz <= bhi.z(); ++bz)
            for (int by = blo.y(); by <= bhi.y(); ++by)
                for (int bx = blo.x(); bx <= bhi.x(); ++bx) {
                    const VoxelKey b(bx, by, bz);
                    const BlockMask mask = dilated_occupancy(grid, b, lo, hi);
                    if (popcount(mask) > 0) {
                        EXPECT_TRUE(listed.count({bx, by, bz})) << "block with points not listed, box " << lo << ".." << hi;
                    }
                    for (int offset = 0; offset < 512; ++offset) {
                        const VoxelKey p = BlockMap<int>::key_at(b, offset);
                        const bool bit = (mask[static_cast<std::size_t>(offset >> 6)] >> (offset & 63)) & 1u;
                        ASSERT_EQ(bit, brute_force(grid, p, lo, hi)) << "point " << p.transpose() << " box " << lo << ".." << hi;
                        marked += bit;
                    }
                }
        EXPECT_GE(marked, static_cast<int>(grid.size()) * (hi - lo + 1)) << "box " << lo << ".." << hi;
        // The whole dilation: exactly the non-empty blocks, with the same masks.
        const std::vector<MaskedBlock> all = dilated_occupancy(grid, lo, hi);
        int points = 0;
        for (const MaskedBlock& b : all) {
            EXPECT_GT(popcount(b.mask), 0);
            EXPECT_EQ(b.mask, dilated_occupancy(grid, b.block, lo, hi));
            points += popcount(b.mask);
        }
        EXPECT_EQ(points, marked) << "box " << lo << ".." << hi;
    }
}

TEST(BlockMask, ForEachBitVisitsTheSetOffsetsInOrder) {
    BlockMask mask{};
    const std::vector<int> offsets = {0, 7, 63, 64, 200, 511};
    for (int o : offsets) mask[static_cast<std::size_t>(o >> 6)] |= std::uint64_t{1} << (o & 63);
    std::vector<int> seen;
    for_each_bit(mask, [&](int o) { seen.push_back(o); });
    EXPECT_EQ(seen, offsets);
    EXPECT_EQ(popcount(mask), 6);
}
