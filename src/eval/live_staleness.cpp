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
// Area of the triangles of `mesh`, and of those whose centroid is within `tolerance` of
// `other` (none when it is empty).
std::pair<double, double> area_near(const Mesh& mesh, const Mesh& other, double tolerance) {
    std::optional<MeshDistance> distance;
    if (!other.triangles.empty()) distance.emplace(other);
    using Sum = std::pair<double, double>;
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 1024), Sum{0, 0},
        [&](const auto& r, Sum acc) {
            for (std::size_t t = r.begin(); t != r.end(); ++t) {
                const double area = mesh.triangle_area(t);
                acc.first += area;
                if (distance && distance->distance(centroid(mesh, t)) <= tolerance) acc.second += area;
            }
            return acc;
        },
        [](Sum a, const Sum& b) { return Sum{a.first + b.first, a.second + b.second}; });
}
}  // namespace

Staleness measure_staleness(const Mesh& live, const Mesh& exact, const Eigen::Vector3d& centre, double radius, double tolerance) {
    if (!(radius > 0) || !(tolerance >= 0) || !centre.allFinite()) throw InvalidArgument("measure_staleness: radius > 0, tolerance >= 0, a finite centre");
    // A triangle within the tolerance of a centroid inside the radius lies within radius +
    // tolerance + its own size (under a metre) of the centre.
    const double reach = radius + tolerance + 1.0;
    const Mesh live_in = crop(live, centre, radius), exact_in = crop(exact, centre, radius);
    Staleness s;
    s.triangles = live_in.triangles.size();
    const auto [live_area, fresh_area] = area_near(live_in, crop(exact, centre, reach), tolerance);
    s.live_area = live_area;
    s.stale_area = std::max(0.0, live_area - fresh_area);
    std::tie(s.exact_area, s.covered_area) = area_near(exact_in, crop(live, centre, reach), tolerance);
    return s;
}

}  // namespace lidarsurf
