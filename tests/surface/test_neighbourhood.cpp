#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

// Oracle: the points whose voxel index lies in [v-k, v+k-1]^3, selected one by one.
std::vector<Eigen::Vector3d> points_in_h(const std::vector<Eigen::Vector3d>& local_pts, double alpha, const VoxelKey& v, int k) {
    std::vector<Eigen::Vector3d> out;
    for (const auto& p : local_pts) {
        bool inside = true;
        for (int a = 0; a < 3; ++a) {
            const int i = static_cast<int>(std::floor(p[a] / alpha));
            inside = inside && i >= v[a] - k && i <= v[a] + k - 1;
        }
        if (inside) out.push_back(p);
    }
    return out;
}

TEST(Neighbourhood, MergedStatisticsMatchDirectComputation) {
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    const double alpha = 0.2;
    VoxelGrid grid(alpha);
    std::vector<Eigen::Vector3d> pts;
    const Eigen::Vector3d offset(4e5, 5e6, 30.0);  // UTM-like coordinates
    for (int i = 0; i < 4000; ++i) pts.push_back(offset + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng)));
    for (const auto& p : pts) grid.insert(p);
    std::vector<Eigen::Vector3d> local;
    for (const auto& p : pts) local.push_back(grid.to_local(p));
    std::uniform_int_distribution<int> c(-6, 6);
    for (int trial = 0; trial < 30; ++trial) {
        const VoxelKey v(c(rng), c(rng), c(rng) / 3);
        VoxelStats grown;
        for (int k = 1; k <= 5; ++k) {
            const auto members = points_in_h(local, alpha, v, k);
            const VoxelStats merged = merge_neighbourhood(grid, v, k);
            grow_neighbourhood(grid, v, k, grown);
            ASSERT_EQ(merged.count, members.size()) << "k=" << k;
            ASSERT_EQ(grown.count, members.size()) << "k=" << k;
            if (members.empty()) continue;
            const auto d = test::direct_stats(members);
            EXPECT_LT((merged.mean - d.mean).norm(), 1e-9);
            EXPECT_LT((merged.covariance() - d.cov).cwiseAbs().maxCoeff(), 1e-10);
            EXPECT_LT((grown.mean - d.mean).norm(), 1e-9);
            EXPECT_LT((grown.covariance() - d.cov).cwiseAbs().maxCoeff(), 1e-10);
        }
    }
}

// The slab S^k(v) (slab fallback): the points whose voxel index is in [v-k, v+k-1] along x and y
// and in [v_z - 1, v_z] along z, selected one by one, against merge_box(slab_box).
TEST(Neighbourhood, SlabIsTheCubeCutToTheTwoLayersBesideTheVertex) {
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    const double alpha = 0.2;
    VoxelGrid grid(alpha, Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 4000; ++i) pts.push_back(Eigen::Vector3d(u(rng), u(rng), 0.5 * u(rng)));
    for (const auto& p : pts) grid.insert(p);
    std::uniform_int_distribution<int> c(-6, 6);
    for (int trial = 0; trial < 30; ++trial) {
        const VoxelKey v(c(rng), c(rng), c(rng) / 2);
        for (int k = 1; k <= 5; ++k) {
            const VoxelBox box = slab_box(v, k);
            EXPECT_EQ(box.lo, VoxelKey(v.x() - k, v.y() - k, v.z() - 1));
            EXPECT_EQ(box.hi, VoxelKey(v.x() + k - 1, v.y() + k - 1, v.z()));
            std::vector<Eigen::Vector3d> members;
            for (const auto& p : pts) {
                const int x = static_cast<int>(std::floor(p.x() / alpha)), y = static_cast<int>(std::floor(p.y() / alpha)),
                          z = static_cast<int>(std::floor(p.z() / alpha));
                if (x >= v.x() - k && x < v.x() + k && y >= v.y() - k && y < v.y() + k && (z == v.z() - 1 || z == v.z())) members.push_back(p);
            }
            const VoxelStats merged = merge_box(grid, box);
            ASSERT_EQ(merged.count, members.size()) << "k=" << k;
            if (members.empty()) continue;
            const auto d = test::direct_stats(members);
            EXPECT_LT((merged.mean - d.mean).norm(), 1e-9);
            EXPECT_LT((merged.covariance() - d.cov).cwiseAbs().maxCoeff(), 1e-10);
        }
    }
    EXPECT_THROW(slab_box(VoxelKey::Zero(), 0), InvalidArgument);
}

TEST(Neighbourhood, RadialSlabExtendsAlongTheAxisAwayFromTheSensor) {
    const VoxelKey v(4, -2, 1);
    const VoxelBox square = slab_box(v, 3), along_x = slab_box(v, 3, {2, 0}), along_y = slab_box(v, 3, {0, 2});
    EXPECT_EQ(along_x.lo, VoxelKey(square.lo.x() - 2, square.lo.y(), square.lo.z()));
    EXPECT_EQ(along_x.hi, VoxelKey(square.hi.x() + 2, square.hi.y(), square.hi.z()));
    EXPECT_EQ(along_y.lo, VoxelKey(square.lo.x(), square.lo.y() - 2, square.lo.z()));
    EXPECT_EQ(along_y.hi, VoxelKey(square.hi.x(), square.hi.y() + 2, square.hi.z()));
    EXPECT_THROW(slab_box(v, 3, {-1, 0}), InvalidArgument);
    // The axis on which the vertex is further from the sensor; x on a tie; z plays no part.
    const Eigen::Vector3d sensor(1.0, 2.0, 1.7);
    auto ext = [&](double x, double y, double z) { return radial_extension(Eigen::Vector3d(x, y, z), sensor, 3); };
    EXPECT_EQ(ext(11.0, 3.0, 0.0).x, 3);
    EXPECT_EQ(ext(11.0, 3.0, 0.0).y, 0);
    EXPECT_EQ(ext(-9.0, 5.0, -1.7).x, 3);
    EXPECT_EQ(ext(2.0, -18.0, 0.0).y, 3);
    EXPECT_EQ(ext(2.0, -18.0, 0.0).x, 0);
    EXPECT_EQ(ext(4.0, 5.0, 30.0).x, 3);  // |dx| = |dy| = 3
    EXPECT_EQ(ext(4.0, 5.0, 30.0).y, 0);
    EXPECT_EQ(radial_extension(Eigen::Vector3d(9, 0, 0), sensor, 0).x, 0);
}

TEST(Neighbourhood, LevelOneIsTheEightAdjacentVoxels) {
    VoxelGrid g(1.0);
    // Put one point at the centre of every voxel of a 4x4x4 block around vertex (0,0,0).
    g.insert({0.0, 0.0, 0.0});  // origin (0,0,0); this point lands in voxel (0,0,0)
    for (int z = -2; z < 2; ++z)
        for (int y = -2; y < 2; ++y)
            for (int x = -2; x < 2; ++x) g.insert({x + 0.5, y + 0.5, z + 0.5});
    EXPECT_EQ(merge_neighbourhood(g, {0, 0, 0}, 1).count, 8u + 1u);   // (2k)^3 = 8 voxels, plus the first point
    EXPECT_EQ(merge_neighbourhood(g, {0, 0, 0}, 2).count, 64u + 1u);  // (2k)^3 = 64
    EXPECT_EQ(merge_neighbourhood(g, {2, 0, 0}, 1).count, 4u);        // only x in [1, 2): half of H^1 is outside
}

}  // namespace
