#pragma once
// Local planar surface of a neighbourhood (Sec. III-B2): PCA of H_sigma, normal oriented toward
// the sensor (Eq. 2).
#include <optional>

#include <Eigen/Core>

#include "lidarsurf/core/voxel_stats.hpp"

namespace lidarsurf {

struct LocalPlane {
    Eigen::Vector3d mean;     ///< H_mu, a point of the plane Pi.
    Eigen::Vector3d normal;   ///< n, unit, oriented toward the sensor (Eq. 2).
    double lambda1 = 0, lambda2 = 0, lambda3 = 0;  ///< eigenvalues, lambda1 >= lambda2 >= lambda3.
    /// H_sigma, whose in-plane principal axes e1, e2 (eigenvectors of lambda1, lambda2) Eq. (3)
    /// uses through the quadratic form (gaussian_confidence.hpp), so they are not stored.
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

/// How the 3x3 covariance is diagonalised: Eigen's iterative QL (the reference), or the fast path's
/// closed form: plane_eigen (plane_eigen.hpp: Newton for lambda3, the normal as a kernel), and
/// Eigen's trigonometric computeDirect where that refuses (lambda2 ~ lambda3). Normals accurate to
/// ~1e-10 rad unless two eigenvalues nearly coincide.
enum class EigenSolver { Iterative, ClosedForm };

/// Fits the plane of `stats` if |H| >= n_min (Eq. 1). Returns nullopt when Eq. (1) fails or the
/// covariance is degenerate: lambda2 <= min_lambda2 (all points identical or exactly collinear: no
/// plane and no 2-D Gaussian exist) or lambda2 < min_planarity * lambda1 (points along a line, such
/// as one scan ring, whose PCA "plane" is not a surface). `sensor` is in stats.mean's frame.
std::optional<LocalPlane> fit_plane(const VoxelStats& stats, int n_min, const Eigen::Vector3d& sensor,
                                    double min_lambda2, double min_planarity = 0.0,
                                    EigenSolver solver = EigenSolver::Iterative);

/// Signed distance of x to the plane: n . (x - H_mu), Eq. (4).
inline double signed_distance(const LocalPlane& plane, const Eigen::Vector3d& x) {
    return plane.normal.dot(x - plane.mean);
}

}  // namespace lidarsurf
