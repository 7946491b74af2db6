#include "lidarsurf/surface/local_plane.hpp"

#include <Eigen/Eigenvalues>

namespace lidarsurf {

std::optional<LocalPlane> fit_plane(const VoxelStats& stats, int n_min, const Eigen::Vector3d& sensor,
                                    double min_lambda2, double min_planarity, EigenSolver method) {
    if (stats.count < static_cast<std::uint64_t>(n_min)) return std::nullopt;  // Eq. (1)
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    if (method == EigenSolver::ClosedForm)
        solver.computeDirect(stats.covariance());
    else
        solver.compute(stats.covariance());
    if (solver.info() != Eigen::Success) return std::nullopt;
    // Eigen sorts eigenvalues ascending: lambda3 <= lambda2 <= lambda1.
    const Eigen::Vector3d ev = solver.eigenvalues();
    if (!(ev[1] > min_lambda2)) return std::nullopt;             // points identical or collinear
    if (ev[1] < min_planarity * ev[2]) return std::nullopt;        // a line (one scan ring), not a plane
    LocalPlane plane;
    plane.mean = stats.mean;
    plane.lambda1 = ev[2];
    plane.lambda2 = ev[1];
    plane.lambda3 = std::max(ev[0], 0.0);
    plane.e1 = solver.eigenvectors().col(2);
    plane.e2 = solver.eigenvectors().col(1);
    const Eigen::Vector3d e3 = solver.eigenvectors().col(0);
    plane.normal = e3.dot(sensor - stats.mean) > 0 ? e3 : Eigen::Vector3d(-e3);  // Eq. (2)
    return plane;
}

}  // namespace lidarsurf
