#include "lidarsurf/surface/plane_eigen.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "lidarsurf/core/simd.hpp"

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
    // steps per fit on KITTI 000000; the early stop below saves another). Rounding may put it right of the root (p > 0 there): then the start stays -T/3.
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
        // planarity bound keeps) could stop short of rounding. The same estimate, taken with this
        // step's own numbers (3 |l| s^2 / p', p' as used for the step), stops where the error left
        // is <= 1e-17 T, below the rounding of l (|l| is about T / 3): one Newton step (a
        // division) fewer in 96k of the 160k fits of KITTI 000000.
        if (std::fabs(step) <= 1e-13 * t || 3.0 * std::fabs(l) * step * step <= 1e-17 * t * dp) {
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

namespace {

#if defined(__x86_64__) && defined(__GNUC__) && !defined(LIDARSURF_SCALAR)
#define LIDARSURF_PLANE_EIGEN_LANES 1
}  // namespace
}  // namespace lidarsurf
#include <immintrin.h>
namespace lidarsurf {
namespace {
// plane_eigen in four lanes (GCC's vector extensions: element-wise IEEE operations, compiled for
// the Avx2 level, which has no FMA). Every `if` of the scalar code becomes a lane mask: `ok` for
// the lanes that have not failed a test, `live` for those still taking Newton steps. A comparison
// gives -1 (all bits) in a true lane, 0 in a false one; a failed lane computes on, harmlessly.
// The formulas are plane_eigen's, written again: one template for both (masks as bools for one
// value) gave the same bits but made the scalar fit, which the evaluation runs, 1-2 % slower end
// to end (branches became selects). The test
// PlaneEigen.FourLanesGiveTheScalarBits holds the two to the same bits.
using Lanes = double __attribute__((vector_size(32)));
using Mask = long long __attribute__((vector_size(32)));

[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline Lanes select(Mask m, Lanes a, Lanes b) { return (Lanes)((m & (Mask)a) | (~m & (Mask)b)); }
[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline Lanes abs_of(Lanes x) { return (Lanes)((Mask)x & ~(Mask)(Lanes{-0.0, -0.0, -0.0, -0.0})); }
[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline Mask finite(Lanes x) { return abs_of(x) < HUGE_VAL; }  // false for NaN
[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline Lanes square_root(Lanes x) { return (Lanes)_mm256_sqrt_pd((__m256d)x); }
[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline bool any(Mask m) { return _mm256_movemask_pd((__m256d)m) != 0; }

// (x, y, z) replaces (ex, ey, ez) in the lanes where its squared norm is larger than norm2.
[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline void take_if_larger(Lanes x, Lanes y, Lanes z, Lanes& ex, Lanes& ey, Lanes& ez, Lanes& norm2) {
    const Lanes n2 = x * x + y * y + z * z;
    const Mask larger = n2 > norm2;
    ex = select(larger, x, ex), ey = select(larger, y, ey), ez = select(larger, z, ez), norm2 = select(larger, n2, norm2);
}

[[gnu::target(LIDARSURF_AVX2_TARGET)]] std::array<std::optional<PlaneEigen>, 4> plane_eigen_lanes(const std::array<Eigen::Matrix3d, 4>& c) {
    Lanes cxx, cxy, cxz, cyy, cyz, czz;
    for (int i = 0; i < 4; ++i) {
        const Eigen::Matrix3d& a = c[static_cast<std::size_t>(i)];
        cxx[i] = a(0, 0), cxy[i] = a(0, 1), cxz[i] = a(0, 2), cyy[i] = a(1, 1), cyz[i] = a(1, 2), czz[i] = a(2, 2);
    }
    // The scalar code's steps, in its order (plane_eigen above).
    const Lanes t = cxx + cyy + czz;
    Mask ok = (t > 0) & finite(t);
    const Lanes shift = t / 3.0;
    const Lanes xx = cxx - shift, xy = cxy, xz = cxz, yy = cyy - shift, yz = cyz, zz = czz - shift;
    const Lanes m = xx * yy - xy * xy + xx * zz - xz * xz + yy * zz - yz * yz;
    const Lanes d = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    ok &= finite(m + d);
    Lanes l = -shift - 1e-12 * t;
    Lanes p = (l * l + m) * l - d;
    ok &= ~(p > 0);
    {
        const Lanes minors = cxx * cyy - cxy * cxy + cxx * czz - cxz * cxz + cyy * czz - cyz * cyz;
        const Lanes det = cxx * (cyy * czz - cyz * cyz) - cxy * (cxy * czz - cyz * cxz) + cxz * (cxy * cyz - cyy * cxz);
        const Lanes g = det / minors - shift;
        const Lanes pg = (g * g + m) * g - d;
        const Mask closer = (minors > 0) & (det > 0) & (g > l) & (pg <= 0);
        l = select(closer, g, l);
        p = select(closer, pg, p);
    }
    Lanes last = {HUGE_VAL, HUGE_VAL, HUGE_VAL, HUGE_VAL};
    Mask live = ok, converged = {0, 0, 0, 0};
    for (int i = 0; i < 50 && any(live); ++i) {
        const Lanes dp = 3.0 * l * l + m;
        const Mask root = live & ~(dp > 0);  // at a multiple root: fails
        ok &= ~root;
        live &= ~root;
        const Lanes step = p / dp, size = abs_of(step);
        const Mask stop = live & (~(size < last) | (size <= 1e-17 * t));  // converged, step not taken
        converged |= stop;
        live &= ~stop;
        l = select(live, l - step, l);
        const Mask done = live & ((size <= 1e-13 * t) | (3.0 * abs_of(l) * step * step <= 1e-17 * t * dp));  // converged with this step
        converged |= done;
        live &= ~done;
        last = select(live, size, last);
        p = select(live, (l * l + m) * l - d, p);
    }
    ok &= converged;
    const Lanes q = -m - 0.75 * l * l;
    const Lanes r = square_root(select(q < 0.0, Lanes{0, 0, 0, 0}, q));  // std::max(q, 0.0)
    const Lanes lambda1 = shift - 0.5 * l + r, lambda2 = shift - 0.5 * l - r, lambda3 = shift + l;
    ok &= lambda2 - lambda3 >= 1e-3 * (lambda1 - lambda3);
    // e3: the largest of the rows' cross products, first largest in the order c01, c02, c12.
    const Lanes r0x = xx - l, r0y = xy, r0z = xz, r1x = xy, r1y = yy - l, r1z = yz, r2x = xz, r2y = yz, r2z = zz - l;
    Lanes ex = r0y * r1z - r0z * r1y, ey = r0z * r1x - r0x * r1z, ez = r0x * r1y - r0y * r1x;
    Lanes norm2 = ex * ex + ey * ey + ez * ez;
    take_if_larger(r0y * r2z - r0z * r2y, r0z * r2x - r0x * r2z, r0x * r2y - r0y * r2x, ex, ey, ez, norm2);
    take_if_larger(r1y * r2z - r1z * r2y, r1z * r2x - r1x * r2z, r1x * r2y - r1y * r2x, ex, ey, ez, norm2);
    ok &= norm2 > 0;
    const Lanes norm = square_root(norm2);
    ex = ex / norm, ey = ey / norm, ez = ez / norm;
    std::array<std::optional<PlaneEigen>, 4> out;
    for (int i = 0; i < 4; ++i)
        if (ok[i]) out[static_cast<std::size_t>(i)] = PlaneEigen{lambda1[i], lambda2[i], lambda3[i], Eigen::Vector3d(ex[i], ey[i], ez[i])};
    return out;
}
#endif

}  // namespace

std::array<std::optional<PlaneEigen>, 4> plane_eigen4(const std::array<Eigen::Matrix3d, 4>& c) {
#if defined(LIDARSURF_PLANE_EIGEN_LANES)
    if (simd_level() >= SimdLevel::Avx2) return plane_eigen_lanes(c);
#endif
    return {plane_eigen(c[0]), plane_eigen(c[1]), plane_eigen(c[2]), plane_eigen(c[3])};
}

}  // namespace lidarsurf
