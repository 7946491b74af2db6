// Solids are closed and outward-facing: the divergence theorem gives their analytic volume.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include <Eigen/Geometry>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/sim/mesh_builder.hpp"

using namespace lidarsurf;
using namespace lidarsurf::sim;

namespace {

/// Signed volume (positive when every triangle faces out of a closed surface).
double signed_volume(const Mesh& m) {
    double v = 0;
    for (const auto& t : m.triangles) v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
    return v;
}

/// Every edge used once in each direction: the surface is closed and consistently oriented.
bool closed_and_oriented(const Mesh& m) {
    std::map<std::pair<Eigen::Vector3d, Eigen::Vector3d>, int, bool (*)(const std::pair<Eigen::Vector3d, Eigen::Vector3d>&,
                                                                         const std::pair<Eigen::Vector3d, Eigen::Vector3d>&)>
        edges([](const auto& a, const auto& b) {
            for (int i = 0; i < 3; ++i) {
                if (a.first[i] != b.first[i]) return a.first[i] < b.first[i];
            }
            for (int i = 0; i < 3; ++i) {
                if (a.second[i] != b.second[i]) return a.second[i] < b.second[i];
            }
            return false;
        });
    for (const auto& t : m.triangles)
        for (int i = 0; i < 3; ++i) ++edges[{m.vertices[t[i]], m.vertices[t[(i + 1) % 3]]}];
    for (const auto& [e, n] : edges) {
        const auto it = edges.find({e.second, e.first});
        if (n != 1 || it == edges.end() || it->second != 1) return false;
    }
    return true;
}

TEST(MeshBuilder, BoxVolumeAndOrientation) {
    MeshBuilder b;
    b.box({1, 2, 3}, {0.5, 1.0, 2.0}, 0.7);
    EXPECT_NEAR(signed_volume(b.mesh()), 8 * 0.5 * 1.0 * 2.0, 1e-9);
    EXPECT_TRUE(closed_and_oriented(b.mesh()));
}

TEST(MeshBuilder, CylinderVolumeIsThePrismVolume) {
    for (const Eigen::Vector3d& axis : {Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(0, 2, 0), Eigen::Vector3d(1, 1, 1)}) {
        MeshBuilder b;
        const int n = 16;
        b.cylinder({1, -2, 0.5}, Eigen::Vector3d(1, -2, 0.5) + axis, 0.4, n);
        const double polygon = 0.5 * n * 0.4 * 0.4 * std::sin(2 * M_PI / n);
        EXPECT_NEAR(signed_volume(b.mesh()), polygon * axis.norm(), 1e-9);
        EXPECT_TRUE(closed_and_oriented(b.mesh()));
    }
}

TEST(MeshBuilder, ConeAndEllipsoidVolumes) {
    MeshBuilder c;
    const int n = 32;
    c.cone({0, 0, 0}, {0, 0, 3}, 1.0, n);
    EXPECT_NEAR(signed_volume(c.mesh()), 0.5 * n * std::sin(2 * M_PI / n) * 3 / 3.0, 1e-9);
    EXPECT_TRUE(closed_and_oriented(c.mesh()));
    MeshBuilder e;
    e.ellipsoid({2, 0, 1}, {1.0, 2.0, 0.5}, 24);
    const double exact = 4.0 / 3.0 * M_PI * 1.0 * 2.0 * 0.5;
    EXPECT_NEAR(signed_volume(e.mesh()), exact, 0.02 * exact);  // inscribed polyhedron: slightly smaller
    EXPECT_LT(signed_volume(e.mesh()), exact);
    EXPECT_TRUE(closed_and_oriented(e.mesh()));
}

TEST(MeshBuilder, HeightFieldSamplesTheFunctionAndFacesUp) {
    MeshBuilder b;
    b.height_field(0, 10, -5, 5, 0.5, [](double x, double y) { return 0.1 * x - 0.2 * y; });
    for (const auto& p : b.mesh().vertices) EXPECT_NEAR(p.z(), 0.1 * p.x() - 0.2 * p.y(), 1e-12);
    for (const auto& t : b.mesh().triangles) {
        const auto& v = b.mesh().vertices;
        EXPECT_GT((v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]).z(), 0);
    }
    EXPECT_EQ(b.mesh().triangles.size(), 2u * 20 * 20);  // 20 x 20 cells of 0.5 m
}

TEST(MeshBuilder, ReflectivityFollowsThePartsAndAppendKeepsIt) {
    MeshBuilder plain;
    plain.box_between({0, 0, 0}, {1, 1, 1});
    EXPECT_TRUE(plain.mesh().intensity.empty());  // off until set
    MeshBuilder b;
    b.box_between({0, 0, 0}, {1, 1, 1});  // before: the default
    b.set_reflectivity(0.6f);
    b.box_between({2, 0, 0}, {3, 1, 1});
    b.append(plain.mesh());  // no intensity of its own: the current one
    MeshBuilder other;
    other.set_reflectivity(0.9f);
    other.box_between({4, 0, 0}, {5, 1, 1});
    b.append(other.mesh());
    const Mesh& m = b.mesh();
    ASSERT_EQ(m.intensity.size(), m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
        const double x = m.vertices[i].x();
        const float expected = x <= 1 ? MeshBuilder::kDefaultReflectivity : x <= 3 ? 0.6f : 0.9f;
        // The appended plain box lies at x in [0, 1] too: it took 0.6.
        if (i >= 16 && i < 24) EXPECT_EQ(m.intensity[i], 0.6f) << i;
        else EXPECT_EQ(m.intensity[i], expected) << i;
    }
    EXPECT_THROW(b.set_reflectivity(1.5f), InvalidArgument);
    EXPECT_THROW(b.set_reflectivity(std::nanf("")), InvalidArgument);
    MeshBuilder late;  // a builder that only appends a reflective mesh turns reflectivity on
    late.box_between({0, 0, 0}, {1, 1, 1});
    late.append(other.mesh());
    ASSERT_EQ(late.mesh().intensity.size(), 16u);
    EXPECT_EQ(late.mesh().intensity[0], MeshBuilder::kDefaultReflectivity);
    EXPECT_EQ(late.mesh().intensity[15], 0.9f);
}

}  // namespace
