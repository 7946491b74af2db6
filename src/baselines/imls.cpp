#include "lidarsurf/baselines/imls.hpp"

#include <chrono>
#include <cstdio>
#include <cmath>
#include <string>

#include <Eigen/Eigenvalues>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/core/format_value.hpp"
#include "lidarsurf/core/stopwatch.hpp"

namespace lidarsurf {

std::string ImlsSummary::to_string() const {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "points %zu (dropped %zu non-finite), vertices evaluated %zu, defined %zu, mesh %zu vertices %zu triangles; "
                  "time normals %.1f ms, field %.1f ms, mesh %.1f ms (r %.3g m, k %d, h %.3g m)",
                  points, dropped, candidates, defined, mesh_vertices, mesh_triangles, 1e3 * seconds_normals, 1e3 * seconds_field,
                  1e3 * seconds_mesh, radius, normal_k, bandwidth);
    return buf;
}

ImlsConfig ImlsConfig::matching(const SurfaceConfig& config, int threads) {
    ImlsConfig c;
    c.voxel_size = config.voxel_size;
    c.radius = config.voxel_size * config.max_level();
    c.normal_k = config.n_min;
    c.bandwidth = c.radius / 3.0;
    c.threads = threads;
    return c;
}

void ImlsConfig::validate() const {
    auto fail = [](const std::string& m) { throw InvalidArgument("imls: " + m); };
    if (!std::isfinite(voxel_size) || voxel_size < 1e-4 || voxel_size > 1e3)
        fail("voxel size must be within [1e-4, 1e3] m (got " + format_value(voxel_size) + ")");
    if (!std::isfinite(radius) || radius <= 0) fail("radius must be finite and > 0 (got " + format_value(radius) + ")");
    if (radius > kMaxNeighbourhoodLevel * voxel_size)
        fail("radius must be at most " + format_value(kMaxNeighbourhoodLevel) + " voxels (got " + format_value(radius) + " m)");
    if (normal_k < 3 || normal_k > 1000) fail("normal k must be in [3, 1000] (got " + format_value(normal_k) + ")");
    if (!std::isfinite(bandwidth) || bandwidth <= 0) fail("bandwidth h must be finite and > 0 (got " + format_value(bandwidth) + ")");
    if (!std::isfinite(truncation_voxels) || truncation_voxels < 0)
        fail("truncation must be finite and >= 0 voxels (got " + format_value(truncation_voxels) + ")");
    if (truncation_voxels > 0 && truncation_voxels < 0.8660254037844386)
        fail("truncation below sqrt(3)/2 voxels would cut surfaces crossing a cube (got " + format_value(truncation_voxels) + ")");
    if (threads < 0 || threads > 1024) fail("threads must be in [0, 1024] (got " + format_value(threads) + ")");
}

std::vector<Eigen::Vector3d> estimate_normals(const KdTree& tree, int k, const Eigen::Vector3d& sensor) {
    const auto& pts = tree.points();
    std::vector<Eigen::Vector3d> normals(pts.size(), Eigen::Vector3d::Zero());
    tbb::enumerable_thread_specific<std::vector<Neighbour>> scratch;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pts.size(), 512), [&](const auto& r) {
        auto& nb = scratch.local();
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            tree.knn(pts[i], static_cast<std::size_t>(k), nb);
            if (nb.size() < 3) continue;
            // Centred around the query point for precision, then shifted to the mean.
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
            for (const Neighbour& n : nb) {
                const Eigen::Vector3d d = pts[n.index] - pts[i];
                sum += d;
                outer += d * d.transpose();
            }
            const double m = static_cast<double>(nb.size());
            const Eigen::Vector3d mean = sum / m;
            const Eigen::Matrix3d cov = outer / m - mean * mean.transpose();
            Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
            const Eigen::Vector3d ev = solver.eigenvalues();  // ascending
            // Same degeneracy rule as the voxel planes: no second direction, no plane.
            if (!(ev[1] > 1e-12 * (ev[2] + 1e-30)) || !(ev[2] > 0)) continue;
            Eigen::Vector3d n = solver.eigenvectors().col(0);
            if (n.dot(sensor - pts[i]) < 0) n = -n;  // toward the sensor, as Eq. (2)
            normals[i] = n;
        }
    });
    return normals;
}

ImlsFunction::ImlsFunction(const KdTree& tree, std::vector<Eigen::Vector3d> normals, double radius, double bandwidth)
    : tree_(tree), normals_(std::move(normals)), radius_(radius), inv_h2_(1.0 / (bandwidth * bandwidth)) {
    if (normals_.size() != tree.size()) throw InvalidArgument("imls: one normal per point is required");
}

VertexSample ImlsFunction::evaluate(const Eigen::Vector3d& x, std::vector<Neighbour>& scratch) const {
    VertexSample s;
    tree_.radius(x, radius_, scratch);
    double num = 0, den = 0;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    const auto& pts = tree_.points();
    for (const Neighbour& nb : scratch) {
        const Eigen::Vector3d& n = normals_[nb.index];
        if (n.isZero()) continue;
        const double theta = std::exp(-nb.squared_distance * inv_h2_);
        num += theta * (x - pts[nb.index]).dot(n);
        den += theta;
        normal += theta * n;
    }
    if (!(den > 0)) return s;
    s.defined = true;
    s.tsdf = static_cast<float>(num / den);
    s.level = 0;
    s.confidence = static_cast<float>(den);
    const double len = normal.norm();
    if (len > 0) s.normal = (normal / len).cast<float>();
    return s;
}

Mesh reconstruct_imls(const PointCloud& cloud, const Eigen::Vector3d& sensor, const ImlsConfig& config, ImlsSummary* summary) {
    config.validate();
    if (!sensor.allFinite()) throw InvalidArgument("sensor origin must be finite");
    ImlsSummary sum;
    sum.points = cloud.points.size();
    // The lattice: the same voxel grid (and local origin) as the paper's method would use.
    VoxelGrid grid(config.voxel_size);
    std::vector<Eigen::Vector3d> local;
    local.reserve(cloud.points.size());
    for (const auto& p : cloud.points) {
        if (!p.allFinite()) {
            ++sum.dropped;
            continue;
        }
        grid.insert(p);
        local.push_back(grid.to_local(p));
    }
    if (local.empty())
        throw InvalidInput(sum.points == 0 ? "the input has no points" : "the input has no finite point (all " + format_value(sum.points) + " dropped)");

    Mesh mesh;
    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        auto t0 = std::chrono::steady_clock::now();
        const KdTree tree(std::move(local));
        const Eigen::Vector3d sensor_local = grid.to_local(sensor);
        ImlsFunction f(tree, estimate_normals(tree, config.normal_k, sensor_local), config.radius, config.bandwidth);
        sum.seconds_normals = seconds_since(t0);

        t0 = std::chrono::steady_clock::now();
        // A vertex within r of a point has that point's voxel in H^{ceil(r/alpha)}(v).
        const int level = static_cast<int>(std::ceil(config.radius / config.voxel_size - 1e-9));
        const std::vector<VoxelKey> candidates = candidate_vertices(grid, std::max(level, 1));
        std::vector<VertexSample> samples(candidates.size());
        tbb::enumerable_thread_specific<std::vector<Neighbour>> scratch;
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 256), [&](const auto& r) {
            auto& nb = scratch.local();
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                samples[i] = f.evaluate(candidates[i].cast<double>() * config.voxel_size, nb);
        });
        const double truncation = truncation_distance_of(config.truncation_voxels, config.voxel_size);
        TsdfStats stats;
        const TsdfField field = assemble_field(grid, candidates, samples, Truncation{truncation}, &stats);
        sum.candidates = stats.candidates;
        sum.defined = stats.defined;
        sum.seconds_field = seconds_since(t0);

        t0 = std::chrono::steady_clock::now();
        mesh = extract_mesh(field);
        sum.seconds_mesh = seconds_since(t0);
    });
    sum.mesh_vertices = mesh.vertices.size();
    sum.mesh_triangles = mesh.triangles.size();
    sum.radius = config.radius;
    sum.bandwidth = config.bandwidth;
    sum.normal_k = config.normal_k;
    if (summary) *summary = sum;
    return mesh;
}

}  // namespace lidarsurf
