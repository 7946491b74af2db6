// Which blocks a live mesh re-meshes (map/block_changes.hpp), on hand-made grids: the reach of a
// change, the growth threshold, removals, and the cells that keep a long drive's old blocks out
// of each update.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <tuple>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/map/block_changes.hpp"

using namespace lidarsurf;

namespace {

using KeyTuple = std::tuple<int, int, int>;
std::set<KeyTuple> as_set(const std::vector<BlockChanges::Due>& due) {
    std::set<KeyTuple> s;
    for (const BlockChanges::Due& d : due) s.insert({d.key.x(), d.key.y(), d.key.z()});
    return s;
}
// `n` points in voxel `v` (alpha 0.2, origin at 0: the first point is at the voxel's centre).
void add(VoxelGrid& grid, const VoxelKey& v, int n) {
    std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(n), (v.cast<double>() + Eigen::Vector3d::Constant(0.5)) * 0.2);
    grid.insert(points);
}
std::set<KeyTuple> due(BlockChanges& c) { return as_set(c.due_near(Eigen::Vector3d::Zero(), 0.2, 1e3)); }

}  // namespace

TEST(BlockChanges, AChangeMakesTheBlocksWithinReachDueOnce) {
    VoxelGrid grid(0.2, Eigen::Vector3d::Zero());
    grid.track_changes();
    BlockChanges changes(0.5, 1);
    add(grid, {3, 3, 3}, 10);  // block (0, 0, 0)
    changes.record(grid, grid.take_changes());
    std::set<KeyTuple> expected;
    for (int z = -1; z <= 1; ++z)
        for (int y = -1; y <= 1; ++y)
            for (int x = -1; x <= 1; ++x) expected.insert({x, y, z});
    EXPECT_EQ(due(changes), expected);
    EXPECT_EQ(changes.due_count(), 27u);
    // Recorded again before meshing: still due once.
    add(grid, {4, 3, 3}, 10);
    changes.record(grid, grid.take_changes());
    EXPECT_EQ(changes.due_count(), 27u);
    EXPECT_EQ(due(changes).size(), 27u);
    for (const auto& [x, y, z] : expected) changes.mark_meshed(grid, {x, y, z});
    EXPECT_EQ(changes.due_count(), 0u);
    EXPECT_TRUE(due(changes).empty());
    EXPECT_EQ(changes.points_near(grid, {0, 0, 0}), 20u);
    EXPECT_EQ(changes.points_near(grid, {2, 0, 0}), 0u);
}

TEST(BlockChanges, PointsMakeABlockDueOnlyPastTheGrowthButARemovalAlways) {
    VoxelGrid grid(0.2, Eigen::Vector3d::Zero());
    grid.track_changes();
    BlockChanges changes(0.5, 0);
    add(grid, {1, 1, 1}, 20);
    changes.record(grid, grid.take_changes());
    changes.mark_meshed(grid, {0, 0, 0});
    add(grid, {1, 1, 1}, 10);  // +50 %: not past it
    changes.record(grid, grid.take_changes());
    EXPECT_TRUE(due(changes).empty());
    add(grid, {2, 1, 1}, 1);  // 11 new on 20: past it
    changes.record(grid, grid.take_changes());
    EXPECT_EQ(due(changes), (std::set<KeyTuple>{{0, 0, 0}}));
    EXPECT_FALSE(changes.due_near(Eigen::Vector3d::Zero(), 0.2, 1e3).at(0).urgent) << "grown, meshed before";
    changes.mark_meshed(grid, {0, 0, 0});
    EXPECT_EQ(changes.points_near(grid, {0, 0, 0}), 31u);
    // One voxel removed: due at once, and its points are gone from the count.
    grid.remove(static_cast<std::size_t>(grid.find({2, 1, 1}) - grid.stats().data()));
    changes.record(grid, grid.take_changes());
    EXPECT_EQ(due(changes), (std::set<KeyTuple>{{0, 0, 0}}));
    EXPECT_TRUE(changes.due_near(Eigen::Vector3d::Zero(), 0.2, 1e3).at(0).urgent) << "a voxel removed near it";
    changes.mark_meshed(grid, {0, 0, 0});
    EXPECT_EQ(changes.points_near(grid, {0, 0, 0}), 30u);
    EXPECT_THROW(BlockChanges(-1, 1), InvalidArgument);
}

TEST(BlockChanges, OnlyTheDueBlocksWithinTheRadiusAreRead) {
    VoxelGrid grid(0.2, Eigen::Vector3d::Zero());
    grid.track_changes();
    BlockChanges changes(0.25, 0);
    // Blocks every 8 blocks (12.8 m) along x: one per cell.
    for (int i = 0; i < 10; ++i) add(grid, {64 * i, 0, 0}, 5);
    changes.record(grid, grid.take_changes());
    EXPECT_EQ(changes.due_count(), 10u);
    // Block b's centre is at 1.6 b + 0.8 m (0.8 m off the axis): within 30 m of x = 60 m, the
    // blocks at 39.2, 52, 64.8 and 77.6 m (26.4 and 90.4 m are not).
    const std::vector<BlockChanges::Due> due = changes.due_near(Eigen::Vector3d(60, 0, 0), 0.2, 30);
    EXPECT_EQ(as_set(due), (std::set<KeyTuple>{{24, 0, 0}, {32, 0, 0}, {40, 0, 0}, {48, 0, 0}}));
    for (const BlockChanges::Due& d : due) {
        const double dx = 1.6 * d.key.x() + 0.8 - 60;
        EXPECT_NEAR(d.distance2, dx * dx + 2 * 0.8 * 0.8, 1e-9);
        EXPECT_TRUE(d.urgent) << "never meshed";
    }
}

// Carving removes a voxel: its own block is due at once (urgent); the blocks around it count the
// removed points as a change, due only past the growth like inserted points.
TEST(BlockChanges, ARemovalMakesItsOwnBlockUrgentAndCountsAsAChangeAroundIt) {
    VoxelGrid grid(0.2, Eigen::Vector3d::Zero());
    grid.track_changes();
    BlockChanges changes(0.5, 1);
    add(grid, {3, 3, 3}, 40);   // block (0, 0, 0)
    add(grid, {11, 3, 3}, 60);  // block (1, 0, 0)
    add(grid, {4, 3, 3}, 4);    // block (0, 0, 0), to be carved
    changes.record(grid, grid.take_changes());
    for (int z = -1; z <= 1; ++z)
        for (int y = -1; y <= 1; ++y)
            for (int x = -1; x <= 2; ++x) changes.mark_meshed(grid, {x, y, z});
    ASSERT_EQ(changes.due_count(), 0u);
    // 4 of the 104 points within reach of blocks (0, *, *) and (1, *, *), 4 of the 44 of blocks
    // (-1, *, *): under 50 %.
    grid.remove(static_cast<std::size_t>(grid.find({4, 3, 3}) - grid.stats().data()));
    changes.record(grid, grid.take_changes());
    const std::vector<BlockChanges::Due> carved = changes.due_near(Eigen::Vector3d::Zero(), 0.2, 1e3);
    ASSERT_EQ(as_set(carved), (std::set<KeyTuple>{{0, 0, 0}}));
    EXPECT_TRUE(carved[0].urgent);
    changes.mark_meshed(grid, {0, 0, 0});
    // The voxel of block (1, 0, 0) carved: 60 points, past 50 % of the 100 within reach of block
    // (0, 0, 0), of the 104 of the other blocks (0..1, *, *) (64 changed with the first removal) and of
    // the 60 of blocks (2, *, *): due around it, urgent only itself.
    grid.remove(static_cast<std::size_t>(grid.find({11, 3, 3}) - grid.stats().data()));
    changes.record(grid, grid.take_changes());
    std::set<KeyTuple> around;
    for (int z = -1; z <= 1; ++z)
        for (int y = -1; y <= 1; ++y)
            for (int x = 0; x <= 2; ++x) around.insert({x, y, z});
    EXPECT_EQ(due(changes), around);
    for (const BlockChanges::Due& d : changes.due_near(Eigen::Vector3d::Zero(), 0.2, 1e3))
        EXPECT_EQ(d.urgent, d.key == VoxelKey(1, 0, 0)) << d.key.transpose();
}
