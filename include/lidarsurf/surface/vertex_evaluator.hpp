#pragma once
// Per-vertex choice of the neighbourhood level k' (Sec. III-C1 and the modes of Sec. IV-B) and
// the TSDF value of Eq. (4). This is the straightforward reference evaluation of one vertex.
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Core>

#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/local_plane.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"

namespace lidarsurf {

struct VertexSample {
    bool defined = false;    ///< false: no level satisfied the mode's conditions.
    float tsdf = 0;          ///< n^{k'} . (v - H^{k'}_mu), Eq. (4), metres.
    std::uint8_t level = 0;  ///< k'.
    float confidence = 0;    ///< N_PDF at w^{k'} (Eq. 3), also computed for the non-GC modes.
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< n^{k'}.
};

/// Truncation (docs/method.md, "Truncation"): which evaluated samples define the field.
struct Truncation {
    double distance = std::numeric_limits<double>::infinity();  ///< metres from the sample's plane
    /// Scale the distance by the L1 norm of the unit normal: a cube's extent along n is
    /// alpha * |n|_1 (1 for a plane along the lattice, up to sqrt(3) across it), so every corner
    /// of a cube the plane crosses is kept whatever the plane's orientation. Used on grids with
    /// viewpoints (fused sequences), where oblique surfaces seen from all sides (crowns, wall
    /// tops) lost those corners; a single scan keeps the lattice distance.
    bool along_normal = false;

    bool keeps(const VertexSample& s) const {
        if (!s.defined) return false;
        const double limit = along_normal ? distance * static_cast<double>(s.normal.cwiseAbs().sum()) : distance;
        return std::fabs(s.tsdf) <= limit;
    }
};
/// The truncation of a reconstruction: `config`'s distance, along the normal on a grid with viewpoints.
inline Truncation truncation_of(const SurfaceConfig& config, const VoxelGrid& grid) {
    return {config.truncation_distance(), grid.has_viewpoints()};
}

/// The position v's normal is oriented toward (Eq. 2) and its radial slabs are measured from:
/// `sensor_local` (the sensor, local frame), or on a grid with viewpoints (several sensor
/// positions) the point-weighted mean viewpoint of H^{max_level}(v), `sensor_local` when that box
/// is empty. Both evaluations below start with it (docs/method.md, "Sequences").
Eigen::Vector3d vertex_viewpoint(const VoxelGrid& grid, const VoxelKey& v, const SurfaceConfig& config,
                                 const Eigen::Vector3d& sensor_local);

/// Evaluates vertex `v` of `grid` with `config` (already validated). `sensor_local` is the sensor
/// position in the grid's local frame. The reference: Chan merges over the grid, iterative eigen
/// solver.
VertexSample evaluate_vertex(const VoxelGrid& grid, const VoxelKey& v, const SurfaceConfig& config,
                             const Eigen::Vector3d& sensor_local);

/// The same through a NeighbourhoodWindow (v in the window's vertex block) with the given eigen
/// solver: the fast path. Equal to the reference up to rounding (tests/surface).
VertexSample evaluate_vertex(const NeighbourhoodWindow& window, const VoxelKey& v, const SurfaceConfig& config,
                             const Eigen::Vector3d& sensor_local, EigenSolver solver);

/// The conditions of one level (Eq. 1-3 per mode) on the merged statistics of H^level(v) at
/// `position` (local frame); a defined sample with the TSDF of Eq. (4) when they hold. Shared by
/// both evaluations above.
VertexSample evaluate_level(const VoxelStats& stats, int level, const Eigen::Vector3d& position,
                            const SurfaceConfig& config, const Eigen::Vector3d& sensor_local, double min_lambda2,
                            EigenSolver solver);

/// A bridge's plane must be within 45 degrees of horizontal: |n_z| >= cos 45 degrees.
inline constexpr double kBridgeMinNormalZ = 0.70710678118654752;

/// The bridge of a vertex no level defines (docs/method.md, "Bridges"; AN+GC on a single scan):
/// `near` and `far` are the merged statistics of its two bridge_boxes (the sensor's side first).
/// Defined, with the TSDF to the plane of both and a confidence below tau, when each holds
/// ceil(N_min / 2) points, their points are not one line, are no thicker than the thickness
/// guard, both means lie on the plane within it, and the plane is within 45 degrees of
/// horizontal. Shared by both evaluations above.
VertexSample evaluate_bridge(const VoxelStats& near, const VoxelStats& far, const Eigen::Vector3d& position, const SurfaceConfig& config,
                             const Eigen::Vector3d& sensor_local, double min_lambda2, EigenSolver solver);

/// Whether the invariants of the covariance alone prove that evaluate_level rejects a level, so
/// that the fast path can skip the eigen solve (about 28 % of the solves on a lidar frame):
///  - planarity: with T = tr C = l1 + l2 + l3 and M = l1 l2 + l1 l3 + l2 l3 (the sum of C's
///    principal 2x2 minors), M >= l1 l2 and l1 >= T / 3, so l2 / l1 <= 9 M / T^2;
///  - thickness: l3 > t^2 iff C - t^2 I is positive definite (Sylvester: leading minors > 0).
/// Both keep a relative margin of 1e-6, so rounding cannot reject a level the eigenvalues keep.
bool rejected_by_invariants(const VoxelStats& stats, const SurfaceConfig& config);

/// Covariances with lambda2 below this (relative to alpha^2) are treated as degenerate.
double degenerate_lambda2(double voxel_size);

}  // namespace lidarsurf
