#include "lidarsurf/surface/vertex_evaluator.hpp"

#include <algorithm>
#include <cmath>

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

// Whether v at `position` is one the bridges may define: bridges on, a single scan (a grid fused
// from viewpoints has none), within bridge_range (horizontally) of the sensor.
bool may_bridge(const Eigen::Vector3d& position, const Eigen::Vector3d& sensor_local, const SurfaceConfig& config, const VoxelGrid& grid) {
    return config.bridges() && !grid.has_viewpoints() &&
           (position - sensor_local).head<2>().squaredNorm() <= config.bridge_range * config.bridge_range;
}

}  // namespace

bool rejected_by_invariants(const VoxelStats& stats, const SurfaceConfig& config) {
    // On the scatter S = n C rather than C (no division; fit_plane forms C itself): the planarity
    // bound is homogeneous of degree 2, and l3(C) > t^2 iff S - n t^2 I is positive definite.
    const Eigen::Matrix3d c = stats.scatter.full();
    if (config.min_planarity > 0) {
        const double t = c.trace();
        const double m = c(0, 0) * c(1, 1) - c(0, 1) * c(0, 1) + c(0, 0) * c(2, 2) - c(0, 2) * c(0, 2) +
                         c(1, 1) * c(2, 2) - c(1, 2) * c(1, 2);
        if (9.0 * m < (1.0 - 1e-6) * config.min_planarity * t * t) return true;
    }
    if (config.max_thickness > 0) {
        const double s = (1.0 + 1e-6) * std::pow(config.max_thickness * config.voxel_size, 2) * static_cast<double>(stats.count);
        const Eigen::Matrix3d a = c - s * Eigen::Matrix3d::Identity();
        const double det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(1, 2)) - a(0, 1) * (a(0, 1) * a(2, 2) - a(1, 2) * a(0, 2)) +
                           a(0, 2) * (a(0, 1) * a(1, 2) - a(1, 1) * a(0, 2));
        if (a(0, 0) > 0 && a(0, 0) * a(1, 1) - a(0, 1) * a(0, 1) > 0 && det > 0) return true;
    }
    return false;
}

namespace {

// The level loop of the modes (Sec. III-C1, Sec. IV-B). `stats_of(level)` gives the merged
// statistics of H^level(v); the adaptive modes call it with level = 1, 2, ... in order, so it may
// grow one accumulator shell by shell. `slab_of(level, first, e)` gives those of the slab
// S^level(v) extended by e (slab fallback, radial slabs), called with consecutive levels from the
// first slab level (`first`) and the same e, so it may grow its own accumulator likewise.
// `first_level`: the adaptive loop starts there (the levels below are known to fail Eq. (1) on
// the count, and a level failing on the count never switches to slabs, so skipping them changes
// nothing); stats_of is then first called with it.
template <typename StatsOf, typename SlabOf>
VertexSample choose_level(StatsOf&& stats_of, SlabOf&& slab_of, const Eigen::Vector3d& position, const SurfaceConfig& config,
                          const Eigen::Vector3d& sensor_local, double min_lambda2, EigenSolver solver, int first_level = 1) {
    if (!config.adaptive())  // CN, CN+GC: only H^k.
        return evaluate_level(stats_of(config.k), config.k, position, config, sensor_local, min_lambda2, solver);
    // AN, AN+GC: the smallest k in [1, k_max] that satisfies the conditions.
    int switched = 0;  // the level whose cube switched v to slabs (0: not yet)
    for (int level = first_level; level <= config.k_max && switched == 0; ++level) {
        const VoxelStats& cube = stats_of(level);
        const VertexSample s = evaluate_level(cube, level, position, config, sensor_local, min_lambda2, solver);
        if (s.defined) return s;
        // Slab fallback (docs/method.md): from level 2 on, H^k has the points but no plane,
        // typically because it reaches an object beside the ground (a larger cube reaches more
        // of it), or because it holds one scan ring of a wall. v then tries the slabs (from
        // slab_from_level: narrower slabs rarely hold two scan rings) up to k_max, and only
        // then the larger cubes (the next ring of a wall).
        if (config.slab_from_level != 0 && level >= 2 && cube.count >= static_cast<std::uint64_t>(config.n_min) &&
            std::max(level, config.slab_from_level) <= config.k_max)
            switched = level;
    }
    if (switched == 0) return {};
    const int slab_start = std::max(switched, config.slab_from_level);
    const SlabExtension extension = radial_extension(position, sensor_local, config.slab_radial_extension);
    for (int level = slab_start; level <= config.k_max; ++level) {
        const VertexSample s = evaluate_level(slab_of(level, level == slab_start, extension), level, position, config, sensor_local, min_lambda2, solver);
        if (s.defined) return s;
    }
    for (int level = switched + 1; level <= config.k_max; ++level) {
        const VertexSample s = evaluate_level(stats_of(level), level, position, config, sensor_local, min_lambda2, solver);
        if (s.defined) return s;
    }
    return {};
}

}  // namespace

VertexSample evaluate_level(const VoxelStats& stats, int level, const Eigen::Vector3d& position,
                            const SurfaceConfig& config, const Eigen::Vector3d& sensor_local, double min_lambda2,
                            EigenSolver solver) {
    if (stats.count < static_cast<std::uint64_t>(config.n_min)) return {};  // Eq. (1)
    if (solver == EigenSolver::ClosedForm && rejected_by_invariants(stats, config)) return {};
    const auto plane = fit_plane(stats, config.n_min, sensor_local, min_lambda2, config.min_planarity, solver);  // Eq. (1), (2)
    if (!plane) return {};
    const double thickness = config.max_thickness * config.voxel_size;
    if (thickness > 0 && plane->lambda3 > thickness * thickness) return {};  // not one surface
    const double confidence = gaussian_confidence(*plane, position);  // Eq. (3)
    if (config.gaussian() && confidence < config.tau) return {};
    return make_sample(*plane, position, level, confidence);
}

VertexSample evaluate_bridge(const VoxelStats& near, const VoxelStats& far, const Eigen::Vector3d& position, const SurfaceConfig& config,
                             const Eigen::Vector3d& sensor_local, double min_lambda2, EigenSolver solver) {
    // A ring on each side: half of Eq. (1) on either side of v.
    const auto half = static_cast<std::uint64_t>((config.n_min + 1) / 2);
    if (near.count < half || far.count < half) return {};
    VoxelStats both = near;
    both.merge(far);
    // No planarity guard here: two rings far apart are a long, narrow plane (lambda2 / lambda1
    // below the guard); one line is told apart by the spread across the boxes instead.
    const auto plane = fit_plane(both, config.n_min, sensor_local, min_lambda2, 0.0, solver);  // Eq. (2)
    if (!plane) return {};
    const double width = config.k_max * config.voxel_size;  // the boxes are 2 k_max voxels wide
    if (plane->lambda2 < config.min_planarity * plane->lambda1 && plane->lambda2 < width * width / 12) return {};  // one line
    const double thickness = config.max_thickness > 0 ? config.max_thickness * config.voxel_size : config.voxel_size;
    if (plane->lambda3 > thickness * thickness) return {};  // not one surface
    // Both sides on the plane (the rings agree), and the plane ground-like (z up).
    if (std::abs(signed_distance(*plane, near.mean)) > thickness || std::abs(signed_distance(*plane, far.mean)) > thickness) return {};
    if (std::abs(plane->normal.z()) < kBridgeMinNormalZ) return {};
    // Eq. (3) is not required; the confidence stays below tau: inferred surface.
    const double confidence = std::min(gaussian_confidence(*plane, position), std::nextafter(config.tau, 0.0));
    return make_sample(*plane, position, config.k_max, confidence);
}

Eigen::Vector3d vertex_viewpoint(const VoxelGrid& grid, const VoxelKey& v, const SurfaceConfig& config,
                                 const Eigen::Vector3d& sensor_local) {
    if (!grid.has_viewpoints()) return sensor_local;
    const int level = config.max_level();  // H^level(v) = [v - level, v + level - 1]
    return grid.mean_viewpoint(v.array() - level, v.array() + (level - 1)).value_or(sensor_local);
}

VertexSample evaluate_vertex(const VoxelGrid& grid, const VoxelKey& v, const SurfaceConfig& config,
                             const Eigen::Vector3d& sensor) {
    const Eigen::Vector3d sensor_local = vertex_viewpoint(grid, v, config, sensor);
    VoxelStats acc, slab;
    auto stats_of = [&](int level) -> const VoxelStats& {
        if (config.adaptive())
            grow_neighbourhood(grid, v, level, acc);
        else
            acc = merge_neighbourhood(grid, v, level);
        return acc;
    };
    auto slab_of = [&](int level, bool, SlabExtension e) -> const VoxelStats& {  // merged whole at every level: the simple way
        slab = merge_box(grid, slab_box(v, level, e));
        return slab;
    };
    const Eigen::Vector3d position = v.cast<double>() * grid.voxel_size();
    const VertexSample s = choose_level(stats_of, slab_of, position, config, sensor_local, degenerate_lambda2(grid.voxel_size()), EigenSolver::Iterative);
    if (s.defined || !may_bridge(position, sensor_local, config, grid)) return s;
    const auto boxes = bridge_boxes(v, config.k_max, config.bridge_extent(), position, sensor_local);
    return evaluate_bridge(merge_box(grid, boxes[0]), merge_box(grid, boxes[1]), position, config, sensor_local,
                           degenerate_lambda2(grid.voxel_size()), EigenSolver::Iterative);
}

namespace {

VertexSample evaluate_windowed(const NeighbourhoodWindow& window, const VoxelKey& v, const SurfaceConfig& config,
                               const Eigen::Vector3d& sensor, EigenSolver solver) {
    const Eigen::Vector3d sensor_local = vertex_viewpoint(window.grid(), v, config, sensor);
    const Eigen::Vector3d position = v.cast<double>() * window.voxel_size();
    auto stats = [&](const Moments& m) {
        if (m.n < config.n_min) {  // Eq. (1) fails: only the count is read
            VoxelStats few;
            few.count = static_cast<std::uint64_t>(m.n);
            return few;
        }
        return m.to_stats(position);
    };
    Moments acc, slab;
    // The adaptive modes start at the first level whose cube can hold N_min points, summed whole,
    // then grow shell by shell (docs/method.md, "Levels that fail on the count").
    const int counted = config.adaptive() ? window.first_counted_level(v, config.n_min) : 1;
    auto stats_of = [&](int level) {
        if (config.adaptive() && level > counted)
            window.grow(v, level, acc);
        else
            acc = window.box(v, level);
        return stats(acc);
    };
    auto slab_of = [&](int level, bool first, SlabExtension e) {
        if (first)
            slab = window.slab(v, level, e);
        else
            window.grow_slab(v, level, slab, e);
        return stats(slab);
    };
    const VertexSample s = choose_level(stats_of, slab_of, position, config, sensor_local, degenerate_lambda2(window.voxel_size()), solver, counted);
    if (s.defined || !may_bridge(position, sensor_local, config, window.grid())) return s;
    const auto boxes = bridge_boxes(v, config.k_max, config.bridge_extent(), position, sensor_local);
    return evaluate_bridge(window.sum_box(boxes[0], v).to_stats(position), window.sum_box(boxes[1], v).to_stats(position), position, config,
                           sensor_local, degenerate_lambda2(window.voxel_size()), solver);
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(LIDARSURF_SCALAR)
#define LIDARSURF_EVALUATE_V3 1
// The same evaluation compiled for the Avx2 level (core/simd.hpp), everything it calls inlined
// (flatten): the scalar double arithmetic of the fits in VEX encoding (three operands, so most of
// its register copies go) and the window's AVX2 walk inline. AVX2 brings no FMA: the same
// operations, so the same bits as the baseline build (tests/surface/test_vertex_evaluator.cpp).
[[gnu::target(LIDARSURF_AVX2_TARGET), gnu::flatten]] VertexSample evaluate_windowed_v3(const NeighbourhoodWindow& window, const VoxelKey& v,
                                                                                     const SurfaceConfig& config,
                                                                                     const Eigen::Vector3d& sensor, EigenSolver solver) {
    return evaluate_windowed(window, v, config, sensor, solver);
}
#endif

}  // namespace

VertexSample evaluate_vertex(const NeighbourhoodWindow& window, const VoxelKey& v, const SurfaceConfig& config,
                             const Eigen::Vector3d& sensor, EigenSolver solver) {
#if defined(LIDARSURF_EVALUATE_V3)
    if (window.simd() >= SimdLevel::Avx2) return evaluate_windowed_v3(window, v, config, sensor, solver);
#endif
    return evaluate_windowed(window, v, config, sensor, solver);
}

}  // namespace lidarsurf
