// Intensity on the mesh: a scan painted with stripes of two known intensities (lane markings
// 0.8 on asphalt 0.1, 8 m wide); the vertices whose neighbourhood lies on one stripe read its value.
// And a simulated town scan in front of a zebra crossing: each road vertex reads what its world's
// materials give under it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/mesh/vertex_intensity.hpp"
#include "lidarsurf/sim/mesh_scene.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "test_scans.hpp"

using namespace lidarsurf;

namespace {

constexpr double kStripe = 8.0;  // metres along x
constexpr float kBright = 0.8f, kDark = 0.1f;

float paint(const Eigen::Vector3d& p) { return (static_cast<long>(std::floor(p.x() / kStripe)) % 2 == 0) ? kBright : kDark; }
// Distance along x to the nearest stripe border.
double to_border(const Eigen::Vector3d& p) {
    const double r = p.x() / kStripe - std::floor(p.x() / kStripe);
    return kStripe * std::min(r, 1 - r);
}

PointCloud painted_scan() {
    PointCloud cloud = test::demo_scan();
    cloud.intensities.resize(cloud.points.size());
    for (std::size_t i = 0; i < cloud.points.size(); ++i) cloud.intensities[i] = paint(cloud.points[i]);
    return cloud;
}

}  // namespace

TEST(VertexIntensity, VerticesOnOneStripeReadItsValue) {
    const ReconstructionConfig config;
    Reconstructor rec(config, Eigen::Vector3d::Zero());
    rec.integrate(painted_scan());
    const Mesh mesh = rec.extract_mesh();
    ASSERT_EQ(mesh.intensity.size(), mesh.vertices.size());
    std::size_t inside = 0, exact = 0, nan = 0;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const float value = mesh.intensity[i];
        if (std::isnan(value)) {
            ++nan;
            continue;
        }
        // A mean of the two values.
        EXPECT_GE(value, kDark - 1e-6f);
        EXPECT_LE(value, kBright + 1e-6f);
        // H^k of the lattice vertex nearest the vertex: k voxels and the rounding's half voxel
        // (and a snapped vertex's offset, below a voxel) around it.
        // Bridged vertices (confidence below tau) may take a wider box (attach_intensity).
        const double extent = (mesh.levels[i] + 1.5) * config.voxel_size;
        if (mesh.confidence[i] < config.tau || to_border(mesh.vertices[i]) <= extent) continue;
        ++inside;
        exact += std::fabs(value - paint(mesh.vertices[i])) < 1e-5f;
    }
    EXPECT_EQ(nan, 0u);
    ASSERT_GT(inside, mesh.vertices.size() / 2);
    EXPECT_GE(static_cast<double>(exact), 0.995 * static_cast<double>(inside)) << exact << " of " << inside;
}

TEST(VertexIntensity, ScansWithoutIntensityGiveNone) {
    Reconstructor rec(ReconstructionConfig{}, Eigen::Vector3d::Zero());
    rec.integrate(test::demo_scan());
    EXPECT_TRUE(rec.extract_mesh().intensity.empty());
}

TEST(VertexIntensity, TheLiveMeshAndTheExactMeshAgree) {
    // A scan integrated as a sequence: the live mesh's blocks carry the same vertex intensities.
    Reconstructor rec(ReconstructionConfig{}, Eigen::Vector3d::Zero());
    const PointCloud cloud = painted_scan();
    rec.integrate(cloud.points, Eigen::Vector3d::Zero(), {}, cloud.intensities);
    rec.update_mesh();
    const Mesh live = rec.live_mesh(), exact = rec.extract_mesh();
    ASSERT_EQ(live.intensity.size(), live.vertices.size());
    ASSERT_FALSE(live.vertices.empty());
    for (std::size_t i = 0; i < live.vertices.size(); i += 97) {
        EXPECT_TRUE(std::isfinite(live.intensity[i]));
        EXPECT_GE(live.intensity[i], kDark - 1e-6f);
        EXPECT_LE(live.intensity[i], kBright + 1e-6f);
    }
    EXPECT_EQ(exact.intensity.size(), exact.vertices.size());
}

TEST(VertexIntensity, ThePlyKeepsIt) {
    Reconstructor rec(ReconstructionConfig{}, Eigen::Vector3d::Zero());
    rec.integrate(painted_scan());
    const Mesh mesh = rec.extract_mesh();
    const auto path = std::filesystem::temp_directory_path() / "lidarsurf_intensity.ply";
    write_mesh(mesh, path);
    const Mesh back = read_mesh(path);
    std::filesystem::remove(path);
    ASSERT_EQ(back.intensity.size(), mesh.intensity.size());
    for (std::size_t i = 0; i < mesh.intensity.size(); ++i) ASSERT_EQ(back.intensity[i], mesh.intensity[i]) << i;
}

namespace {

/// The least and the most reflective material of the town's carriageway within the square of
/// half-width h around (x, y): paint where a marking reaches into it, asphalt unless one marking holds it all.
std::pair<float, float> carriageway_range(const std::vector<sim::Marking>& marks, double x, double y, double h) {
    bool touches = false, inside = false;
    for (const auto& m : marks) {
        touches = touches || (x + h > m.x0 && x - h < m.x1 && y + h > m.y0 && y - h < m.y1);
        inside = inside || (x - h >= m.x0 && x + h <= m.x1 && y - h >= m.y0 && y + h <= m.y1);
    }
    return {inside ? sim::Material::kRoadPaint : sim::Material::kAsphalt, touches ? sim::Material::kRoadPaint : sim::Material::kAsphalt};
}

}  // namespace

TEST(VertexIntensity, ATownScanReadsTheZebraCrossingAndTheAsphalt) {
    sim::SceneConfig scene_config;
    scene_config.seed = 4;
    const sim::World world = sim::make_world(scene_config);
    ASSERT_EQ(world.static_mesh.intensity.size(), world.static_mesh.vertices.size());
    const auto marks = sim::town_markings(scene_config.length);
    const sim::MeshScene scene(world.static_mesh);
    const sim::SensorModel sensor = sim::SensorModel::hdl64();
    // 3-6 m before the zebra of the cross street at x = 60 (its bars at x in [51, 54]), where the
    // returns are densest and the road vertices take k' = 1.
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(48, -1.75, sensor.mount_height);
    PointCloud scan = sim::simulate_scan(scene, sensor, pose, 7);
    ASSERT_EQ(scan.intensities.size(), scan.points.size());
    for (auto& p : scan.points) p = pose * p;

    // The returns: each reads its surface's reflectivity, within the sensor's intensity noise.
    std::size_t road_points = 0, off = 0;
    for (std::size_t i = 0; i < scan.points.size(); ++i) {
        const Eigen::Vector3d& p = scan.points[i];
        if (std::fabs(p.z()) > 0.05 || std::fabs(p.y()) > 2.8 || std::fabs(p.x() - 50) > 15) continue;
        const auto [lo, hi] = carriageway_range(marks, p.x(), p.y(), 0.1);  // the range noise moves a return along its ray
        ++road_points;
        off += scan.intensities[i] < lo - 5 * sensor.intensity_noise || scan.intensities[i] > hi + 5 * sensor.intensity_noise;
    }
    ASSERT_GT(road_points, 5000u);
    EXPECT_LE(off, road_points / 1000) << off << " of " << road_points;

    // The mesh: a road vertex's intensity lies within the materials of the square its
    // neighbourhood covers (attach_intensity: H^k around its nearer lattice vertex, see above).
    // 0.1 m voxels, as for road markings: a 0.6 m bar then holds whole neighbourhoods of k' = 1.
    ReconstructionConfig config;
    config.voxel_size = 0.1;
    Reconstructor rec(config, pose.translation());
    rec.integrate(scan);
    const Mesh mesh = rec.extract_mesh();
    ASSERT_EQ(mesh.intensity.size(), mesh.vertices.size());
    const double tolerance = 0.04;  // two sigmas of one return's noise: a voxel's mean has several
    std::size_t road = 0, within = 0, paint = 0, asphalt = 0, asphalt_ok = 0;
    double paint_sum = 0, paint_worst = 0;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Eigen::Vector3d& p = mesh.vertices[i];
        const double h = (mesh.levels[i] + 1.5) * config.voxel_size;
        if (mesh.confidence[i] < config.tau || std::fabs(p.z()) > 0.1 || std::fabs(p.y()) + h > 2.8 || std::fabs(p.x() - 50) > 15) continue;
        const auto [lo, hi] = carriageway_range(marks, p.x(), p.y(), h);
        const float value = mesh.intensity[i];
        ++road;
        within += value >= lo - tolerance && value <= hi + tolerance;
        if (lo == sim::Material::kRoadPaint) {
            ++paint;
            paint_sum += value;
            paint_worst = std::max(paint_worst, std::fabs(value - static_cast<double>(sim::Material::kRoadPaint)));
        } else if (hi == sim::Material::kAsphalt) {
            ++asphalt;
            asphalt_ok += std::fabs(value - sim::Material::kAsphalt) <= tolerance;
        }
    }
    std::printf("road vertices %zu (%zu within their square's materials); on paint only %zu (mean %.4f, worst %.4f off); "
                "on asphalt only %zu (%zu within %.2f)\n",
                road, within, paint, paint ? paint_sum / static_cast<double>(paint) : 0.0, paint_worst, asphalt, asphalt_ok, tolerance);
    ASSERT_GT(road, 2000u);
    EXPECT_GE(static_cast<double>(within), 0.995 * static_cast<double>(road));
    ASSERT_GE(paint, 20u);
    EXPECT_NEAR(paint_sum / static_cast<double>(paint), sim::Material::kRoadPaint, 0.02);
    EXPECT_LE(paint_worst, 2 * tolerance);
    ASSERT_GE(asphalt, 1000u);
    EXPECT_GE(static_cast<double>(asphalt_ok), 0.99 * static_cast<double>(asphalt));
}
