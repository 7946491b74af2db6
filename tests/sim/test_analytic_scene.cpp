#include <gtest/gtest.h>

#include <cmath>

#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"

using namespace lidarsurf;
using namespace lidarsurf::sim;

namespace {

TEST(AnalyticScene, RaysHitAtKnownRanges) {
    AnalyticScene s;
    s.grounds.push_back({-2.0, 0, 0, 50, 50});
    s.boxes.push_back({{4, -1, -2}, {6, 1, 0}});
    s.cylinders.push_back({0, 10, 1.0, -2, 3});
    const Eigen::Vector3d o = Eigen::Vector3d::Zero();
    EXPECT_NEAR(*s.intersect(o, {0, 0, -1}, 100), 2.0, 1e-12);                           // ground below
    EXPECT_NEAR(*s.intersect(o, {1, 0, 0}, 100), 4.0, 1e-12);                            // box face x = 4
    EXPECT_NEAR(*s.intersect(o, {0, 1, 0}, 100), 9.0, 1e-12);                            // cylinder side
    const Eigen::Vector3d d = Eigen::Vector3d(1, 0, -1).normalized();
    EXPECT_NEAR(*s.intersect(o, d, 100), 2.0 * std::sqrt(2.0), 1e-12);                   // ground at x = 2
    EXPECT_FALSE(s.intersect(o, {0, 0, 1}, 100));                                        // sky
    EXPECT_FALSE(s.intersect(o, {1, 0, 0}, 3.5));                                        // beyond max range
    EXPECT_NEAR(s.distance({5, 0, 0.5}), 0.5, 1e-12);                                    // above the box top
    EXPECT_NEAR(s.distance({5, 0.5, -1}), 0.5, 1e-12);                                   // inside the box
    EXPECT_NEAR(s.distance({0, 7, 0}), 2.0, 1e-12);                                      // beside the cylinder
}

TEST(SensorModel, Hdl64PatternAndDeterminism) {
    const SensorModel hdl = SensorModel::hdl64();
    ASSERT_EQ(hdl.elevations_deg.size(), 64u);
    EXPECT_NEAR(hdl.elevations_deg.front(), 2.0, 1e-12);
    EXPECT_NEAR(hdl.elevations_deg.back(), -24.8, 1e-12);
    const AnalyticScene scene = AnalyticScene::demo();
    const PointCloud a = simulate_scan(scene, hdl, Eigen::Vector3d::Zero(), 42);
    const PointCloud b = simulate_scan(scene, hdl, Eigen::Vector3d::Zero(), 42);
    ASSERT_EQ(a.points.size(), b.points.size());
    EXPECT_EQ(a.points, b.points);
    EXPECT_LE(a.points.size(), 64u * 2000u);
    // Noise is along the ray with sigma = 2 cm: the residual to the true surface has that scale.
    double sum2 = 0;
    for (const auto& p : a.points) sum2 += std::pow(scene.distance(p), 2);
    const double rms = std::sqrt(sum2 / static_cast<double>(a.points.size()));
    EXPECT_GT(rms, 0.005);
    EXPECT_LT(rms, 0.025);
}

}  // namespace
