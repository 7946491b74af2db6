// BlockMap against std::map (the oracle) on random keys, negative ones included; the accessors;
// the grid's occupancy bits against its index; the packed snapshot against the grid.
#include <gtest/gtest.h>

#include <bitset>
#include <cstring>
#include <thread>
#include <map>
#include <random>
#include <tuple>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/core/voxel_grid.hpp"

using namespace lidarsurf;

namespace {
using Tuple = std::tuple<int, int, int>;
Tuple tuple_of(const VoxelKey& k) { return {k.x(), k.y(), k.z()}; }
}  // namespace

// Without a box, and with a dense box holding part of the near blocks (-5..5 per axis), the
// rest and the far blocks in the hash.
class BlockMapBoxed : public ::testing::TestWithParam<bool> {};
INSTANTIATE_TEST_SUITE_P(WithAndWithoutABox, BlockMapBoxed, ::testing::Bool());

TEST_P(BlockMapBoxed, MatchesAnOrderedMapOnRandomKeys) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> near(-40, 40), far(-kMaxLatticeIndex, kMaxLatticeIndex);
    BlockMap<int> map(-1);
    if (GetParam()) map.use_box({VoxelKey(-5, -4, -3), VoxelKey(8, 11, 6)});
    std::map<Tuple, int> oracle;
    BlockMap<int>::WriteAccessor writer(map);
    for (int i = 0; i < 20000; ++i) {
        const bool wide = i % 10 == 0;
        const VoxelKey k = wide ? VoxelKey(far(rng), far(rng), far(rng)) : VoxelKey(near(rng), near(rng), near(rng));
        if (i % 2) map[k] = i; else writer[k] = i;
        oracle[tuple_of(k)] = i;
    }
    BlockMap<int>::Accessor reader(map);
    for (int i = 0; i < 20000; ++i) {
        const VoxelKey k(near(rng), near(rng), near(rng));
        auto it = oracle.find(tuple_of(k));
        const int* slot = map.find(k);
        const int* via_accessor = reader.find(k);
        EXPECT_EQ(slot, via_accessor);
        if (it == oracle.end()) {
            EXPECT_TRUE(slot == nullptr || *slot == -1);
        } else {
            ASSERT_NE(slot, nullptr);
            EXPECT_EQ(*slot, it->second);
        }
    }
    for (const auto& [t, value] : oracle) {
        const VoxelKey k(std::get<0>(t), std::get<1>(t), std::get<2>(t));
        ASSERT_NE(map.find(k), nullptr);
        EXPECT_EQ(*map.find(k), value);
    }
    // Every block's keys map back to that block (also through the writer, whose table of recent
    // blocks holds some of them); key_at inverts block_of/offset_of.
    for (std::size_t b = 0; b < map.block_count(); ++b) {
        const VoxelKey bk = map.block_keys()[b];
        EXPECT_EQ(map.index_of(bk), static_cast<std::int64_t>(b));
        EXPECT_EQ(writer.block_index(bk), b);  // through the writer's recent-block table
        for (int o = 0; o < BlockMap<int>::kVolume; o += 37) {
            const VoxelKey k = BlockMap<int>::key_at(bk, o);
            EXPECT_EQ(BlockMap<int>::block_of(k), bk);
            EXPECT_EQ(BlockMap<int>::offset_of(k), o);
            // last_axes: the axes along which the next key is in another block.
            int next_block_axes = 0;
            for (int a = 0; a < 3; ++a)
                next_block_axes |= (BlockMap<int>::block_of(k + VoxelKey::Unit(a)) != bk) << a;
            EXPECT_EQ(BlockMap<int>::last_axes(k), next_block_axes);
        }
    }
}

// BlockIndex's dense box against a std::map (the oracle), keys in and around the box; the box
// only on an empty index; dense_block_box against the keys' extent.
TEST(BlockIndex, ABoxHoldsItsKeysAndTheHashTheOthers) {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> coord(-12, 12);
    BlockIndex index;
    const BlockBox box{VoxelKey(-6, -3, -2), VoxelKey(9, 7, 4)};
    index.use_box(box);
    EXPECT_TRUE(index.has_box());
    EXPECT_THROW(index.use_box(box), InvalidArgument);
    std::map<Tuple, std::uint32_t> oracle;
    for (std::uint32_t i = 0; i < 3000; ++i) {
        const VoxelKey k(coord(rng), coord(rng), coord(rng));
        const auto [value, added] = index.try_emplace(k, i);
        const auto [it, oracle_added] = oracle.try_emplace(tuple_of(k), i);
        ASSERT_EQ(added, oracle_added);
        ASSERT_EQ(value, it->second);
    }
    std::size_t inside = 0;
    for (int z = -13; z <= 13; ++z)
        for (int y = -13; y <= 13; ++y)
            for (int x = -13; x <= 13; ++x) {
                const auto it = oracle.find({x, y, z});
                ASSERT_EQ(index.find(VoxelKey(x, y, z)), it == oracle.end() ? BlockIndex::kAbsent : it->second);
                inside += it != oracle.end() && (VoxelKey(x, y, z) - box.lo).minCoeff() >= 0 && ((box.size - (VoxelKey(x, y, z) - box.lo)).array() > 0).all();
            }
    EXPECT_GT(inside, 0u);  // the box held some keys, the hash the others
    EXPECT_LT(inside, oracle.size());
    BlockIndex filled;
    filled.try_emplace(VoxelKey(0, 0, 0), 0);
    EXPECT_THROW(filled.use_box(box), InvalidArgument);
    EXPECT_THROW(BlockIndex().use_box({VoxelKey(0, 0, 0), VoxelKey(0, 1, 1)}), InvalidArgument);

    const std::vector<VoxelKey> keys{{3, -2, 0}, {-1, 5, 1}, {0, 0, -4}};
    const std::optional<BlockBox> b = dense_block_box(keys, 2, 360);  // 1,080 cells: 360 per key
    ASSERT_TRUE(b);
    EXPECT_EQ(b->lo, VoxelKey(-3, -4, -6));
    EXPECT_EQ(b->size, VoxelKey(9, 12, 10));  // extent 5, 8, 6 plus 2 on each side
    EXPECT_FALSE(dense_block_box(keys, 2, 359));
    EXPECT_TRUE(dense_block_box(keys, 2, 360, 1080));
    EXPECT_FALSE(dense_block_box(keys, 2, 360, 1079));  // the cap on the cells
    EXPECT_FALSE(dense_block_box({}, 0, 64));
    EXPECT_FALSE(dense_block_box({VoxelKey(-kMaxLatticeIndex / 8, 0, 0), VoxelKey(kMaxLatticeIndex / 8, 0, 0)}, 0, 64));
}

// CornerAccessor (remembers a block per parity of its coordinates) against the map's own lookup:
// the corners of cubes around block corners (eight blocks in turn), blocks of the same parity
// in alternation, absent blocks, and a block created after it found the block absent.
TEST(BlockMap, CornerAccessorFindsWhatTheMapFinds) {
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> near(-24, 24);
    BlockMap<int> map(-1);
    for (int i = 0; i < 3000; ++i) map[VoxelKey(near(rng), near(rng), near(rng))] = i;
    BlockMap<int>::CornerAccessor reader(map);
    std::size_t found = 0, absent = 0;
    for (int i = 0; i < 20000; ++i) {
        // A cube whose base is near a block corner (multiples of 8), or anywhere, or far off.
        const VoxelKey base = i % 3 == 0   ? VoxelKey(8 * (near(rng) / 8) - 1, 8 * (near(rng) / 8) - 1, 8 * (near(rng) / 8) - 1)
                              : i % 3 == 1 ? VoxelKey(near(rng), near(rng), near(rng))
                                           : VoxelKey(near(rng) + 64, near(rng), near(rng));
        for (int c = 0; c < 8; ++c) {
            const VoxelKey k = base + VoxelKey(c & 1, (c >> 1) & 1, c >> 2);
            const int* expected = map.find(k);
            ASSERT_EQ(reader.find(k), expected) << k.transpose();
            (expected ? found : absent) += 1;
        }
    }
    EXPECT_GT(found, 1000u);
    EXPECT_GT(absent, 1000u);
    // Two blocks of the same parity in alternation share an entry: still the right ones.
    map[VoxelKey(0, 0, 0)] = 1;
    map[VoxelKey(16, 0, 0)] = 2;
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(*reader.find(VoxelKey(0, 0, 0)), 1);
        EXPECT_EQ(*reader.find(VoxelKey(16, 0, 0)), 2);
    }
    // Absent, then created: found once it exists.
    const VoxelKey late(200, 200, 200);
    EXPECT_EQ(reader.find(late), nullptr);
    map[late] = 5;
    ASSERT_NE(reader.find(late), nullptr);
    EXPECT_EQ(*reader.find(late), 5);
}

TEST(BlockMap, CornerStepIsTheSlotDistanceToACornerInTheSameBlock) {
    // Every cube base of a block (negative block included) whose corners share its block: corner
    // c's slot is the base's plus corner_step(c), as the map itself finds them.
    BlockMap<int> map(-1);
    for (const VoxelKey& block : {VoxelKey(0, 0, 0), VoxelKey(-2, 1, -1)}) {
        int value = 0;
        for (int z = 0; z < 8; ++z)
            for (int y = 0; y < 8; ++y)
                for (int x = 0; x < 8; ++x) map[block * 8 + VoxelKey(x, y, z)] = value++;
        for (int z = 0; z < 7; ++z)
            for (int y = 0; y < 7; ++y)
                for (int x = 0; x < 7; ++x) {
                    const VoxelKey base = block * 8 + VoxelKey(x, y, z);
                    ASSERT_EQ(BlockMap<int>::last_axes(base), 0);
                    const int* slot = map.find(base);
                    for (int c = 0; c < 8; ++c)
                        EXPECT_EQ(slot + BlockMap<int>::corner_step(c), map.find(base + VoxelKey(c & 1, (c >> 1) & 1, c >> 2))) << c;
                }
    }
}

TEST(BlockMap, SlotsStayValidWhileBlocksAreAdded) {
    BlockMap<int> map(0);
    int& first = map[{0, 0, 0}];
    first = 42;
    for (int i = 1; i < 5000; ++i) map[{8 * i, -8 * i, 3 * i}] = i;  // thousands of new blocks, index rehashed
    EXPECT_EQ(first, 42);
    EXPECT_EQ(&first, map.find({0, 0, 0}));
}

// Blocks created unfilled (the seeded search creates them serially and fills them in parallel):
// the same creation indices and keys as block_index(), a second request finds the block without
// creating it, and once filled every slot holds the empty value.
TEST(BlockMap, UnfilledBlocksAreFilledWithTheEmptyValue) {
    BlockMap<std::int32_t> lazy(-7), eager(-7);
    const std::vector<VoxelKey> blocks{{0, 0, 0}, {-3, 2, 9}, {0, 0, 0}, {5, -5, 1}, {-3, 2, 9}};
    std::vector<std::uint32_t> created;
    for (const VoxelKey& b : blocks) {
        const auto [index, added] = lazy.block_index_unfilled(b);
        ASSERT_EQ(index, eager.block_index(b));
        if (added) created.push_back(index);
    }
    ASSERT_EQ(created.size(), 3u);  // three distinct keys
    EXPECT_EQ(lazy.block_keys(), eager.block_keys());
    for (std::uint32_t i : created) lazy.fill_block(i);
    for (std::size_t i = 0; i < lazy.block_count(); ++i)
        for (std::int32_t v : lazy.block_at(i)) ASSERT_EQ(v, -7) << i;
    lazy[VoxelKey(1, 2, 3)] = 4;  // and the map works as usual
    EXPECT_EQ(*lazy.find(VoxelKey(1, 2, 3)), 4);
    EXPECT_EQ(*lazy.find(VoxelKey(0, 2, 3)), -7);
}

TEST(VoxelGrid, OccupancyBitsMatchTheIndex) {
    // The oracle: a map from each inserted point's key to the statistics of its points, built here.
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    const double alpha = 0.2;
    VoxelGrid grid(alpha, Eigen::Vector3d::Zero());
    std::map<std::array<int, 3>, std::size_t> points_of;
    for (int i = 0; i < 3000; ++i) {
        const Eigen::Vector3d p{u(rng), u(rng), 0.2 * u(rng)};
        grid.insert(p);
        ++points_of[{static_cast<int>(std::floor(p.x() / alpha)), static_cast<int>(std::floor(p.y() / alpha)),
                     static_cast<int>(std::floor(p.z() / alpha))}];
    }
    ASSERT_EQ(grid.size(), points_of.size());
    std::size_t occupied = 0;
    for (std::size_t b = 0; b < grid.index().block_count(); ++b) {
        const auto& occ = grid.occupancy(b);
        const VoxelKey block = grid.index().block_keys()[b];
        std::vector<std::int32_t> in_bit_order;
        for (int o = 0; o < BlockMap<std::int32_t>::kVolume; ++o) {
            const VoxelKey key = BlockMap<std::int32_t>::key_at(block, o);
            const bool bit = (occ[static_cast<std::size_t>(o >> 6)] >> (o & 63)) & 1u;
            const auto it = points_of.find({key.x(), key.y(), key.z()});
            EXPECT_EQ(bit, it != points_of.end()) << "block " << b << " offset " << o;
            const std::int32_t v = grid.voxel_at(key);
            EXPECT_EQ(bit, v >= 0) << "block " << b << " offset " << o;
            if (!bit) continue;
            ++occupied;
            in_bit_order.push_back(v);
            ASSERT_LT(static_cast<std::size_t>(v), grid.size());
            EXPECT_TRUE(same_key(grid.keys()[static_cast<std::size_t>(v)], key));
            EXPECT_EQ(grid.stats()[static_cast<std::size_t>(v)].count, it->second);
        }
        const auto listed = grid.block_voxels(b);
        EXPECT_EQ(std::vector<std::int32_t>(listed.begin(), listed.end()), in_bit_order) << "block " << b;
    }
    EXPECT_EQ(occupied, grid.size());
}

// The packed snapshot against the grid (the oracle): every occupied voxel's record, found by its
// rank in the occupancy bits, holds that voxel's statistics; absent blocks are nullptr.
TEST(PackedVoxels, EveryVoxelIsFoundByRankWithItsStatistics) {
    std::mt19937 rng(9);
    std::normal_distribution<double> g(0.0, 1.5);
    VoxelGrid grid(0.2);
    for (int i = 0; i < 20000; ++i) grid.insert(Eigen::Vector3d(g(rng), g(rng), 0.5 * g(rng)));
    const PackedVoxels packed(grid);
    for (std::size_t v = 0; v < grid.size(); ++v) {
        const VoxelKey key = grid.keys()[v];
        const PackedVoxels::Block* block = packed.find(BlockMap<std::int32_t>::block_of(key));
        ASSERT_NE(block, nullptr);
        const int offset = BlockMap<std::int32_t>::offset_of(key);
        const PackedVoxels::Voxel& r = block->at(offset);
        ASSERT_EQ(&block->at_layer_bit(offset >> 6, offset & 63), &r);  // the popcount rank: the same record
        const VoxelStats& s = grid.stats()[v];
        ASSERT_EQ(r.count, static_cast<double>(s.count));
        ASSERT_EQ(Eigen::Vector3d(r.mx, r.my, r.mz), s.mean);
        ASSERT_EQ((SymmetricMatrix3{r.xx, r.xy, r.xz, r.yy, r.yz, r.zz}), s.scatter);
    }
    EXPECT_EQ(packed.find(VoxelKey(1000, 1000, 1000)), nullptr);
    for (int i = 0; i < 256; ++i) EXPECT_EQ(PackedVoxels::kBitCount[static_cast<std::size_t>(i)], std::bitset<8>(static_cast<unsigned>(i)).count());
}

// find() of the dense table (a compact frame) and of the hash fallback (two clusters far apart)
// against the grid's hash index (the oracle), on every block key of the blocks' box and a margin
// around it: the same block (its occupancy words) or nullptr.
TEST(PackedVoxels, FindsEveryBlockKeyAsTheGridsIndexWithOrWithoutTheDenseTable) {
    std::mt19937 rng(13);
    std::normal_distribution<double> g(0.0, 3.0);
    for (const bool far_cluster : {false, true}) {
        VoxelGrid grid(0.2);
        for (int i = 0; i < 20000; ++i) grid.insert(Eigen::Vector3d(g(rng), g(rng), -1.0 + 0.3 * g(rng)));
        if (far_cluster)  // 10 km away: the box would hold millions of cells per block
            for (int i = 0; i < 100; ++i) grid.insert(Eigen::Vector3d(1e4 + g(rng), -1e4 + g(rng), 0.3 * g(rng)));
        const PackedVoxels packed(grid);
        EXPECT_EQ(packed.dense(), !far_cluster);
        // The near cluster's blocks' box (blocks are 1.6 m: the far ones have |x| > 6000).
        std::size_t near = 0;
        VoxelKey lo = VoxelKey::Constant(1 << 20), hi = VoxelKey::Constant(-(1 << 20));
        for (const VoxelKey& k : grid.index().block_keys())
            if (std::abs(k.x()) < 1000) lo = lo.cwiseMin(k), hi = hi.cwiseMax(k), ++near;
        std::size_t found = 0;
        for (int z = lo.z() - 2; z <= hi.z() + 2; ++z)
            for (int y = lo.y() - 2; y <= hi.y() + 2; ++y)
                for (int x = lo.x() - 2; x <= hi.x() + 2; ++x) {
                    const VoxelKey key(x, y, z);
                    const std::int64_t b = grid.index().index_of(key);
                    const PackedVoxels::Block* block = packed.find(key);
                    if (b < 0) {
                        ASSERT_EQ(block, nullptr) << x << " " << y << " " << z;
                    } else {
                        ASSERT_NE(block, nullptr) << x << " " << y << " " << z;
                        ASSERT_EQ(block->occupancy, &grid.occupancy(static_cast<std::size_t>(b)));
                        ++found;
                    }
                }
        EXPECT_EQ(found, near);  // every near block was found
        EXPECT_EQ(packed.find(VoxelKey(kMaxLatticeIndex >> 3, -(kMaxLatticeIndex >> 3), 0)), nullptr);
    }
}

// A snapshot with some blocks packed up front: the others are packed when first found, with
// the same records as the full snapshot's, also when two threads find them at once; absent
// blocks stay nullptr.
TEST(PackedVoxels, BlocksLeftForLaterArePackedWhenFirstFound) {
    std::mt19937 rng(10);
    std::normal_distribution<double> g(0.0, 3.0);
    VoxelGrid grid(0.2);
    for (int i = 0; i < 20000; ++i) grid.insert(Eigen::Vector3d(g(rng), g(rng), 0.5 * g(rng)));
    const std::size_t blocks = grid.index().block_count();
    ASSERT_GT(blocks, 4u);
    std::vector<std::uint8_t> eager(blocks, 0);
    std::size_t eager_count = 0;
    for (std::size_t b = 0; b < blocks; b += 2, ++eager_count) eager[b] = 1;
    const PackedVoxels full(grid), some(grid, &eager);
    EXPECT_EQ(full.packed_blocks(), blocks);
    EXPECT_EQ(some.packed_blocks(), eager_count);
    auto check = [&] {
        for (std::size_t v = 0; v < grid.size(); ++v) {
            const VoxelKey key = grid.keys()[v];
            const VoxelKey block = BlockMap<std::int32_t>::block_of(key);
            const int offset = BlockMap<std::int32_t>::offset_of(key);
            const PackedVoxels::Voxel &r = some.find(block)->at(offset), &f = full.find(block)->at(offset);
            ASSERT_EQ(std::memcmp(&r, &f, sizeof r), 0) << v;
        }
    };
    std::thread other(check);
    check();
    other.join();
    EXPECT_EQ(some.packed_blocks(), blocks);
    EXPECT_EQ(some.find(VoxelKey(1000, 1000, 1000)), nullptr);
    std::vector<std::uint8_t> wrong(blocks + 1, 1);
    EXPECT_THROW(PackedVoxels(grid, &wrong), InvalidArgument);
}
