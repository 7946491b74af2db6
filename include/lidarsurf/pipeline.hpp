#pragma once
// The reconstruction pipeline (Sec. III): points -> voxel statistics -> adaptive TSDF ->
// marching cubes. Composes the modules; holds the voxel grid so more scans can be integrated.
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "lidarsurf/baselines/imls.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/map/free_space.hpp"
#include "lidarsurf/map/live_mesh.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/reconstruction_config.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"

namespace lidarsurf {

/// What a process running the library holds besides its maps: code, libraries, thread stacks
/// (measured: the CLI on a 1,600-point scan peaks at 15 MiB). Part of every memory estimate.
inline constexpr std::size_t kProcessBaselineBytes = std::size_t{16} << 20;

struct ReconstructionSummary {
    std::size_t points_read = 0;
    std::size_t points_dropped = 0;  ///< non-finite coordinates
    std::size_t voxels = 0;
    std::size_t candidate_vertices = 0;  ///< vertices evaluated by the last extraction
    std::size_t reused_vertices = 0;     ///< vertices the last extraction took from the one before
    std::size_t defined_vertices = 0;
    std::size_t mesh_vertices = 0;
    std::size_t mesh_triangles = 0;
    std::size_t memory_estimate = 0;  ///< bytes: kProcessBaselineBytes, the map and estimate_extraction_bytes (the budget check)
    std::size_t carved_voxels = 0;  ///< voxels removed by free-space carving, over all scans
    double seconds_insert = 0, seconds_carve = 0, seconds_tsdf = 0, seconds_mesh = 0;
    /// The fusion and extraction stages together: insert, carving, TSDF and mesh (seconds).
    double seconds_total() const { return seconds_insert + seconds_carve + seconds_tsdf + seconds_mesh; }
    /// The TSDF stage by phase, for the fast path with seeded_surface (zero otherwise).
    SeededTiming tsdf_phases;

    /// One line: counts and per-stage times.
    std::string to_string() const;
};

/// How the TSDF is computed: both give the same mesh (tests/test_pipeline.cpp checks it).
enum class Evaluation {
    Fast,       ///< with seeded_surface: only the vertices the surface search touches
    Reference,  ///< every candidate vertex, the straightforward per-vertex evaluation
};

class Reconstructor {
public:
    /// Validates `config` (throws InvalidArgument). `sensor` orients the normals (Eq. 2).
    /// `grid_origin` (world) fixes the voxel lattice's local origin (VoxelGrid): by default the
    /// first point integrated sets it; the parts of one map fused apart (tiles/tiles.hpp) all take
    /// the one the whole map would have, so that their statistics agree to the last bit.
    Reconstructor(const ReconstructionConfig& config, const Eigen::Vector3d& sensor,
                  const std::optional<Eigen::Vector3d>& grid_origin = std::nullopt);

    /// Adds the finite points of `cloud` to the voxel statistics; counts the others as dropped.
    /// With the cloud's intensities, the voxels keep their mean and the mesh's vertices get one
    /// (Mesh::intensity; every overload below takes them as `intensity`, one per point or none).
    /// Throws ResourceLimit (with an estimate) when the grid would outgrow config.max_memory_mb.
    /// Points are taken in chunks of 262,144: a chunk that would not fit is refused before it
    /// changes the grid (the chunks of the same call before it stay), so the Reconstructor keeps
    /// taking later batches that fit.
    void integrate(const PointCloud& cloud);
    /// The same on a view (no copy): used by the Python bindings on numpy arrays.
    void integrate(std::span<const Eigen::Vector3d> points, std::span<const float> intensity = {});
    /// Points seen from `viewpoint` (same frame as the points, e.g. a sequence's world frame with
    /// the pose's translation). The first call turns on per-voxel viewpoints for good: each
    /// vertex's normal is then oriented toward the mean viewpoint of the points near it
    /// (vertex_viewpoint, docs/method.md "Sequences"); points integrated without a viewpoint count
    /// as seen from the constructor's sensor. Turning them on after points were integrated makes
    /// the next extraction evaluate every vertex again. Throws InvalidArgument if not finite.
    void integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint);
    /// The same, with the unit directions (world frame) of the scan's rays that returned nothing:
    /// free-space carving takes them as free space up to config.carve_empty_range.
    void integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, std::span<const Eigen::Vector3f> no_return,
                   std::span<const float> intensity = {});
    /// A part of a map (tiles/tiles.hpp): of the scan's points seen from `viewpoint`, only those
    /// inside `keep` (world) are integrated, while free-space carving takes the whole scan (a ray
    /// through the part may return outside it). summary().points_read counts the points kept.
    void integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, const Eigen::AlignedBox3d& keep,
                   std::span<const Eigen::Vector3f> no_return = {}, std::span<const float> intensity = {});
    /// The same with the scan's range image built already: `image` is RangeImage::build of the
    /// whole scan `points` from `viewpoint` in this grid's frame (the origin given to the
    /// constructor) with config.carve_empty_range and the scan's rays that returned nothing. Several
    /// parts of one map fused in one pass over the scans share it (tiles/tiles.hpp, fuse_tiles).
    void integrate(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, const Eigen::AlignedBox3d& keep,
                   const RangeImage& image, std::span<const float> intensity = {});
    /// A scan of a sequence that reaches nothing of this grid (a part of a map, tiles/tiles.hpp):
    /// free-space carving counts it, as it counts every scan of the drive.
    void skip_scan();

    /// Computes the TSDF and extracts the mesh. Throws InvalidInput if no point was integrated and
    /// ResourceLimit if kProcessBaselineBytes, the map and estimate_extraction_bytes exceed config.max_memory_mb.
    ///
    /// Incremental: integrate, extract, integrate more, extract again re-evaluates only the
    /// vertices that the new points can reach (the blocks within max_reach() of a block that
    /// received a point, VoxelGrid::touched_blocks); the fast path keeps the previous field for
    /// that (summary().reused_vertices). The mesh is the one a single extraction after all the
    /// integrations gives. The reference path always evaluates every vertex.
    Mesh extract_mesh(Evaluation evaluation = Evaluation::Fast);

    /// The mesh of the cubes that `owns` accepts (cube = its minimum corner, grid keys), with the
    /// surface search kept to `region` (SearchRegion): a part of a map meshed apart
    /// (tiles/tiles.hpp). The same vertex values and marching cubes as extract_mesh(); the cubes are
    /// those the search reaches without leaving the region. Throws InvalidArgument without the
    /// seeded surface or with min_component_triangles (a filter over the whole map), InvalidInput
    /// if no point was integrated, ResourceLimit as extract_mesh() with the estimate of the region
    /// (estimate_extraction_bytes).
    Mesh extract_mesh(const SearchRegion& region, const std::function<bool(const VoxelKey&)>& owns);

    /// Brings the live mesh up to date with the scans integrated since the last call, nearest the
    /// last viewpoint first, within `budget_ms` milliseconds (<= 0: everything due), and returns
    /// what changed (map/live_mesh.hpp): applying the deltas in order gives live_mesh(). The
    /// first call meshes what the grid holds. The exact mesh stays extract_mesh(), which the live
    /// mesh does not change. Throws InvalidArgument for a configuration without the seeded surface
    /// (the paper as written).
    MeshDelta update_mesh(double budget_ms = 0);
    /// The live mesh as the updates so far made it (empty before the first update_mesh()).
    Mesh live_mesh() const { return live_ ? live_->mesh() : Mesh{}; }
    /// The live mesh's state, or nullptr before the first update_mesh().
    const LiveMesh* live() const { return live_ ? &*live_ : nullptr; }

    const ReconstructionSummary& summary() const { return summary_; }
    const VoxelGrid& grid() const { return grid_; }
    /// Bytes the map holds between scans: the grid, the carving evidence, the last extraction's
    /// field (kept for the next incremental one) and the live mesh (capacities).
    std::size_t map_bytes() const;
    const ReconstructionConfig& config() const { return config_; }

private:
    /// integrate(points, viewpoint) of `points`, taken from the whole scan `scan` (carving sees it).
    void integrate_seen(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, std::span<const Eigen::Vector3d> scan,
                        std::span<const Eigen::Vector3f> no_return, std::span<const float> intensity, const RangeImage* image = nullptr);
    /// integrate(points, viewpoint, keep, ...): the points inside `keep`, their intensities too.
    void integrate_kept(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, const Eigen::AlignedBox3d& keep,
                        std::span<const Eigen::Vector3f> no_return, std::span<const float> intensity, const RangeImage* image);
    /// Inserts `points`; carving (on) sees `scan`, the whole scan they are taken from, and its rays
    /// that returned nothing, or its range image `image` when given.
    void add(std::span<const Eigen::Vector3d> points, const std::optional<Eigen::Vector3d>& seen_from,
             std::span<const Eigen::Vector3d> scan, std::span<const Eigen::Vector3f> no_return = {}, std::span<const float> intensity = {},
             const RangeImage* image = nullptr);
    void ensure_carver();
    double budget_bytes() const;
    std::string over_budget(const std::string& what, double bytes, const std::string& detail) const;

    /// The configuration the surface is extracted with: config_, without bridges on a grid
    /// fused from viewpoints (a map's scans fill in each other's rings).
    SurfaceConfig surface_config(bool from_viewpoints) const;
    /// Sets summary().memory_estimate (the grid, the previous field, the carver and what the
    /// extraction will allocate) and throws ResourceLimit when it passes the budget.
    void check_extraction_budget(const SurfaceConfig& config, Evaluation evaluation, const SearchRegion* region = nullptr);
    /// The fast path's field over the grid (reusing the previous one) or over `region`; its
    /// counts and time in the summary.
    SeededTsdf seeded_field(const SurfaceConfig& config, const SearchRegion* region);
    VertexPlacement vertex_placement() const;
    ReconstructionConfig config_;
    Eigen::Vector3d sensor_;
    VoxelGrid grid_;
    std::optional<TsdfField> previous_;  // the last fast extraction's field, for the next one
    std::optional<FreeSpaceCarver> carver_;  // with config.carve, from the first scan with a viewpoint
    std::uint32_t skipped_scans_ = 0;        // skip_scan() calls before the carver was made
    std::optional<LiveMesh> live_;           // from the first update_mesh()
    Eigen::Vector3d last_viewpoint_;         // where the last scan was seen from: the live mesh's nearest blocks go first
    ReconstructionSummary summary_;
};

/// Estimated peak bytes extract_mesh allocates on top of `grid` (the search's voxel lists and
/// slots, the evaluated vertices, the TSDF field, welding tables, the mesh), from the grid's
/// blocks: their voxels and their voxels' cube corners (src/extraction_memory.cpp). Calibrated
/// against peak RSS in docs/reliability.md (0.9-1.45x on the fast path). The reference path's
/// count stops once the estimate passes `limit`.
/// With `region` (the fast path's search kept to a part of the map, extract_mesh(region, owns)),
/// only the grid's blocks within the region's bounding box, grown by the configuration's reach,
/// are counted: what that search can pack and visit.
std::size_t estimate_extraction_bytes(const VoxelGrid& grid, const SurfaceConfig& config, Evaluation evaluation,
                                      std::size_t limit = SIZE_MAX, const SearchRegion* region = nullptr);

/// One-shot helper: integrate `cloud` and extract the mesh.
Mesh reconstruct(const PointCloud& cloud, const Eigen::Vector3d& sensor, const ReconstructionConfig& config,
                 ReconstructionSummary* summary = nullptr);

/// The methods a scan can be meshed with: the adaptive TSDF, as lidarsurf's default or as the
/// paper wrote it (which of the two is `config`'s business: ReconstructionConfig::paper), or the
/// paper's IMLS baseline.
struct MethodConfig {
    bool imls = false;            ///< the IMLS baseline instead of the TSDF
    ReconstructionConfig config;  ///< the TSDF's parameters
    ImlsConfig imls_config;       ///< IMLS's; ImlsConfig::matching(config) makes it comparable

    /// Throws InvalidArgument naming the first bad field of the method that runs (a TSDF run does
    /// not fail on IMLS's limits).
    void validate() const;
};

/// The one entry point that the CLI, the Python module and the benchmark call: the points, seen from
/// `sensor`, meshed by `method`. `summary`, when given, gets one line of counts and times. The mesh
/// may be empty (too sparse a cloud); the caller decides whether that is an error. `intensity`
/// (one per point, or none) reaches the mesh's vertices (IMLS ignores it).
Mesh reconstruct_with(const MethodConfig& method, std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& sensor,
                      std::string* summary = nullptr, std::span<const float> intensity = {});
inline Mesh reconstruct_with(const MethodConfig& method, const PointCloud& cloud, const Eigen::Vector3d& sensor,
                             std::string* summary = nullptr) {
    return reconstruct_with(method, std::span<const Eigen::Vector3d>(cloud.points), sensor, summary, cloud.intensities);
}
/// The same, freeing the cloud once it is integrated: the extraction's memory then comes in place
/// of the input's (the CLI's reconstruct).
Mesh reconstruct_with(const MethodConfig& method, PointCloud&& cloud, const Eigen::Vector3d& sensor, std::string* summary = nullptr);

}  // namespace lidarsurf
