#include "lidarsurf/surface/vertex_evaluator.hpp"

#include "lidarsurf/surface/gaussian_confidence.hpp"
#include "lidarsurf/surface/local_plane.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"

namespace lidarsurf {

double degenerate_lambda2(double voxel_size) { return 1e-12 * voxel_size * voxel_size; }

namespace {

VertexSample make_sample(const LocalPlane& plane, const Eigen::Vector3d& v, int level, double confidence) {
    VertexSample s;
    s.defined = true;
    s.tsdf = static_cast<float>(signed_distance(plane, v));  // Eq. (4)
    s.level = static_cast<std::uint8_t>(level);
    s.confidence = static_cast<float>(confidence);
    s.normal = plane.normal.cast<float>();
    return s;
}

}  // namespace

VertexSample evaluate_vertex(const VoxelGrid& grid, const VoxelKey& v, const ReconstructionConfig& config,
                             const Eigen::Vector3d& sensor_local) {
    const Eigen::Vector3d position = v.cast<double>() * grid.voxel_size();
    const double min_lambda2 = degenerate_lambda2(grid.voxel_size());

    // Tests one level; returns a defined sample when the mode's conditions hold at that level.
    auto try_level = [&](const VoxelStats& stats, int level) -> VertexSample {
        const auto plane = fit_plane(stats, config.n_min, sensor_local, min_lambda2, config.min_planarity);  // Eq. (1), (2)
        if (!plane) return {};
        const double confidence = gaussian_confidence(*plane, position);  // Eq. (3)
        if (config.gaussian() && confidence < config.tau) return {};
        return make_sample(*plane, position, level, confidence);
    };

    if (!config.adaptive()) {  // CN, CN+GC: only H^k.
        return try_level(merge_neighbourhood(grid, v, config.k), config.k);
    }
    // AN, AN+GC: the smallest k in [1, k_max] that satisfies the conditions (Sec. III-C1).
    VoxelStats acc;
    for (int level = 1; level <= config.k_max; ++level) {
        grow_neighbourhood(grid, v, level, acc);
        VertexSample s = try_level(acc, level);
        if (s.defined) return s;
    }
    return {};
}

}  // namespace lidarsurf
