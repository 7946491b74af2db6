#include "lidarsurf/surface/local_plane.hpp"

#include <Eigen/Eigenvalues>

#include "lidarsurf/surface/plane_eigen.hpp"

namespace lidarsurf {

namespace {

// The plane of `stats` (covariance c) from its eigenvalues (l1 >= l2 >= l3) and the normal's
// eigenvector e3, or nullopt for a degenerate covariance (fit_plane).
std::optional<LocalPlane> make_plane(const VoxelStats& stats, const Eigen::Matrix3d& c, double l1, double l2, double l3,
                                     const Eigen::Vector3d& e3, const Eigen::Vector3d& sensor, double min_lambda2,
                                     double min_planarity) {
    if (!(l2 > min_lambda2)) return std::nullopt;       // points identical or collinear
    if (l2 < min_planarity * l1) return std::nullopt;   // a line (one scan ring), not a plane
    LocalPlane plane;
    plane.mean = stats.mean;
    plane.lambda1 = l1;
    plane.lambda2 = l2;
    plane.lambda3 = std::max(l3, 0.0);
    plane.covariance = c;
    plane.normal = e3.dot(sensor - stats.mean) > 0 ? e3 : Eigen::Vector3d(-e3);  // Eq. (2)
    return plane;
}

}  // namespace

std::optional<LocalPlane> fit_plane(const VoxelStats& stats, int n_min, const Eigen::Vector3d& sensor,
                                    double min_lambda2, double min_planarity, EigenSolver method) {
    if (stats.count < static_cast<std::uint64_t>(n_min)) return std::nullopt;  // Eq. (1)
    const Eigen::Matrix3d covariance = stats.covariance();
    if (method == EigenSolver::ClosedForm) {
        if (const auto eig = plane_eigen(covariance))  // nullopt: lambda2 ~ lambda3, Eigen's below
            return make_plane(stats, covariance, eig->lambda1, eig->lambda2, eig->lambda3, eig->e3, sensor, min_lambda2, min_planarity);
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    if (method == EigenSolver::ClosedForm)
        solver.computeDirect(covariance);
    else
        solver.compute(covariance);
    if (solver.info() != Eigen::Success) return std::nullopt;
    // Eigen sorts eigenvalues ascending: lambda3 <= lambda2 <= lambda1.
    const Eigen::Vector3d ev = solver.eigenvalues();
    return make_plane(stats, covariance, ev[2], ev[1], ev[0], solver.eigenvectors().col(0), sensor, min_lambda2, min_planarity);
}

}  // namespace lidarsurf
