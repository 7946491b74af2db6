#include "lidarsurf/pipeline.hpp"

#include <chrono>
#include <cstdio>

#include <tbb/task_arena.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"

namespace lidarsurf {
namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
const ReconstructionConfig& validated(const ReconstructionConfig& c) {
    c.validate();
    return c;
}
}  // namespace

std::string ReconstructionSummary::to_string() const {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "points %zu (dropped %zu non-finite), voxels %zu, vertices evaluated %zu, defined %zu, "
                  "mesh %zu vertices %zu triangles; time insert %.1f ms, tsdf %.1f ms, mesh %.1f ms, total %.1f ms",
                  points_read, points_dropped, voxels, candidate_vertices, defined_vertices, mesh_vertices, mesh_triangles,
                  1e3 * seconds_insert, 1e3 * seconds_tsdf, 1e3 * seconds_mesh,
                  1e3 * (seconds_insert + seconds_tsdf + seconds_mesh));
    return buf;
}

Reconstructor::Reconstructor(const ReconstructionConfig& config, const Eigen::Vector3d& sensor)
    : config_(validated(config)), sensor_(sensor), grid_(config.voxel_size) {
    if (!sensor.allFinite()) throw InvalidArgument("sensor origin must be finite");
}

void Reconstructor::integrate(const PointCloud& cloud) { integrate(std::span<const Eigen::Vector3d>(cloud.points)); }

void Reconstructor::integrate(std::span<const Eigen::Vector3d> points) {
    const auto t0 = std::chrono::steady_clock::now();
    summary_.points_read += points.size();
    for (const auto& p : points) {
        if (!p.allFinite()) {
            ++summary_.points_dropped;
            continue;
        }
        grid_.insert(p);
    }
    summary_.voxels = grid_.size();
    summary_.seconds_insert += seconds_since(t0);
}

Mesh Reconstructor::extract_mesh(Evaluation evaluation) {
    if (grid_.point_count() == 0)
        throw InvalidInput(summary_.points_read == 0 ? "the input has no points"
                                                     : "the input has no finite point (all " + std::to_string(summary_.points_read) + " dropped)");
    tbb::task_arena arena(config_.threads > 0 ? config_.threads : tbb::task_arena::automatic);
    Mesh mesh;
    arena.execute([&] {
        auto t0 = std::chrono::steady_clock::now();
        if (config_.seeded_surface && evaluation == Evaluation::Fast) {
            const SeededTsdf seeded = compute_seeded_tsdf(grid_, config_, sensor_);
            summary_.seconds_tsdf = seconds_since(t0);
            summary_.candidate_vertices = seeded.evaluated;
            summary_.defined_vertices = seeded.field.size();
            t0 = std::chrono::steady_clock::now();
            mesh = lidarsurf::extract_mesh(seeded.field, seeded.cubes);
        } else {
            TsdfStats stats;
            const TsdfField field = compute_tsdf(grid_, config_, sensor_, &stats);
            summary_.candidate_vertices = stats.candidates;
            summary_.defined_vertices = stats.defined;
            if (config_.seeded_surface) {
                const std::vector<VoxelKey> cubes = seeded_cubes(field, grid_, config_.seed_dilation);
                summary_.seconds_tsdf = seconds_since(t0);
                t0 = std::chrono::steady_clock::now();
                mesh = lidarsurf::extract_mesh(field, cubes);
            } else {
                summary_.seconds_tsdf = seconds_since(t0);
                t0 = std::chrono::steady_clock::now();
                mesh = lidarsurf::extract_mesh(field);
            }
        }
        summary_.seconds_mesh = seconds_since(t0);
    });
    summary_.mesh_vertices = mesh.vertices.size();
    summary_.mesh_triangles = mesh.triangles.size();
    return mesh;
}

Mesh reconstruct(const PointCloud& cloud, const Eigen::Vector3d& sensor, const ReconstructionConfig& config,
                 ReconstructionSummary* summary) {
    Reconstructor r(config, sensor);
    r.integrate(cloud);
    Mesh mesh = r.extract_mesh();
    if (summary) *summary = r.summary();
    return mesh;
}

}  // namespace lidarsurf
