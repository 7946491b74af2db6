// Point-to-triangle and point-to-mesh distance against brute force.
#include <gtest/gtest.h>

#include <random>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"

using namespace lidarsurf;

namespace {
// Oracle: the minimum over a dense barycentric grid of the triangle (error <= grid spacing).
double dense_triangle_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                               int n) {
    double best = 1e300;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; i + j <= n; ++j) {
            const double u = double(i) / n, v = double(j) / n;
            best = std::min(best, (a + u * (b - a) + v * (c - a) - p).norm());
        }
    return best;
}
}  // namespace

TEST(MeshDistance, ClosestPointOnTriangleKnownRegions) {
    const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    EXPECT_TRUE(closest_point_on_triangle({0.2, 0.2, 3}, a, b, c).isApprox(Eigen::Vector3d(0.2, 0.2, 0)));  // face
    EXPECT_TRUE(closest_point_on_triangle({-1, -1, 0}, a, b, c).isApprox(a));                                // vertex
    EXPECT_TRUE(closest_point_on_triangle({0.5, -2, 1}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0, 0)));     // edge ab
    EXPECT_TRUE(closest_point_on_triangle({1, 1, 0}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.5, 0)));      // edge bc
    // Degenerate: all three corners on a line.
    const Eigen::Vector3d q = closest_point_on_triangle({0.5, 1, 0}, a, b, {2, 0, 0});
    EXPECT_NEAR((q - Eigen::Vector3d(0.5, 0, 0)).norm(), 0, 1e-12);
}

TEST(MeshDistance, TriangleDistanceMatchesDenseSampling) {
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int trial = 0; trial < 200; ++trial) {
        const Eigen::Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
        const Eigen::Vector3d p = 2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
        const double exact = (closest_point_on_triangle(p, a, b, c) - p).norm();
        const double dense = dense_triangle_distance(p, a, b, c, 300);
        EXPECT_LE(exact, dense + 1e-12);          // never farther than a point of the triangle
        EXPECT_GE(exact, dense - 8.0 / 300);      // and the dense minimum is within its grid step
    }
}

TEST(MeshDistance, BvhMatchesLinearScanOverTriangles) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-5, 5), s(-0.3, 0.3);
    Mesh mesh;
    for (int t = 0; t < 400; ++t) {
        const Eigen::Vector3d c(u(rng), u(rng), 0.2 * u(rng));
        const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
        for (int k = 0; k < 3; ++k) mesh.vertices.push_back(c + Eigen::Vector3d(s(rng), s(rng), s(rng)));
        mesh.triangles.push_back({base, base + 1, base + 2});
    }
    const MeshDistance dist(mesh);
    for (int q = 0; q < 300; ++q) {
        const Eigen::Vector3d p(1.5 * u(rng), 1.5 * u(rng), u(rng));
        double best = 1e300;
        for (const auto& t : mesh.triangles)
            best = std::min(best, (closest_point_on_triangle(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]) - p).norm());
        const SurfacePoint sp = dist.closest(p);
        EXPECT_DOUBLE_EQ(sp.distance, best);
        EXPECT_NEAR((sp.point - p).norm(), sp.distance, 1e-12);
    }
}

TEST(MeshDistance, EmptyMeshIsAnError) {
    EXPECT_THROW(MeshDistance(Mesh{}), InvalidInput);
}
