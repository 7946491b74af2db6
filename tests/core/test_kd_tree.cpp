// kd-tree against a linear scan (the oracle) on random points.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/kd_tree.hpp"

using namespace lidarsurf;

namespace {
std::vector<Eigen::Vector3d> random_points(std::size_t n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-10, 10);
    std::vector<Eigen::Vector3d> pts(n);
    for (auto& p : pts) p = {u(rng), u(rng), 0.1 * u(rng)};
    return pts;
}
std::vector<double> linear_sorted_d2(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& q) {
    std::vector<double> d;
    for (const auto& p : pts) d.push_back((p - q).squaredNorm());
    std::sort(d.begin(), d.end());
    return d;
}
}  // namespace

TEST(KdTree, NearestKnnAndRadiusMatchLinearScan) {
    const auto pts = random_points(3000, 1);
    const KdTree tree(pts);
    const auto queries = random_points(200, 2);
    std::vector<Neighbour> out;
    for (const auto& q : queries) {
        const auto d = linear_sorted_d2(pts, q);
        const Neighbour nn = tree.nearest(q);
        EXPECT_DOUBLE_EQ(nn.squared_distance, d[0]);
        EXPECT_DOUBLE_EQ((pts[nn.index] - q).squaredNorm(), d[0]);

        tree.knn(q, 10, out);
        ASSERT_EQ(out.size(), 10u);
        for (std::size_t i = 0; i < out.size(); ++i) EXPECT_DOUBLE_EQ(out[i].squared_distance, d[i]);

        const double r = 1.5;
        tree.radius(q, r, out);
        const auto expected = static_cast<std::size_t>(std::upper_bound(d.begin(), d.end(), r * r) - d.begin());
        EXPECT_EQ(out.size(), expected);
        for (const Neighbour& n : out) EXPECT_LE((pts[n.index] - q).squaredNorm(), r * r);
    }
}

TEST(KdTree, SmallAndEmptySets) {
    const KdTree empty(std::vector<Eigen::Vector3d>{});
    std::vector<Neighbour> out;
    EXPECT_THROW(empty.nearest(Eigen::Vector3d::Zero()), InvalidInput);
    empty.knn(Eigen::Vector3d::Zero(), 5, out);
    EXPECT_TRUE(out.empty());
    empty.radius(Eigen::Vector3d::Zero(), 5, out);
    EXPECT_TRUE(out.empty());

    const KdTree two(std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}});
    two.knn(Eigen::Vector3d(0.9, 0, 0), 5, out);  // k larger than the set
    ASSERT_EQ(out.size(), 2u);
    EXPECT_EQ(out[0].index, 1u);
}

TEST(KdTree, RejectsNonFinitePointsAndSurvivesMoves) {
    EXPECT_THROW(KdTree(std::vector<Eigen::Vector3d>{{0, 0, 0}, {std::nan(""), 0, 0}}), InvalidInput);
    KdTree a(random_points(100, 3));
    const Eigen::Vector3d q(1, 2, 0);
    const Neighbour before = a.nearest(q);
    KdTree b(std::move(a));
    EXPECT_EQ(b.nearest(q).index, before.index);
    KdTree c(std::vector<Eigen::Vector3d>{{5, 5, 5}});
    c = std::move(b);
    EXPECT_EQ(c.nearest(q).index, before.index);
}
