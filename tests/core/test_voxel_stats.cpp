#include <gtest/gtest.h>

#include <random>

#include "lidarsurf/core/voxel_stats.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

std::vector<Eigen::Vector3d> random_cloud(std::mt19937& rng, int n, const Eigen::Vector3d& centre, double spread) {
    std::normal_distribution<double> g(0.0, spread);
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < n; ++i) pts.push_back(centre + Eigen::Vector3d(g(rng), 0.5 * g(rng), 0.1 * g(rng)));
    return pts;
}

class VoxelStatsAt : public ::testing::TestWithParam<double> {};

TEST_P(VoxelStatsAt, IncrementalMatchesTwoPass) {
    std::mt19937 rng(7);
    const Eigen::Vector3d centre = Eigen::Vector3d::Constant(GetParam());
    const auto pts = random_cloud(rng, 500, centre, 0.1);
    VoxelStats s;
    for (const auto& p : pts) s.add(p);
    const auto d = test::direct_stats(pts);
    EXPECT_EQ(s.count, 500u);
    EXPECT_LT((s.mean - d.mean).norm(), 1e-12 * std::max(1.0, GetParam()) + 1e-12);
    // Covariance entries are ~1e-2..1e-4: absolute accuracy must not degrade with the offset.
    EXPECT_LT((s.covariance() - d.cov).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_P(VoxelStatsAt, MergeOfRandomPartsMatchesTwoPass) {
    std::mt19937 rng(11);
    const Eigen::Vector3d centre = Eigen::Vector3d::Constant(GetParam());
    const auto pts = random_cloud(rng, 1000, centre, 0.3);
    std::uniform_int_distribution<int> part(0, 6);
    std::vector<VoxelStats> parts(7);
    for (const auto& p : pts) parts[static_cast<std::size_t>(part(rng))].add(p);
    VoxelStats merged;
    for (const auto& s : parts) merged.merge(s);
    const auto d = test::direct_stats(pts);
    EXPECT_EQ(merged.count, 1000u);
    EXPECT_LT((merged.mean - d.mean).norm(), 1e-11 * std::max(1.0, GetParam()) + 1e-12);
    EXPECT_LT((merged.covariance() - d.cov).cwiseAbs().maxCoeff(), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(NearAndFar, VoxelStatsAt, ::testing::Values(0.0, 1e3, 1e5, 1e6));

TEST(VoxelStats, MergeWithEmptyIsIdentity) {
    VoxelStats a, empty;
    a.add({1, 2, 3});
    a.add({2, 2, 3});
    VoxelStats b = a;
    b.merge(empty);
    EXPECT_EQ(b.count, a.count);
    EXPECT_EQ(b.mean, a.mean);
    empty.merge(a);
    EXPECT_EQ(empty.scatter, a.scatter);
    EXPECT_EQ(VoxelStats{}.covariance(), Eigen::Matrix3d::Zero());
}

}  // namespace
