#include "lidarsurf/surface/plane_eigen.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace lidarsurf {

std::optional<PlaneEigen> plane_eigen(const Eigen::Matrix3d& c) {
    // Shifted by the mean eigenvalue, as Eigen's computeDirect: the trace-free b = c - (T/3) I has
    // the eigenvalues lambda - T/3, and its polynomial p(l) = l^3 + m l - d (m = sum of b's principal
    // 2x2 minors, d = det b) rounds relative to b's spread rather than to T: without the shift a
    // nearly isotropic covariance would lose lambda3 to rounding.
    const double t = c(0, 0) + c(1, 1) + c(2, 2);
    if (!(t > 0) || !std::isfinite(t)) return std::nullopt;
    const double shift = t / 3.0;
    const double xx = c(0, 0) - shift, xy = c(0, 1), xz = c(0, 2), yy = c(1, 1) - shift, yz = c(1, 2), zz = c(2, 2) - shift;
    const double m = xx * yy - xy * xy + xx * zz - xz * xz + yy * zz - yz * yz;
    const double d = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    if (!std::isfinite(m + d)) return std::nullopt;

    // b's smallest eigenvalue lambda3 - T/3 is in [-T/3, 0] for a PSD c. Newton on p from just
    // left of -T/3: there p is increasing and concave (p'' = 6 l < 0), so the iterates rise
    // monotonically to the root; for a planar neighbourhood (lambda3 << lambda2) the start is
    // already within lambda3 of it (4-5 steps to rounding). In exact arithmetic the steps shrink
    // strictly, quadratically near a simple root, by about half far from a double one; so the
    // first step that does not shrink is rounding, and the iterate is the root to rounding.
    // After 50 steps (a near-double root) the caller's solver takes over.
    double l = -shift - 1e-12 * t;
    double p = (l * l + m) * l - d;
    if (p > 0) return std::nullopt;  // a root below l: c is not PSD
    // A closer start, still left of the root: for a PSD c, det(c) / M(c) (M: the sum of c's
    // principal 2x2 minors) = l1 l2 l3 / (l1 l2 + l1 l3 + l2 l3) <= lambda3, short of it by about
    // lambda3^2 (l1 + l2) / (l1 l2): one Newton step fewer on lidar neighbourhoods (5.35 -> 4.35
    // steps per fit on KITTI 000000; the early stop below saves another, docs/benchmarks.md,
    // session 16). Rounding may put it right of the root (p > 0 there): then the start stays -T/3.
    {
        const double cxx = c(0, 0), cxy = c(0, 1), cxz = c(0, 2), cyy = c(1, 1), cyz = c(1, 2), czz = c(2, 2);
        const double minors = cxx * cyy - cxy * cxy + cxx * czz - cxz * cxz + cyy * czz - cyz * cyz;
        const double det = cxx * (cyy * czz - cyz * cyz) - cxy * (cxy * czz - cyz * cxz) + cxz * (cxy * cyz - cyy * cxz);
        if (minors > 0 && det > 0) {
            const double g = det / minors - shift;
            const double pg = (g * g + m) * g - d;
            if (g > l && pg <= 0) l = g, p = pg;
        }
    }
    double last = HUGE_VAL;
    bool converged = false;
    for (int i = 0; i < 50; ++i) {
        const double dp = 3.0 * l * l + m;
        if (!(dp > 0)) return std::nullopt;  // at a multiple root
        const double step = p / dp;
        if (!(std::fabs(step) < last) || std::fabs(step) <= 1e-17 * t) {
            converged = true;
            break;
        }
        l -= step;
        // Near a simple root Newton's error after a step s is about s^2 |p''| / (2 p'), with
        // |p''| = 6 |l| <= 2 T and p' = (l1 - l3)(l2 - l3) >= 1e-3 (l1 - l3)^2 for what the gap
        // test below keeps: after a step <= 1e-13 T it is <= 1e-23 T^3 / (l1 - l3)^2, below
        // 1e-22 T for a plane (l1 - l3 >= T / 3), so the step that would show it (the last of
        // each fit) is skipped. Only a nearly isotropic covariance (l1 - l3 < 1e-3 T, which no
        // planarity bound keeps) could stop short of rounding.
        if (std::fabs(step) <= 1e-13 * t) {
            converged = true;
            break;
        }
        last = std::fabs(step);
        p = (l * l + m) * l - d;
    }
    if (!converged) return std::nullopt;

    // b's other two eigenvalues: their sum is -l (trace 0) and their product m + l^2 (m is the sum
    // of the pairwise products).
    PlaneEigen out;
    const double r = std::sqrt(std::max(-m - 0.75 * l * l, 0.0));
    out.lambda1 = shift - 0.5 * l + r;
    out.lambda2 = shift - 0.5 * l - r;
    out.lambda3 = shift + l;
    // e3 is accurate to about (rounding of lambda3) / (lambda2 - lambda3): refuse small gaps.
    if (!(out.lambda2 - out.lambda3 >= 1e-3 * (out.lambda1 - out.lambda3))) return std::nullopt;

    // e3: c - lambda3 I = b - l I has rank 2; its kernel is the cross product of two of its rows
    // (the largest of the three: the two most independent).
    const Eigen::Vector3d r0(xx - l, xy, xz), r1(xy, yy - l, yz), r2(xz, yz, zz - l);
    const Eigen::Vector3d c01 = r0.cross(r1), c02 = r0.cross(r2), c12 = r1.cross(r2);
    const Eigen::Vector3d* best = &c01;
    double norm2 = c01.squaredNorm();
    for (const Eigen::Vector3d* row_cross : {&c02, &c12})
        if (row_cross->squaredNorm() > norm2) best = row_cross, norm2 = row_cross->squaredNorm();
    if (!(norm2 > 0)) return std::nullopt;
    out.e3 = *best / std::sqrt(norm2);
    return out;
}

}  // namespace lidarsurf
