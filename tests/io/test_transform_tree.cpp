// The tf tree: chained poses against analytic motions that linear interpolation and slerp follow
// exactly (a constant velocity; a constant rate about a fixed axis), so the expected pose at any
// time is the closed form; and the trees tf refuses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/transform_tree.hpp"

namespace lidarsurf {
namespace {

constexpr double kSecond = 1e9;

Eigen::Isometry3d iso(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.linear() = q.toRotationMatrix();
    p.translation() = t;
    return p;
}

// map -> odom: a drift at constant velocity, fixed rotation.
Eigen::Isometry3d drift(double t) { return iso(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(0.5 * t, -0.2 * t, 0.01 * t)); }
// odom -> base_link: turning at a constant rate about a fixed axis, in place.
Eigen::Isometry3d turn(double t) { return iso(Eigen::Quaterniond(Eigen::AngleAxisd(0.7 * t, Eigen::Vector3d(0.1, 0.2, 1).normalized())), Eigen::Vector3d(3, 1, 0)); }
// base_link -> lidar and map -> gps: fixed mounts.
const Eigen::Isometry3d kMount = iso(Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized(), Eigen::Vector3d(1.2, -0.1, 1.7));
const Eigen::Isometry3d kGps = iso(Eigen::Quaterniond(0.7, 0.0, 0.0, 0.7).normalized(), Eigen::Vector3d(-4, 2, 0.5));

void add(TransformTree& tree, const std::string& parent, const std::string& child, double t, const Eigen::Isometry3d& p, bool is_static = false) {
    tree.add(parent, child, static_cast<std::int64_t>(std::llround(t * kSecond)), p.translation(), Eigen::Quaterniond(p.linear()), is_static, "test");
}

// The drift every 0.25 s over [0, 2], the turn every 0.1 s over [0.3, 1.9] (given out of order),
// the mounts static; ROS 1's leading '/' on some names.
TransformTree robot() {
    TransformTree tree;
    for (int k = 16; k >= 0; --k) add(tree, "odom", "/base_link", 0.3 + 0.1 * k, turn(0.3 + 0.1 * k));
    for (int k = 0; k <= 8; ++k) add(tree, "/map", "odom", 0.25 * k, drift(0.25 * k));
    add(tree, "base_link", "lidar", 0, kMount, true);
    add(tree, "map", "gps", 5, kGps, true);
    return tree;
}

void expect_near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tol) {
    EXPECT_LT((a.translation() - b.translation()).norm(), tol);
    EXPECT_LT(Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle(), tol);
}

TEST(TransformTree, ChainsEveryLinkBetweenTheFramesAtEachStampOfItsMovingOnes) {
    const TransformTree tree = robot();
    const Trajectory t = tree.trajectory("map", "lidar");
    // The turn's stamps (0.3 .. 1.9) and the drift's within them (0.5, 0.75, ..., 1.75).
    std::vector<std::int64_t> expected;
    for (int k = 0; k <= 16; ++k) expected.push_back(std::llround((0.3 + 0.1 * k) * kSecond));
    for (int k = 2; k <= 7; ++k) expected.push_back(std::llround(0.25 * k * kSecond));
    std::sort(expected.begin(), expected.end());
    expected.erase(std::unique(expected.begin(), expected.end()), expected.end());  // 0.5, 1.0, 1.5 are in both
    ASSERT_EQ(t.stamps_ns(), expected);
    for (std::size_t i = 0; i < t.size(); ++i) {
        const double s = static_cast<double>(t.stamps_ns()[i]) / kSecond;
        expect_near(t.poses()[i], drift(s) * turn(s) * kMount, 1e-9);
    }
}

TEST(TransformTree, AFixedFrameOnAnotherBranchIsWalkedUpInverted) {
    const Trajectory t = robot().trajectory("gps", "lidar");
    ASSERT_FALSE(t.empty());
    for (std::size_t i = 0; i < t.size(); ++i) {
        const double s = static_cast<double>(t.stamps_ns()[i]) / kSecond;
        expect_near(t.poses()[i], kGps.inverse() * drift(s) * turn(s) * kMount, 1e-9);
    }
    // Backwards: the inverse pose.
    const Trajectory back = robot().trajectory("lidar", "gps");
    ASSERT_EQ(back.size(), t.size());
    for (std::size_t i = 0; i < t.size(); ++i) expect_near(back.poses()[i], t.poses()[i].inverse(), 1e-9);
}

TEST(TransformTree, ARepeatedStampKeepsItsFirstTransform) {
    TransformTree tree;
    add(tree, "odom", "lidar", 0, turn(0));
    add(tree, "odom", "lidar", 1, turn(1));
    add(tree, "odom", "lidar", 1, turn(2));
    const Trajectory t = tree.trajectory("odom", "lidar");
    ASSERT_EQ(t.size(), 2u);
    expect_near(t.poses()[1], turn(1), 1e-12);
}

TEST(TransformTree, TreesTfRefusesAreRefused) {
    const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
    {
        TransformTree tree;
        add(tree, "odom", "base", 0, I);
        EXPECT_THROW(add(tree, "map", "base", 0, I), FormatError);                       // a second parent
        EXPECT_THROW(add(tree, "odom", "base", 1, I, true), FormatError);                // static and moving
        EXPECT_THROW(add(tree, "base", "base", 0, I), FormatError);                      // itself
        EXPECT_THROW(add(tree, "", "x", 0, I), FormatError);                             // no name
        EXPECT_THROW(tree.add("odom", "x", 0, Eigen::Vector3d::Zero(), Eigen::Quaterniond(1.5, 0, 0, 0), false, "test"), FormatError);
        EXPECT_THROW(tree.add("odom", "x", 0, Eigen::Vector3d(NAN, 0, 0), Eigen::Quaterniond::Identity(), false, "test"), FormatError);
        EXPECT_THROW(tree.trajectory("odom", "nowhere"), InvalidArgument);
    }
    {
        TransformTree loop;
        add(loop, "a", "b", 0, I);
        add(loop, "b", "a", 0, I);
        add(loop, "a", "c", 0, I);
        EXPECT_THROW(loop.trajectory("c", "b"), FormatError);
    }
    {
        TransformTree apart;
        add(apart, "odom", "base", 0, I);
        add(apart, "odom", "base", 1, I);
        add(apart, "map", "gps", 0, I);
        EXPECT_THROW(apart.trajectory("map", "base"), InvalidInput);  // two trees
        add(apart, "base", "lidar", 0, I, true);
        EXPECT_THROW(apart.trajectory("base", "lidar"), InvalidInput);  // nothing moves
        add(apart, "gps", "antenna", 5, I);
        add(apart, "gps", "antenna", 6, I);
        add(apart, "map", "odom", 0, I, true);
        EXPECT_THROW(apart.trajectory("antenna", "lidar"), InvalidInput);  // moving links with no common span
    }
}

}  // namespace
}  // namespace lidarsurf
