// Sensor presets, JSON, and the statistics of the simulated noise and dropouts.
#include <gtest/gtest.h>

#include <cmath>

#include <tbb/global_control.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/mesh_builder.hpp"
#include "lidarsurf/sim/mesh_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"

using namespace lidarsurf;
using namespace lidarsurf::sim;

namespace {

double max_of(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }
double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

TEST(SensorModel, PresetsHaveTheirDatasheetPatterns) {
    struct Row { const char* name; std::size_t beams; double top, bottom; };
    for (const Row& r : {Row{"hdl64", 64, 2.0, -24.8}, Row{"vlp16", 16, 15.0, -15.0}, Row{"hdl32", 32, 10.67, -30.67},
                         Row{"os1-128", 128, 22.5, -22.5}, Row{"gt316", 316, 2.0, -24.8}}) {
        const SensorModel s = SensorModel::preset(r.name);
        EXPECT_EQ(s.elevations_deg.size(), r.beams) << r.name;
        EXPECT_NEAR(max_of(s.elevations_deg), r.top, 1e-12) << r.name;
        EXPECT_NEAR(min_of(s.elevations_deg), r.bottom, 1e-12) << r.name;
        EXPECT_NO_THROW(s.validate());
    }
    EXPECT_EQ(SensorModel::hdl64().rays_per_revolution(), 64u * 2000u);  // 0.18 deg step
    EXPECT_THROW(SensorModel::preset("hdl65"), InvalidArgument);
}

TEST(SensorModel, GroundTruthSensorSpansTheSameElevationsNoiseFree) {
    const SensorModel vlp = SensorModel::vlp16();
    const SensorModel gt = SensorModel::ground_truth_for(vlp, 100);
    EXPECT_EQ(gt.elevations_deg.size(), 100u);
    EXPECT_DOUBLE_EQ(max_of(gt.elevations_deg), 15.0);
    EXPECT_DOUBLE_EQ(min_of(gt.elevations_deg), -15.0);
    EXPECT_EQ(gt.range_noise, 0.0);
    EXPECT_EQ(gt.dropout, 0.0);
    EXPECT_LE(gt.azimuth_step_deg, vlp.azimuth_step_deg / 2);
}

TEST(SensorModel, JsonRoundTripAndErrors) {
    SensorModel s = SensorModel::os1_128();
    s.mount_height = 2.1;
    const SensorModel back = SensorModel::from_json(s.to_json());
    EXPECT_EQ(back.name, s.name);
    EXPECT_EQ(back.elevations_deg, s.elevations_deg);
    EXPECT_EQ(back.azimuth_step_deg, s.azimuth_step_deg);
    EXPECT_EQ(back.range_noise, s.range_noise);
    EXPECT_EQ(back.intensity_noise, s.intensity_noise);
    EXPECT_EQ(back.mount_height, 2.1);
    EXPECT_EQ(SensorModel::from_json(R"({"elevations_deg": [0], "intensity_noise": 0.1})").intensity_noise, 0.1);
    EXPECT_THROW(SensorModel::from_json(R"({"elevations_deg": [0], "intensity_noise": -0.1})"), InvalidArgument);
    const SensorModel even = SensorModel::from_json(R"({"beams": 5, "elevation_max_deg": 4, "elevation_min_deg": -4})");
    EXPECT_EQ(even.elevations_deg, (std::vector<double>{4, 2, 0, -2, -4}));
    EXPECT_THROW(SensorModel::from_json("{"), FormatError);
    EXPECT_THROW(SensorModel::from_json(R"({"beams": 4})"), FormatError);
    EXPECT_THROW(SensorModel::from_json(R"({"beams": 4, "elevation_max_deg": 1, "elevation_min_deg": 0, "colour": 3})"), FormatError);
    EXPECT_THROW(SensorModel::from_json(R"({"elevations_deg": "up"})"), FormatError);
    EXPECT_THROW(SensorModel::from_json(R"({"elevations_deg": [0], "range_noise": -1})"), InvalidArgument);
    EXPECT_THROW(SensorModel::from_json(R"({"elevations_deg": [0], "azimuth_step_deg": 0})"), InvalidArgument);
    EXPECT_THROW(SensorModel::from_json(R"({"elevations_deg": []})"), InvalidArgument);
    // Fuzzer regressions: a beam count beyond int (was an out-of-range conversion under UBSan;
    // the second input is fuzz_sensor_json's own crash), and a fractional one (was truncated).
    EXPECT_THROW(SensorModel::from_json(R"({"beams": 1e20, "elevation_max_deg": 5, "elevation_min_deg": -20})"), InvalidArgument);
    EXPECT_THROW(SensorModel::from_json(R"({"name": "s", "beams":68888888888888888888888888888888888888888888888888888888888888888888883,)"
                                        R"( "elevation_max_deg": 5, "elevation_min_deg": 5})"),
                 InvalidArgument);
    EXPECT_THROW(SensorModel::from_json(R"({"beams": 8.7, "elevation_max_deg": 5, "elevation_min_deg": -20})"), InvalidArgument);
}

// A wall 10 m ahead seen by one horizontal beam: the range residuals have the sensor's sigma and
// the share of lost returns is the dropout probability.
TEST(SensorModel, NoiseAndDropoutStatistics) {
    AnalyticScene wall;
    wall.boxes.push_back({{10, -1000, -1000}, {11, 1000, 1000}});
    SensorModel s;
    s.elevations_deg = {0.0};
    s.azimuth_step_deg = 0.01;  // 36,000 rays, half of them towards the wall
    s.range_noise = 0.05;
    s.dropout = 0.1;
    const PointCloud c = simulate_scan(wall, s, Eigen::Vector3d::Zero(), 3);
    double sum = 0, sq = 0;
    for (const auto& p : c.points) {
        const double residual = p.norm() - 10.0 / (p.x() / p.norm());  // measured minus true range
        sum += residual;
        sq += residual * residual;
    }
    const double n = static_cast<double>(c.points.size());
    double rays = 0;  // azimuths whose ray meets the wall within max_range: 10 / cos(az) <= 120
    for (int a = 0; a < 36000; ++a) rays += std::cos(a * 0.01 * M_PI / 180) * s.max_range >= 10.0 ? 1 : 0;
    EXPECT_NEAR(n, 0.9 * rays, 4 * std::sqrt(rays * 0.1 * 0.9));  // binomial, 4 sigma
    EXPECT_NEAR(sum / n, 0.0, 4 * 0.05 / std::sqrt(n));
    EXPECT_NEAR(std::sqrt(sq / n), 0.05, 0.05 * 0.03);
}

// Two walls 10 m ahead, 0.3 and 0.7 reflective, split at y = 0: each return's intensity is its
// wall's, with the sensor's intensity noise, drawn apart from its range noise; a scene without
// reflectivity gives no intensity.
TEST(SensorModel, ReturnsReadTheirSurfacesReflectivity) {
    MeshBuilder b;
    b.set_reflectivity(0.3f);
    b.box_between({10, -1000, -1000}, {11, 0, 1000});
    b.set_reflectivity(0.7f);
    b.box_between({10, 0, -1000}, {11, 1000, 1000});
    const MeshScene walls(b.mesh());
    SensorModel s;
    s.elevations_deg = {0.0};
    s.azimuth_step_deg = 0.01;
    s.range_noise = 0.05;
    s.intensity_noise = 0.05;
    const PointCloud c = simulate_scan(walls, s, Eigen::Vector3d::Zero(), 5);
    ASSERT_EQ(c.intensities.size(), c.points.size());
    double sum[2] = {0, 0}, sq[2] = {0, 0}, n[2] = {0, 0}, cross = 0;
    for (std::size_t i = 0; i < c.points.size(); ++i) {
        const Eigen::Vector3d& p = c.points[i];
        if (std::fabs(p.y()) < 0.5) continue;  // the range noise moves a return along its ray, across the split
        const int side = p.y() > 0;
        const double e = c.intensities[i] - (side ? 0.7 : 0.3), residual = p.norm() - 10.0 / (p.x() / p.norm());
        sum[side] += e, sq[side] += e * e, n[side] += 1, cross += e * residual;
    }
    for (int side : {0, 1}) {
        ASSERT_GT(n[side], 5000);
        EXPECT_NEAR(sum[side] / n[side], 0.0, 4 * 0.05 / std::sqrt(n[side]));
        EXPECT_NEAR(std::sqrt(sq[side] / n[side]), 0.05, 0.05 * 0.04);
    }
    const double samples = n[0] + n[1];
    EXPECT_NEAR(cross / samples / (0.05 * 0.05), 0.0, 4 / std::sqrt(samples));  // correlation of the two noises
    AnalyticScene grey;
    grey.boxes.push_back({{10, -1000, -1000}, {11, 1000, 1000}});
    EXPECT_TRUE(simulate_scan(grey, s, Eigen::Vector3d::Zero(), 5).intensities.empty());
}

TEST(SensorModel, ScansAreDeterministicWhateverTheThreadCount) {
    const AnalyticScene scene = AnalyticScene::demo();
    const SensorModel s = SensorModel::vlp16();
    const PointCloud a = simulate_scan(scene, s, Eigen::Vector3d::Zero(), 11);
    PointCloud b;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        b = simulate_scan(scene, s, Eigen::Vector3d::Zero(), 11);
    }
    ASSERT_EQ(a.points.size(), b.points.size());
    for (std::size_t i = 0; i < a.points.size(); ++i) ASSERT_EQ(a.points[i], b.points[i]);
    const PointCloud c = simulate_scan(scene, s, Eigen::Vector3d::Zero(), 12);
    bool differs = c.points.size() != a.points.size();
    for (std::size_t i = 0; !differs && i < a.points.size(); ++i) differs = a.points[i] != c.points[i];
    EXPECT_TRUE(differs);
}

TEST(SensorModel, PoseRotatesTheBeamsAndPointsStayInTheSensorFrame) {
    AnalyticScene ground;
    ground.grounds.push_back({0.0, 0, 0, 500, 500});
    SensorModel s = SensorModel::hdl64();
    s.range_noise = 0;
    s.dropout = 0;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translate(Eigen::Vector3d(30, -20, 1.73));
    pose.rotate(Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitZ()));
    const PointCloud c = simulate_scan(ground, s, pose, 1);
    ASSERT_GT(c.points.size(), 1000u);
    for (const auto& p : c.points) {
        EXPECT_NEAR(p.z(), -1.73, 1e-9);               // sensor frame: the ground is 1.73 m below
        EXPECT_NEAR((pose * p).z(), 0.0, 1e-9);        // world frame: on the ground
    }
}

}  // namespace
