#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

using KeyTuple = std::tuple<int, int, int>;

// Brute force: group points by floor((p - origin) / alpha) directly.
std::map<KeyTuple, std::vector<Eigen::Vector3d>> group(const std::vector<Eigen::Vector3d>& pts, double alpha, const Eigen::Vector3d& origin) {
    std::map<KeyTuple, std::vector<Eigen::Vector3d>> g;
    for (const auto& p : pts) {
        const Eigen::Vector3d l = p - origin;
        g[{int(std::floor(l.x() / alpha)), int(std::floor(l.y() / alpha)), int(std::floor(l.z() / alpha))}].push_back(l);
    }
    return g;
}

class VoxelGridAt : public ::testing::TestWithParam<double> {};

TEST_P(VoxelGridAt, PerVoxelStatisticsMatchDirectGrouping) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    const Eigen::Vector3d offset(GetParam(), -GetParam(), 0.5 * GetParam());
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 5000; ++i) pts.push_back(offset + Eigen::Vector3d(u(rng), u(rng), 0.2 * u(rng)));
    VoxelGrid grid(0.2);
    for (const auto& p : pts) grid.insert(p);
    // The local origin is a lattice point near the first point.
    EXPECT_LT((grid.origin() - pts[0]).cwiseAbs().maxCoeff(), 0.1 + 1e-9);
    const auto groups = group(pts, 0.2, grid.origin());
    ASSERT_EQ(grid.size(), groups.size());
    EXPECT_EQ(grid.point_count(), pts.size());
    for (const auto& [k, members] : groups) {
        const VoxelStats* s = grid.find({std::get<0>(k), std::get<1>(k), std::get<2>(k)});
        ASSERT_NE(s, nullptr);
        ASSERT_EQ(s->count, members.size());
        const auto d = test::direct_stats(members);
        EXPECT_LT((s->mean - d.mean).norm(), 1e-9);
        EXPECT_LT((s->covariance() - d.cov).cwiseAbs().maxCoeff(), 1e-12);
    }
}

INSTANTIATE_TEST_SUITE_P(NearAndFar, VoxelGridAt, ::testing::Values(0.0, 1e5, 1e6));

TEST(VoxelGrid, BoxQueryMatchesLinearScan) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    VoxelGrid grid(0.25);
    for (int i = 0; i < 3000; ++i) grid.insert({u(rng), u(rng), u(rng)});
    std::uniform_int_distribution<int> c(-14, 14), w(0, 12);
    for (int trial = 0; trial < 50; ++trial) {
        const VoxelKey lo(c(rng), c(rng), c(rng));
        const VoxelKey hi = lo + VoxelKey(w(rng), w(rng), w(rng));
        std::size_t expected_voxels = 0;
        std::uint64_t expected_points = 0;
        for (std::size_t i = 0; i < grid.keys().size(); ++i) {
            const auto& k = grid.keys()[i];
            if ((k.array() >= lo.array()).all() && (k.array() <= hi.array()).all()) {
                ++expected_voxels;
                expected_points += grid.stats()[i].count;
            }
        }
        std::size_t voxels = 0;
        std::uint64_t points = 0;
        grid.for_each_in_box(lo, hi, [&](const VoxelKey&, const VoxelStats& s) { ++voxels; points += s.count; });
        EXPECT_EQ(voxels, expected_voxels);
        EXPECT_EQ(points, expected_points);
    }
}

TEST(VoxelGrid, RejectsBadInput) {
    EXPECT_THROW(VoxelGrid(0.0), InvalidArgument);
    EXPECT_THROW(VoxelGrid(-1.0), InvalidArgument);
    EXPECT_THROW(VoxelGrid(std::nan("")), InvalidArgument);
    VoxelGrid grid(0.2);
    EXPECT_THROW(grid.insert({std::nan(""), 0, 0}), InvalidInput);
    grid.insert({0, 0, 0});
    EXPECT_THROW(grid.insert({1e7, 0, 0}), InvalidInput);  // 5e7 voxels away: beyond the index range
    EXPECT_EQ(grid.point_count(), 1u);
}

}  // namespace
