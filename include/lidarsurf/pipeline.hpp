#pragma once
// The reconstruction pipeline (Sec. III): points -> voxel statistics -> adaptive TSDF ->
// marching cubes. Composes the modules; holds the voxel grid so more scans can be integrated.
#include <span>
#include <string>

#include <Eigen/Core>

#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/surface/config.hpp"

namespace lidarsurf {

struct ReconstructionSummary {
    std::size_t points_read = 0;
    std::size_t points_dropped = 0;  ///< non-finite coordinates
    std::size_t voxels = 0;
    std::size_t candidate_vertices = 0;
    std::size_t defined_vertices = 0;
    std::size_t mesh_vertices = 0;
    std::size_t mesh_triangles = 0;
    double seconds_insert = 0, seconds_tsdf = 0, seconds_mesh = 0;

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
    Reconstructor(const ReconstructionConfig& config, const Eigen::Vector3d& sensor);

    /// Adds the finite points of `cloud` to the voxel statistics; counts the others as dropped.
    void integrate(const PointCloud& cloud);
    /// The same on a view (no copy): used by the Python bindings on numpy arrays.
    void integrate(std::span<const Eigen::Vector3d> points);

    /// Computes the TSDF and extracts the mesh. Throws InvalidInput if no point was integrated.
    Mesh extract_mesh(Evaluation evaluation = Evaluation::Fast);

    const ReconstructionSummary& summary() const { return summary_; }
    const VoxelGrid& grid() const { return grid_; }
    const ReconstructionConfig& config() const { return config_; }

private:
    ReconstructionConfig config_;
    Eigen::Vector3d sensor_;
    VoxelGrid grid_;
    ReconstructionSummary summary_;
};

/// One-shot helper: integrate `cloud` and extract the mesh.
Mesh reconstruct(const PointCloud& cloud, const Eigen::Vector3d& sensor, const ReconstructionConfig& config,
                 ReconstructionSummary* summary = nullptr);

}  // namespace lidarsurf
