#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "lidarsurf/surface/local_plane.hpp"

using namespace lidarsurf;

namespace {

TEST(LocalPlane, RecoversNoisyPlanesAtRandomOrientations) {
    std::mt19937 rng(99);
    std::normal_distribution<double> g(0.0, 1.0);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (int trial = 0; trial < 100; ++trial) {
        const Eigen::Vector3d n = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        const Eigen::Vector3d a = n.unitOrthogonal(), b = n.cross(a);
        const Eigen::Vector3d centre(3 * g(rng), 3 * g(rng), 3 * g(rng));
        VoxelStats s;
        for (int i = 0; i < 400; ++i) s.add(centre + u(rng) * a + u(rng) * b + 0.01 * g(rng) * n);  // 1 cm noise on 1 m patch
        const Eigen::Vector3d sensor = centre + 5.0 * n + 2.0 * a;  // on the +n side
        const auto plane = fit_plane(s, 10, sensor, 1e-14);
        ASSERT_TRUE(plane);
        EXPECT_GT(plane->normal.dot(n), std::cos(2.0 * M_PI / 180.0));  // within 2 degrees, oriented to the sensor
        EXPECT_NEAR(plane->normal.norm(), 1.0, 1e-12);
        EXPECT_GE(plane->lambda1, plane->lambda2);
        EXPECT_GE(plane->lambda2, plane->lambda3);
        EXPECT_NEAR(plane->lambda1, 1.0 / 12.0, 0.02);  // uniform on [-0.5, 0.5]: variance 1/12
        EXPECT_NEAR(plane->lambda3, 1e-4, 3e-5);        // noise variance (0.01 m)^2
        // Sensor on the other side: the normal flips (Eq. 2).
        const auto flipped = fit_plane(s, 10, centre - 5.0 * n, 1e-14);
        ASSERT_TRUE(flipped);
        EXPECT_GT(flipped->normal.dot(-n), std::cos(2.0 * M_PI / 180.0));
    }
}

TEST(LocalPlane, Equation1RequiresNMinPoints) {
    VoxelStats s;
    for (int i = 0; i < 9; ++i) s.add({0.1 * (i % 3), 0.1 * (i / 3), 0.0});
    EXPECT_FALSE(fit_plane(s, 10, {0, 0, 1}, 1e-14));
    s.add({0.05, 0.05, 0.0});
    EXPECT_TRUE(fit_plane(s, 10, {0, 0, 1}, 1e-14));
}

TEST(LocalPlane, DegenerateCovariancesGiveNoPlane) {
    VoxelStats same, line;
    for (int i = 0; i < 20; ++i) {
        same.add({1, 2, 3});
        line.add({0.1 * i, 0.2 * i, -0.05 * i});
    }
    EXPECT_FALSE(fit_plane(same, 10, {0, 0, 10}, 1e-14));
    EXPECT_FALSE(fit_plane(line, 10, {0, 0, 10}, 1e-14));
}

TEST(LocalPlane, PlanarityGuardRejectsASingleScanLine) {
    // One ring segment: 0.4 m along x, 2 cm noise across it. lambda1 = 0.4^2/12 = 0.0133,
    // lambda2 ~ 0.02^2 = 4e-4: ratio ~ 0.03, a line rather than a plane.
    std::mt19937 rng(4);
    std::normal_distribution<double> g(0.0, 0.02);
    VoxelStats ring, patch;
    for (int i = 0; i < 40; ++i) ring.add({0.01 * i, g(rng), 0.002 * g(rng)});
    for (int i = 0; i < 40; ++i) patch.add({0.01 * i, 0.1 * (i % 4), 0.002 * g(rng)});  // four rings
    EXPECT_TRUE(fit_plane(ring, 10, {0, 0, 1}, 1e-14, 0.0));
    EXPECT_FALSE(fit_plane(ring, 10, {0, 0, 1}, 1e-14, 0.05));
    EXPECT_TRUE(fit_plane(patch, 10, {0, 0, 1}, 1e-14, 0.05));
}

TEST(LocalPlane, SignedDistanceIsPositiveOnTheSensorSide) {
    VoxelStats s;
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) s.add({0.1 * i, 0.1 * j, 2.0});
    const auto plane = fit_plane(s, 10, {0, 0, 0}, 1e-14);  // sensor below the plane
    ASSERT_TRUE(plane);
    EXPECT_NEAR(plane->normal.z(), -1.0, 1e-12);
    EXPECT_NEAR(signed_distance(*plane, {0.3, 0.3, 1.5}), 0.5, 1e-12);
    EXPECT_NEAR(signed_distance(*plane, {0.3, 0.3, 2.25}), -0.25, 1e-12);
}

}  // namespace
