#include "lidarsurf/eval/live_staleness.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <tuple>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"

namespace lidarsurf {
namespace {
Eigen::Vector3d centroid(const Mesh& m, std::size_t t) {
    const auto& tri = m.triangles[t];
    return (m.vertices[tri[0]] + m.vertices[tri[1]] + m.vertices[tri[2]]) / 3.0;
}
}  // namespace

namespace {
// The triangles of `mesh` whose centroid lies within `radius` of `centre`, as a mesh of their own.
Mesh crop(const Mesh& mesh, const Eigen::Vector3d& centre, double radius) {
    Mesh near;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
        if ((centroid(mesh, t) - centre).norm() <= radius) {
            const auto base = static_cast<std::uint32_t>(near.vertices.size());
            for (std::uint32_t v : mesh.triangles[t]) near.vertices.push_back(mesh.vertices[v]);
            near.triangles.push_back({base, base + 1, base + 2});
        }
    return near;
}
// The area of the triangles of `mesh` whose centroid lies within `radius` of `centre`, and of
// those among them whose centroid is within `tolerance` of `other` (none when it is empty), and
// their count.
struct Areas {
    double inside = 0, near_other = 0;
    std::size_t triangles = 0;
};
Areas areas(const Mesh& mesh, const Mesh& other, const Eigen::Vector3d& centre, double radius, double tolerance) {
    std::optional<MeshDistance> distance;
    if (!other.triangles.empty()) distance.emplace(other);
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 1024), Areas{},
        [&](const auto& r, Areas acc) {
            for (std::size_t t = r.begin(); t != r.end(); ++t) {
                const Eigen::Vector3d c = centroid(mesh, t);
                if ((c - centre).norm() > radius) continue;
                const double area = mesh.triangle_area(t);
                acc.inside += area;
                ++acc.triangles;
                if (distance && distance->distance(c) <= tolerance) acc.near_other += area;
            }
            return acc;
        },
        [](Areas a, const Areas& b) { return Areas{a.inside + b.inside, a.near_other + b.near_other, a.triangles + b.triangles}; });
}
}  // namespace

Staleness measure_staleness(const Mesh& live, const Mesh& exact, const Eigen::Vector3d& centre, double radius, double tolerance) {
    if (!(radius > 0) || !(tolerance >= 0) || !centre.allFinite()) throw InvalidArgument("measure_staleness: radius > 0, tolerance >= 0, a finite centre");
    // Each mesh cropped once, to what a centroid inside the radius can be within the tolerance of:
    // a triangle within radius + tolerance + its own size (under a metre) of the centre.
    const double reach = radius + tolerance + 1.0;
    const Mesh live_near = crop(live, centre, reach), exact_near = crop(exact, centre, reach);
    const Areas of_live = areas(live_near, exact_near, centre, radius, tolerance);
    const Areas of_exact = areas(exact_near, live_near, centre, radius, tolerance);
    Staleness s;
    s.triangles = of_live.triangles;
    s.live_area = of_live.inside;
    s.stale_area = std::max(0.0, of_live.inside - of_live.near_other);
    s.exact_area = of_exact.inside;
    s.covered_area = of_exact.near_other;
    return s;
}

}  // namespace lidarsurf
