#include "lidarsurf/mesh/simplify.hpp"

#include <array>
#include <cstdint>
#include <vector>

#include <meshoptimizer.h>

namespace lidarsurf {
namespace {
// meshoptimizer's error is its quadric metric's estimate at the collapsed vertices; between them
// the surface strays further (on a curved height field, 1.2-2.2 times the target between 5 and
// 50 mm). This share of max_error keeps that field within max_error (tests/mesh/test_simplify.cpp);
// another reaches 1.28 max_error at 20 mm (docs/method.md, "Simplification").
constexpr double kTargetShare = 0.4;
}  // namespace

std::size_t simplify_mesh(Mesh& mesh, double max_error) {
    if (!(max_error > 0) || mesh.triangles.empty()) return 0;
    mesh.check();
    // meshoptimizer reads float positions: relative to the mesh's lowest corner, so that a map in
    // a large world frame (UTM metres) keeps millimetres.
    Eigen::Vector3d origin = mesh.vertices.front();
    for (const Eigen::Vector3d& v : mesh.vertices) origin = origin.cwiseMin(v);
    std::vector<float> positions;
    positions.reserve(3 * mesh.vertices.size());
    for (const Eigen::Vector3d& v : mesh.vertices)
        for (int a = 0; a < 3; ++a) positions.push_back(static_cast<float>(v[a] - origin[a]));
    std::vector<unsigned int> indices;
    indices.reserve(3 * mesh.triangles.size());
    for (const auto& t : mesh.triangles) indices.insert(indices.end(), t.begin(), t.end());

    constexpr std::size_t kStride = 3 * sizeof(float);
    const float scale = meshopt_simplifyScale(positions.data(), mesh.vertices.size(), kStride);
    if (!(scale > 0)) return 0;  // every vertex at one point
    std::vector<unsigned int> kept(indices.size());
    // Target 0 triangles: as far as the error allows.
    const std::size_t count = meshopt_simplify(kept.data(), indices.data(), indices.size(), positions.data(), mesh.vertices.size(), kStride, 0,
                                               static_cast<float>(kTargetShare * max_error / scale), meshopt_SimplifyLockBorder, nullptr);
    std::vector<std::array<std::uint32_t, 3>> triangles(count / 3);
    for (std::size_t i = 0; i < triangles.size(); ++i) triangles[i] = {kept[3 * i], kept[3 * i + 1], kept[3 * i + 2]};
    const std::size_t removed = mesh.triangles.size() - triangles.size();
    if (removed > 0) mesh.keep_triangles(std::move(triangles));
    return removed;
}

}  // namespace lidarsurf
