// The hold-out split: reproducible for a seed, disjoint, covering, of the requested size.
#include <gtest/gtest.h>

#include <set>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/holdout.hpp"

using namespace lidarsurf;

namespace {
PointCloud numbered(std::size_t n) {
    PointCloud c;
    for (std::size_t i = 0; i < n; ++i) c.points.emplace_back(double(i), 0, 0);  // x identifies the point
    return c;
}
std::set<double> ids(const PointCloud& c) {
    std::set<double> s;
    for (const auto& p : c.points) s.insert(p.x());
    return s;
}
}  // namespace

TEST(Holdout, DisjointCoveringAndOfTheRequestedSize) {
    const PointCloud cloud = numbered(10001);
    const HoldoutSplit s = split_holdout(cloud, 0.3, 42);
    EXPECT_EQ(s.held_out.points.size(), 3000u);  // round(0.3 * 10001)
    EXPECT_EQ(s.kept.points.size(), 7001u);
    const auto a = ids(s.kept), b = ids(s.held_out);
    EXPECT_EQ(a.size(), s.kept.points.size());      // no duplicate
    EXPECT_EQ(b.size(), s.held_out.points.size());
    for (double x : b) EXPECT_EQ(a.count(x), 0u);   // disjoint
    EXPECT_EQ(a.size() + b.size(), cloud.points.size());  // covering
}

TEST(Holdout, ReproducibleForASeedAndDifferentAcrossSeeds) {
    const PointCloud cloud = numbered(5000);
    const HoldoutSplit a = split_holdout(cloud, 0.5, 7), b = split_holdout(cloud, 0.5, 7), c = split_holdout(cloud, 0.5, 8);
    EXPECT_EQ(a.held_out.points, b.held_out.points);
    EXPECT_EQ(a.kept.points, b.kept.points);
    EXPECT_NE(a.held_out.points, c.held_out.points);
}

TEST(Holdout, SpreadsOverTheWholeScan) {
    // Each tenth of the scan should keep about half of its points (binomial, 4 sigma).
    const PointCloud cloud = numbered(20000);
    const HoldoutSplit s = split_holdout(cloud, 0.5, 1);
    std::vector<int> per_tenth(10, 0);
    for (const auto& p : s.held_out.points) ++per_tenth[static_cast<std::size_t>(p.x() / 2000)];
    for (int n : per_tenth) EXPECT_NEAR(n, 1000, 4 * std::sqrt(2000 * 0.25));
}

TEST(Holdout, RejectsBadFractionsAndEmptyParts) {
    const PointCloud cloud = numbered(10);
    EXPECT_THROW(split_holdout(cloud, 0.0, 1), InvalidArgument);
    EXPECT_THROW(split_holdout(cloud, 1.0, 1), InvalidArgument);
    EXPECT_THROW(split_holdout(cloud, std::nan(""), 1), InvalidArgument);
    EXPECT_THROW(split_holdout(cloud, 0.01, 1), InvalidInput);  // rounds to zero held out
    EXPECT_THROW(split_holdout(PointCloud{}, 0.5, 1), InvalidInput);
}
