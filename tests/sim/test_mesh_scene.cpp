// Embree ray casting checked against analytic answers and against the analytic scene.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/mesh_builder.hpp"
#include "lidarsurf/sim/mesh_scene.hpp"

using namespace lidarsurf;
using namespace lidarsurf::sim;

namespace {

TEST(MeshScene, RayHitsAPlaneAtTheKnownRange) {
    MeshBuilder b;
    b.height_field(-50, 50, -50, 50, 10.0, [](double, double) { return -1.73; });
    const MeshScene scene(b.mesh());
    for (double el_deg : {-2.0, -10.0, -24.8, -90.0}) {
        const double el = el_deg * M_PI / 180;
        const Eigen::Vector3d d(std::cos(el) * std::cos(0.3), std::cos(el) * std::sin(0.3), std::sin(el));
        const auto hit = scene.cast(Eigen::Vector3d::Zero(), d, 200);
        const double expected = 1.73 / std::sin(-el);
        if (expected * std::cos(el) > 49) continue;  // beyond the plane's edge
        ASSERT_TRUE(hit) << el_deg;
        EXPECT_NEAR(hit->range, expected, 1e-5 * expected) << el_deg;
        EXPECT_NEAR(hit->normal.z(), 1.0, 1e-9);  // the height field faces +z
    }
    EXPECT_FALSE(scene.intersect(Eigen::Vector3d::Zero(), {0, 0, 1}, 200));      // sky
    EXPECT_FALSE(scene.intersect(Eigen::Vector3d::Zero(), {0, 0, -1}, 1.0));     // beyond max range
}

TEST(MeshScene, BoxMeshAgreesWithTheAnalyticBox) {
    MeshBuilder b;
    b.box_between({4, -1, -2}, {6, 1, 0});
    b.box_between({-3, -8, -2}, {3, -6, 2.5});
    const MeshScene mesh(b.mesh());
    AnalyticScene exact;
    exact.boxes.push_back({{4, -1, -2}, {6, 1, 0}});
    exact.boxes.push_back({{-3, -8, -2}, {3, -6, 2.5}});
    std::mt19937_64 rng(7);
    std::normal_distribution<double> g;
    int hits = 0;
    for (int i = 0; i < 20000; ++i) {
        const Eigen::Vector3d d = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        const auto a = exact.intersect(Eigen::Vector3d::Zero(), d, 100);
        const auto m = mesh.intersect(Eigen::Vector3d::Zero(), d, 100);
        ASSERT_EQ(a.has_value(), m.has_value()) << "ray " << i;  // grazing edges are measure zero
        if (a) {
            EXPECT_NEAR(*a, *m, 1e-4);
            ++hits;
        }
    }
    EXPECT_GT(hits, 1000);  // both boxes subtend a good share of the sphere of directions
}

TEST(MeshScene, HitNormalsPointOutOfTheSolid) {
    MeshBuilder b;
    b.box_between({4, -1, -1}, {6, 1, 1});
    const MeshScene scene(b.mesh());
    const auto hit = scene.cast(Eigen::Vector3d::Zero(), {1, 0, 0}, 100);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->range, 4.0, 1e-5);
    EXPECT_NEAR(hit->normal.x(), -1.0, 1e-9);
}

TEST(MeshScene, Occlusion) {
    MeshBuilder b;
    b.box_between({4, -1, -1}, {6, 1, 1});
    const MeshScene scene(b.mesh());
    EXPECT_TRUE(scene.occluded({0, 0, 0}, {10, 0, 0}));
    EXPECT_FALSE(scene.occluded({0, 0, 0}, {3, 0, 0}));
    EXPECT_FALSE(scene.occluded({0, 0, 0}, {4, 0, 0}));   // the end point on the surface does not occlude itself
    EXPECT_FALSE(scene.occluded({0, 0, 5}, {10, 0, 5}));  // passes above
}

TEST(MeshScene, RejectsEmptyAndNonFiniteMeshes) {
    EXPECT_THROW(MeshScene(Mesh{}), InvalidInput);
    Mesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, NAN, 0}};
    m.triangles = {{0, 1, 2}};
    EXPECT_THROW(MeshScene{m}, InvalidInput);
}

}  // namespace
