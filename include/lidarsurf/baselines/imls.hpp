#pragma once
// The paper's baseline (Sec. IV-A): Implicit Moving Least Squares (Shen et al. 2004) in Kolluri's
// form (2008). Per-point normals n_i by PCA of the k nearest neighbours, oriented toward the sensor;
//   f(x) = sum_i theta_i (x - p_i) . n_i / sum_i theta_i,  theta_i = exp(-||x - p_i||^2 / h^2),
// over the points within radius r of x. Evaluated on the same vertex lattice (alpha) as the
// paper's method and meshed by the same marching cubes.
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/kd_tree.hpp"
#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"

namespace lidarsurf {

/// IMLS settings. The defaults are the paper's comparable choice: r = alpha * k_max, k = N_min,
/// h = r / 3, derived from the SurfaceConfig defaults (see matching()).
struct ImlsConfig {
    double voxel_size = SurfaceConfig{}.voxel_size;  ///< lattice step alpha, metres
    double radius = SurfaceConfig{}.voxel_size * SurfaceConfig{}.k_max;  ///< r, metres
    int normal_k = SurfaceConfig{}.n_min;  ///< k nearest neighbours for the normals
    double bandwidth = radius / 3.0;             ///< h, metres
    /// |f| beyond this many voxels leaves the vertex undefined; 0 (the paper) keeps every vertex.
    double truncation_voxels = 0.0;
    int threads = 0;  ///< 0 = all cores

    /// The settings that make IMLS comparable to `config`: same alpha, r = alpha * k_max
    /// (max_level for the constant modes), k = N_min, h = r / 3; `threads` workers.
    static ImlsConfig matching(const SurfaceConfig& config, int threads);

    /// Throws InvalidArgument naming the first bad field.
    void validate() const;
};

/// Unit normals of `points` by PCA of their k nearest neighbours (including the point itself),
/// oriented toward `sensor` (the same rule as Eq. 2). A point whose neighbourhood is degenerate
/// (fewer than 3 distinct points, or collinear) gets a zero normal and is ignored by f.
std::vector<Eigen::Vector3d> estimate_normals(const KdTree& tree, int k, const Eigen::Vector3d& sensor);

/// The implicit function on a point set with normals.
class ImlsFunction {
public:
    /// `normals` must have one entry per tree point (zero = unusable point).
    ImlsFunction(const KdTree& tree, std::vector<Eigen::Vector3d> normals, double radius, double bandwidth);

    /// f(x); `defined` is false when no usable point lies within r. Reuses `scratch`.
    VertexSample evaluate(const Eigen::Vector3d& x, std::vector<Neighbour>& scratch) const;

private:
    const KdTree& tree_;
    std::vector<Eigen::Vector3d> normals_;
    double radius_, inv_h2_;
};

struct ImlsSummary {
    std::size_t points = 0, dropped = 0, candidates = 0, defined = 0;
    std::size_t mesh_vertices = 0, mesh_triangles = 0;
    double seconds_normals = 0, seconds_field = 0, seconds_mesh = 0;
    double radius = 0, bandwidth = 0;
    int normal_k = 0;

    /// One line: counts, per-stage times and the settings used (like ReconstructionSummary).
    std::string to_string() const;
};

/// IMLS surface of one scan taken from `sensor`: normals, f on the lattice vertices within r of a
/// point (the vertices whose H^{ceil(r/alpha)} holds a point), marching cubes. Non-finite points
/// are dropped (counted in the summary). Throws InvalidInput if no finite point remains.
Mesh reconstruct_imls(const PointCloud& cloud, const Eigen::Vector3d& sensor, const ImlsConfig& config,
                      ImlsSummary* summary = nullptr);

}  // namespace lidarsurf
