// Simplification (mesh/simplify.hpp) against analytic surfaces: a flat square needs no more than
// the triangles of its outline, a curved height field stays within the error of the function it
// samples, the outline is kept vertex for vertex, and a map far from the origin simplifies as one
// at the origin.
#include <gtest/gtest.h>

#include <cmath>

#include "lidarsurf/mesh/simplify.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

// The grid of n x n quads of side h over [0, n h]^2 at height f(x, y), counter-clockwise seen from
// above; each vertex's confidence encodes its position (i + 1000 j), so attributes can be followed.
template <typename F>
Mesh height_field(int n, double h, F&& f, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
    Mesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const double x = i * h, y = j * h;
            m.vertices.push_back(offset + Eigen::Vector3d(x, y, f(x, y)));
            m.normals.emplace_back(0.f, 0.f, 1.f);
            m.levels.push_back(static_cast<std::uint8_t>(i % 7));
            m.confidence.push_back(static_cast<float>(i + 1000 * j));
        }
    auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return m;
}

// Each vertex's attributes still are those of the grid vertex at its position.
void expect_attributes_follow(const Mesh& m, int n, double h, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
    ASSERT_EQ(m.confidence.size(), m.vertices.size());
    for (std::size_t v = 0; v < m.vertices.size(); ++v) {
        const int i = static_cast<int>(std::lround((m.vertices[v].x() - offset.x()) / h));
        const int j = static_cast<int>(std::lround((m.vertices[v].y() - offset.y()) / h));
        ASSERT_TRUE(i >= 0 && i <= n && j >= 0 && j <= n);
        EXPECT_EQ(m.confidence[v], static_cast<float>(i + 1000 * j));
        EXPECT_EQ(m.levels[v], static_cast<std::uint8_t>(i % 7));
    }
}

double area(const Mesh& m) {
    double a = 0;
    for (std::size_t i = 0; i < m.triangles.size(); ++i) a += m.triangle_area(i);
    return a;
}

}  // namespace

TEST(Simplify, AFlatSquareKeepsItsOutlineAndLittleElse) {
    const int n = 60;
    const double h = 0.1;
    Mesh m = height_field(n, h, [](double, double) { return 0.0; });
    const auto outline = test::open_edges(m);
    const std::size_t before = m.triangles.size();
    const std::size_t removed = simplify_mesh(m, 0.02);
    EXPECT_NO_THROW(m.check());
    EXPECT_EQ(removed, before - m.triangles.size());
    // A polygon of 4 n outline vertices needs 4 n - 2 triangles; twice that leaves room for a few
    // interior vertices the collapse keeps.
    EXPECT_LE(m.triangles.size(), 2u * 4 * n);
    EXPECT_TRUE(test::open_edges(m) == outline) << "the outline is kept edge for edge";
    EXPECT_NEAR(area(m), (n * h) * (n * h), 1e-9);
    for (const auto& t : m.triangles) {  // the orientation is kept: no triangle faces down
        const Eigen::Vector3d normal = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
        EXPECT_GE(normal.z(), 0);
    }
    expect_attributes_follow(m, n, h);
}

TEST(Simplify, ACurvedSurfaceStaysWithinTheErrorOfTheFunctionItSamples) {
    // z = A sin(x / L) cos(y / L) sampled every 5 cm: the full mesh's chord error, h^2 A / (8 L^2),
    // is 0.3 mm, so the simplified surface's distance to the function is its own error.
    const int n = 120;
    const double h = 0.05, A = 0.5, L = 1.0;
    auto f = [&](double x, double y) { return A * std::sin(x / L) * std::cos(y / L); };
    for (const double error : {0.005, 0.02, 0.05}) {
        Mesh m = height_field(n, h, f);
        const std::size_t before = m.triangles.size();
        simplify_mesh(m, error);
        EXPECT_LT(m.triangles.size(), before / 2) << error;
        // Vertical distance on a 9-point pattern of each triangle (its slope is below 0.5, so the
        // distance to the surface is at least 0.89 of it); the error with 50 % margin for the
        // quadric metric's approximation of the distance.
        double worst = 0;
        for (const auto& t : m.triangles)
            for (const auto& [a, b] : {std::pair{1.0 / 3, 1.0 / 3}, {0.5, 0.0}, {0.0, 0.5}, {0.5, 0.5}, {0.25, 0.25}, {0.5, 0.25}, {0.25, 0.5}, {0.1, 0.1}, {0.8, 0.1}}) {
                const Eigen::Vector3d p = m.vertices[t[0]] + a * (m.vertices[t[1]] - m.vertices[t[0]]) + b * (m.vertices[t[2]] - m.vertices[t[0]]);
                worst = std::max(worst, std::abs(p.z() - f(p.x(), p.y())));
            }
        EXPECT_LE(worst, error) << error;
        expect_attributes_follow(m, n, h);
    }
}

TEST(Simplify, AMapFarFromTheOriginSimplifiesAsOneAtTheOrigin) {
    const int n = 80;
    const double h = 0.1;
    auto f = [](double x, double y) { return 0.3 * std::sin(x) + 0.1 * y; };
    const Eigen::Vector3d utm(512345.0, 5412345.0, 300.0);  // UTM metres: beyond float's millimetres
    Mesh here = height_field(n, h, f), there = height_field(n, h, f, utm);
    simplify_mesh(here, 0.02);
    simplify_mesh(there, 0.02);
    ASSERT_EQ(here.triangles.size(), there.triangles.size());
    EXPECT_TRUE(here.triangles == there.triangles);
    expect_attributes_follow(there, n, h, utm);
}

TEST(Simplify, NoErrorOrNoTrianglesLeavesTheMeshAsItIs) {
    Mesh m = height_field(10, 0.1, [](double x, double) { return x * x; });
    const Mesh full = m;
    EXPECT_EQ(simplify_mesh(m, 0.0), 0u);
    EXPECT_TRUE(m.triangles == full.triangles && m.vertices == full.vertices);
    Mesh empty;
    EXPECT_EQ(simplify_mesh(empty, 0.02), 0u);
}
