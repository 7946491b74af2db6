#pragma once
// What a plane fit needs of a 3x3 covariance, without trigonometry: its eigenvalues
// and the eigenvector of the smallest, the normal. Shifted by the mean eigenvalue T/3 (as Eigen's
// computeDirect), lambda3 - T/3 is the smallest root of the trace-free matrix's characteristic
// polynomial, found by Newton's method from left of it, where the polynomial is increasing and
// concave, so the iterates rise monotonically to it: from det(C) / M(C) - T/3 (M: the sum of C's
// principal 2x2 minors), within about lambda3^2 / lambda2 of it, else from -T/3, within lambda3
// (3.4 steps per fit on a KITTI frame). lambda1 and lambda2 are the roots of the remaining
// quadratic, e3 the kernel of C - lambda3 I (the cross product of its two most independent rows).
// Eigen's computeDirect spends most of its time in atan2 and sincos for the same values, and on
// two more eigenvectors a plane does not need.
#include <array>
#include <optional>

#include <Eigen/Core>

namespace lidarsurf {

struct PlaneEigen {
    double lambda1 = 0, lambda2 = 0, lambda3 = 0;  ///< lambda1 >= lambda2 >= lambda3
    Eigen::Vector3d e3 = Eigen::Vector3d::Zero();  ///< unit eigenvector of lambda3 (sign arbitrary)
};

/// The eigenvalues of the symmetric covariance `c` and the eigenvector of the smallest, or nullopt
/// when this method cannot give them accurately: lambda2 - lambda3 < 1e-3 (lambda1 - lambda3)
/// (e3 ill-conditioned; Newton slow near the double root), c not positive semi-definite beyond
/// rounding, c zero or not finite. Callers then use a general solver.
std::optional<PlaneEigen> plane_eigen(const Eigen::Matrix3d& c);

/// plane_eigen of four covariances at once: at the Avx2 level (core/simd.hpp) in the four lanes of
/// 256-bit registers, each lane's Newton steps running until the last lane converges (the others
/// keep their values), else as four calls. Lane i is plane_eigen(c[i]) bit for bit: the same
/// operations in the same order, no fused multiply-add. A fit costs about a third of the scalar
/// one this way in a loop of fits alone (bench/surface/bench_surface.cpp, BM_PlaneEigen). The
/// vertex evaluation does not use it: fitting four vertices' planes together made a frame slower
/// (a KITTI frame's time), as the one-by-one fits' latency is already overlapped there.
std::array<std::optional<PlaneEigen>, 4> plane_eigen4(const std::array<Eigen::Matrix3d, 4>& c);

}  // namespace lidarsurf
