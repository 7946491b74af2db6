#include "lidarsurf/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <tbb/task_arena.h>

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/mesh/mesh_filter.hpp"
#include "lidarsurf/mesh/simplify.hpp"
#include "lidarsurf/mesh/vertex_intensity.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"
#include "lidarsurf/core/format_value.hpp"
#include "lidarsurf/core/stopwatch.hpp"

namespace lidarsurf {
namespace {
// The work of a call runs in an arena of config.threads workers (0: every core).
tbb::task_arena arena_of(const RunConfig& run) { return tbb::task_arena(run.threads > 0 ? run.threads : tbb::task_arena::automatic); }
const ReconstructionConfig& validated(const ReconstructionConfig& c) {
    c.validate();
    return c;
}
}  // namespace

std::string ReconstructionSummary::to_string() const {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "points %zu (dropped %zu non-finite), voxels %zu, vertices evaluated %zu (reused %zu), defined %zu, "
                  "mesh %zu vertices %zu triangles, memory estimate %.0f MiB; time insert %.1f ms, tsdf %.1f ms, mesh %.1f ms, total %.1f ms",
                  points_read, points_dropped, voxels, candidate_vertices, reused_vertices, defined_vertices, mesh_vertices, mesh_triangles,
                  static_cast<double>(memory_estimate) / 1048576.0,
                  1e3 * seconds_insert, 1e3 * seconds_tsdf, 1e3 * seconds_mesh,
                  1e3 * seconds_total());
    if (seconds_carve > 0 || carved_voxels > 0) {
        char carve[128];
        std::snprintf(carve, sizeof carve, "; carving %.1f ms, %zu voxels carved", 1e3 * seconds_carve, carved_voxels);
        return buf + std::string(carve);
    }
    return buf;
}

Reconstructor::Reconstructor(const ReconstructionConfig& config, const Eigen::Vector3d& sensor, const std::optional<Eigen::Vector3d>& grid_origin)
    : config_(validated(config)), sensor_(sensor), grid_(config.voxel_size, grid_origin), last_viewpoint_(sensor) {
    if (!sensor.allFinite()) throw InvalidArgument("sensor origin must be finite");
}

void Reconstructor::integrate(const PointCloud& cloud) { integrate(std::span<const Eigen::Vector3d>(cloud.points), cloud.intensities); }

void Reconstructor::integrate(std::span<const Eigen::Vector3d> points, std::span<const float> intensity) {
    add(points, grid_.has_viewpoints() ? std::optional<Eigen::Vector3d>(sensor_) : std::nullopt, points, {}, intensity);
}

void Reconstructor::integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint) {
    integrate_seen(points, viewpoint, points, {}, {});
}

void Reconstructor::integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint,
                              std::span<const Eigen::Vector3f> no_return, std::span<const float> intensity) {
    integrate_seen(points, viewpoint, points, no_return, intensity);
}

void Reconstructor::integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, const Eigen::AlignedBox3d& keep,
                              std::span<const Eigen::Vector3f> no_return, std::span<const float> intensity) {
    integrate_kept(points, viewpoint, keep, no_return, intensity, nullptr);
}

void Reconstructor::integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, const Eigen::AlignedBox3d& keep,
                              const RangeImage& image, std::span<const float> intensity) {
    integrate_kept(points, viewpoint, keep, {}, intensity, &image);
}

void Reconstructor::integrate_kept(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, const Eigen::AlignedBox3d& keep,
                                   std::span<const Eigen::Vector3f> no_return, std::span<const float> intensity, const RangeImage* image) {
    if (!intensity.empty() && intensity.size() != points.size())
        throw InvalidArgument("intensity: " + std::to_string(intensity.size()) + " values for " + std::to_string(points.size()) + " points");
    std::vector<Eigen::Vector3d> kept;
    std::vector<float> kept_intensity;
    for (std::size_t i = 0; i < points.size(); ++i)
        if (keep.contains(points[i])) {  // a non-finite point is in no box
            kept.push_back(points[i]);
            if (!intensity.empty()) kept_intensity.push_back(intensity[i]);
        }
    // summary().points_read counts the points kept.
    integrate_seen(kept, viewpoint, points, no_return, kept_intensity, image);
}

void Reconstructor::integrate_seen(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint,
                                   std::span<const Eigen::Vector3d> scan, std::span<const Eigen::Vector3f> no_return,
                                   std::span<const float> intensity, const RangeImage* image) {
    if (!viewpoint.allFinite()) throw InvalidArgument("viewpoint must be finite");
    if (!grid_.has_viewpoints()) {
        grid_.enable_viewpoints(sensor_);  // the points integrated before were seen from the sensor
        if (grid_.point_count() > 0) previous_.reset();  // every orientation may change: evaluate all again
    }
    add(points, viewpoint, scan, no_return, intensity, image);
    last_viewpoint_ = viewpoint;
}

void Reconstructor::skip_scan() {
    if (carver_) carver_->skip();
    else ++skipped_scans_;
}

void Reconstructor::ensure_carver() {
    if (carver_) return;
    carver_.emplace(config_.carving(), config_.voxel_size);
    carver_->skip(skipped_scans_);
    skipped_scans_ = 0;
}

MeshDelta Reconstructor::update_mesh(double budget_ms) {
    if (!std::isfinite(budget_ms)) throw InvalidArgument("update_mesh: the budget must be finite (<= 0: no limit)");
    if (!live_) live_.emplace(surface_config(true), config_.live());
    tbb::task_arena arena = arena_of(config_);
    return arena.execute([&] { return live_->update(grid_, sensor_, last_viewpoint_, budget_ms / 1e3); });
}

void Reconstructor::add(std::span<const Eigen::Vector3d> points, const std::optional<Eigen::Vector3d>& seen_from,
                        std::span<const Eigen::Vector3d> scan, std::span<const Eigen::Vector3f> no_return, std::span<const float> intensity,
                        const RangeImage* image) {
    if (!intensity.empty() && intensity.size() != points.size())
        throw InvalidArgument("intensity: " + std::to_string(intensity.size()) + " values for " + std::to_string(points.size()) + " points");
    const auto t0 = std::chrono::steady_clock::now();
    // The budget is checked between chunks; one chunk holds a whole HDL-64 frame (~120k points):
    // a frame cut in two chunks paid two groupings and two parallel updates (0.6-0.8 ms).
    constexpr std::size_t kChunk = 1 << 18;
    const std::size_t before = grid_.memory_bytes();
    tbb::task_arena arena = arena_of(config_);
    // Free-space carving: on scans seen from a known position (sequences), after the scan's points.
    const bool carving = config_.carve && grid_.has_viewpoints() && seen_from;
    if (carving) ensure_carver();
    std::vector<VoxelGrid::Hit> hits, chunk_hits;
    for (std::size_t begin = 0; begin < points.size(); begin += kChunk) {
        const std::size_t end = std::min(points.size(), begin + kChunk);
        const std::span<const Eigen::Vector3d> chunk = points.subspan(begin, end - begin);
        // Near the budget, the chunk's growth is counted first: a chunk that would not fit is
        // refused before the grid changes, so later batches that fit are still taken.
        if (static_cast<double>(grid_.memory_bytes_after(chunk.size(), chunk.size(), chunk.size())) > budget_bytes()) {
            const auto [new_voxels, new_blocks] = grid_.count_new(chunk);
            const double after = static_cast<double>(grid_.memory_bytes_after(new_voxels, new_blocks, chunk.size()));
            if (after > budget_bytes()) {
                const double growth = (after - static_cast<double>(before)) * static_cast<double>(points.size()) / static_cast<double>(end);
                throw ResourceLimit(over_budget("the voxel grid", static_cast<double>(before) + growth,
                                                format_value(points.size()) + " points at voxel size " + format_value(config_.voxel_size) +
                                                    " m; nothing of this chunk was integrated"));
            }
        }
        summary_.points_dropped += arena.execute([&] { return grid_.insert(chunk, seen_from, carving ? &chunk_hits : nullptr,
                                                                                intensity.empty() ? intensity : intensity.subspan(begin, end - begin)); });
        summary_.points_read += chunk.size();  // a refused chunk leaves no trace, in the counts either
        for (VoxelGrid::Hit h : chunk_hits) {
            h.point += static_cast<std::uint32_t>(begin);
            hits.push_back(h);
        }
        const double used = static_cast<double>(grid_.memory_bytes());
        if (used > budget_bytes()) {
            // Extrapolate this call's growth to all of its points for the message.
            const double growth = (used - static_cast<double>(before)) * static_cast<double>(points.size()) / static_cast<double>(end);
            throw ResourceLimit(over_budget("the voxel grid", static_cast<double>(before) + growth,
                                            format_value(points.size()) + " points at voxel size " + format_value(config_.voxel_size) + " m"));
        }
    }
    summary_.seconds_insert += seconds_since(t0);
    if (carving) {
        const auto t1 = std::chrono::steady_clock::now();
        const CarvingStats carved = arena.execute(
            [&] { return image ? carver_->carve(grid_, *image, hits) : carver_->carve(grid_, scan, hits, *seen_from, no_return); });
        summary_.carved_voxels += carved.removed;
        summary_.seconds_carve += seconds_since(t1);
    }
    summary_.voxels = grid_.size();
}

Mesh Reconstructor::extract_mesh(Evaluation evaluation) {
    if (grid_.point_count() == 0)
        throw InvalidInput(summary_.points_read == 0 ? "the input has no points"
                                                     : "the input has no finite point (all " + format_value(summary_.points_read) + " dropped)");
    const SurfaceConfig config = surface_config(grid_.has_viewpoints());
    check_extraction_budget(config, evaluation);
    tbb::task_arena arena = arena_of(config_);
    Mesh mesh;
    const VertexPlacement placement = vertex_placement();
    arena.execute([&] {
        auto t0 = std::chrono::steady_clock::now();
        if (config.seeded_surface && evaluation == Evaluation::Fast) {
            SeededTsdf seeded = seeded_field(config, nullptr);
            t0 = std::chrono::steady_clock::now();
            mesh = lidarsurf::extract_mesh(seeded.field, seeded.cubes, placement);
            // The next extraction redoes only what the points integrated from now on can reach.
            previous_ = std::move(seeded.field);
            grid_.clear_touched();
        } else if (config.seeded_surface && config.bridges()) {
            // Bridged vertices may lie beyond H^{k_max} of the data, outside compute_tsdf's candidates.
            summary_.tsdf_phases = {};
            const SeededTsdf seeded = reference_seeded_tsdf(grid_, config, sensor_);
            summary_.candidate_vertices = seeded.evaluated;
            summary_.reused_vertices = 0;
            summary_.defined_vertices = seeded.field.size();
            summary_.seconds_tsdf = seconds_since(t0);
            t0 = std::chrono::steady_clock::now();
            mesh = lidarsurf::extract_mesh(seeded.field, seeded.cubes, placement);
        } else {
            summary_.tsdf_phases = {};
            TsdfStats stats;
            const TsdfField field = compute_tsdf(grid_, config, sensor_, &stats);
            summary_.candidate_vertices = stats.candidates;
            summary_.reused_vertices = 0;
            summary_.defined_vertices = stats.defined;
            if (config_.seeded_surface) {
                const std::vector<VoxelKey> cubes = seeded_cubes(field, grid_, config_.seed_dilation);
                summary_.seconds_tsdf = seconds_since(t0);
                t0 = std::chrono::steady_clock::now();
                mesh = lidarsurf::extract_mesh(field, cubes, placement);
            } else {
                summary_.seconds_tsdf = seconds_since(t0);
                t0 = std::chrono::steady_clock::now();
                mesh = lidarsurf::extract_mesh(field, placement);
            }
        }
        attach_intensity(mesh, grid_, config.max_reach());
        remove_small_components(mesh, static_cast<std::size_t>(config_.min_component_triangles));
        simplify_mesh(mesh, config_.simplify);
        summary_.seconds_mesh = seconds_since(t0);
    });
    summary_.mesh_vertices = mesh.vertices.size();
    summary_.mesh_triangles = mesh.triangles.size();
    return mesh;
}

Mesh Reconstructor::extract_mesh(const SearchRegion& region, const std::function<bool(const VoxelKey&)>& owns) {
    if (!config_.seeded_surface) throw InvalidArgument("a part of a map is meshed with the seeded surface (not the paper as written)");
    if (config_.min_component_triangles > 0)
        throw InvalidArgument("min_component_triangles filters the whole map's components: not for a part of it");
    if (grid_.point_count() == 0) throw InvalidInput("the input has no points");
    const SurfaceConfig config = surface_config(grid_.has_viewpoints());
    check_extraction_budget(config, Evaluation::Fast, &region);
    tbb::task_arena arena = arena_of(config_);
    Mesh mesh;
    arena.execute([&] {
        SeededTsdf seeded = seeded_field(config, &region);
        const auto t0 = std::chrono::steady_clock::now();
        std::erase_if(seeded.cubes, [&](const VoxelKey& cube) { return !owns(cube); });
        mesh = lidarsurf::extract_mesh(seeded.field, seeded.cubes, vertex_placement());
        attach_intensity(mesh, grid_, config.max_reach());
        simplify_mesh(mesh, config_.simplify);  // the seams are the part's borders: kept
        summary_.seconds_mesh = seconds_since(t0);
    });
    summary_.mesh_vertices = mesh.vertices.size();
    summary_.mesh_triangles = mesh.triangles.size();
    return mesh;
}

void Reconstructor::check_extraction_budget(const SurfaceConfig& config, Evaluation evaluation, const SearchRegion* region) {
    const auto budget = static_cast<std::size_t>(budget_bytes());
    summary_.memory_estimate = kProcessBaselineBytes + map_bytes() + estimate_extraction_bytes(grid_, config, evaluation, budget, region);
    if (summary_.memory_estimate > budget)
        throw ResourceLimit(over_budget("the surface extraction", static_cast<double>(summary_.memory_estimate),
                                        format_value(grid_.size()) + " voxels in " + format_value(grid_.index().block_count()) +
                                            " blocks, max level " + format_value(config_.max_level())));
}

SeededTsdf Reconstructor::seeded_field(const SurfaceConfig& config, const SearchRegion* region) {
    const auto t0 = std::chrono::steady_clock::now();
    // A region search does not reuse the previous field (compute_seeded_tsdf).
    const TsdfField* previous = region || !previous_ ? nullptr : &*previous_;
    SeededTsdf seeded = compute_seeded_tsdf(grid_, config, sensor_, EigenSolver::ClosedForm, previous, region);
    summary_.seconds_tsdf = seconds_since(t0);
    summary_.tsdf_phases = seeded.timing;
    summary_.candidate_vertices = seeded.evaluated;
    summary_.reused_vertices = seeded.reused;
    summary_.defined_vertices = seeded.field.size();
    return seeded;
}

VertexPlacement Reconstructor::vertex_placement() const {
    return config_.snap_to_plane ? VertexPlacement::SnappedToPlane : VertexPlacement::Interpolated;
}

SurfaceConfig Reconstructor::surface_config(bool from_viewpoints) const {
    SurfaceConfig c = config_;
    if (from_viewpoints) c.bridge_reach = 0;  // bridges are for the rings of one scan
    return c;
}

std::size_t Reconstructor::map_bytes() const {
    return grid_.memory_bytes() + (previous_ ? previous_->memory_bytes() : 0) + (carver_ ? carver_->memory_bytes() : 0) +
           (live_ ? live_->memory_bytes() : 0);
}

double Reconstructor::budget_bytes() const { return config_.max_memory_mb * 1048576.0; }

std::string Reconstructor::over_budget(const std::string& what, double bytes, const std::string& detail) const {
    char buf[160];
    std::snprintf(buf, sizeof buf, " would need about %.0f MiB, above the memory budget of %.0f MiB (", bytes / 1048576.0,
                  config_.max_memory_mb);
    return what + buf + detail + "); use a larger voxel size, split the cloud, or raise the budget (max_memory_mb, CLI --max-memory-mb)";
}

Mesh reconstruct(const PointCloud& cloud, const Eigen::Vector3d& sensor, const ReconstructionConfig& config,
                 ReconstructionSummary* summary) {
    Reconstructor r(config, sensor);
    r.integrate(cloud);
    Mesh mesh = r.extract_mesh();
    if (summary) *summary = r.summary();
    return mesh;
}

void MethodConfig::validate() const {
    if (imls) imls_config.validate();
    else config.validate();
}

namespace {

// IMLS or the TSDF on the points `integrate` gives a Reconstructor; `release`, called once they
// are integrated, may free them before the extraction.
template <class Integrate>
Mesh run_method(const MethodConfig& method, const Eigen::Vector3d& sensor, std::string* summary, std::span<const Eigen::Vector3d> points,
                Integrate integrate) {
    method.validate();
    if (method.imls) {
        PointCloud cloud;  // IMLS keeps its own copy for its kd-tree
        cloud.points.assign(points.begin(), points.end());
        ImlsSummary s;
        Mesh mesh = reconstruct_imls(cloud, sensor, method.imls_config, &s);
        if (summary) *summary = s.to_string();
        return mesh;
    }
    Reconstructor rec(method.config, sensor);
    integrate(rec);
    Mesh mesh = rec.extract_mesh();
    if (summary) *summary = rec.summary().to_string();
    return mesh;
}

}  // namespace

Mesh reconstruct_with(const MethodConfig& method, std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& sensor,
                      std::string* summary, std::span<const float> intensity) {
    return run_method(method, sensor, summary, points, [&](Reconstructor& rec) { rec.integrate(points, intensity); });
}

Mesh reconstruct_with(const MethodConfig& method, PointCloud&& cloud, const Eigen::Vector3d& sensor, std::string* summary) {
    return run_method(method, sensor, summary, cloud.points, [&](Reconstructor& rec) {
        rec.integrate(cloud.points, cloud.intensities);
        cloud = PointCloud{};  // the extraction's memory comes in place of the points', not on top of it
    });
}

}  // namespace lidarsurf
