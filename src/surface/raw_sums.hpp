#pragma once
// The raw moments a neighbourhood window adds voxel by voxel (RawSums, RawSums4 for the AVX2 and
// AVX-512 kernels), shared by the window's walks (neighbourhood_window.cpp) and the voxel-list
// kernels (list_kernels.cpp). Internal to src/surface/. The SSE2 code (x86-64's baseline) unless
// LIDARSURF_SCALAR asks for the portable code.
#include <cstddef>
#include <type_traits>

#if defined(__SSE2__) && !defined(LIDARSURF_SCALAR)
#define LIDARSURF_SSE2 1
#include <immintrin.h>
#endif

#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"

namespace lidarsurf::window {

// Moments being accumulated, in locals (registers) rather than through a Moments; each voxel is
// added as raw moments about the reference point p (the header's formula):
//   n += w, s1 += w d, s2 += V_M2 + w d d^T   (w = |V|, d = V_mu - p, upper triangle of s2).
// With SSE2 the sums are pairs of doubles; every lane does the scalar code's operations in its
// order (no fused multiply-add), so both give the same bits.
static_assert(sizeof(PackedVoxels::Voxel) == 10 * sizeof(double) && offsetof(PackedVoxels::Voxel, zz) == 9 * sizeof(double),
              "RawSums reads a record as 10 consecutive doubles");
#if defined(LIDARSURF_SSE2)
struct RawSums {
    __m128d p0x, pyz;           // (0, px), (py, pz)
    __m128d s1xy, s1zn;         // (s1x, s1y), (s1z, n)
    __m128d sxx_xy, sxz_yy, syz_zz;
    RawSums(const Moments& acc, const Eigen::Vector3d& p)
        : p0x(_mm_set_pd(p.x(), 0.0)), pyz(_mm_set_pd(p.z(), p.y())), s1xy(_mm_set_pd(acc.s1.y(), acc.s1.x())),
          s1zn(_mm_set_pd(acc.n, acc.s1.z())), sxx_xy(_mm_set_pd(acc.s2(0, 1), acc.s2(0, 0))),
          sxz_yy(_mm_set_pd(acc.s2(1, 1), acc.s2(0, 2))), syz_zz(_mm_set_pd(acc.s2(2, 2), acc.s2(1, 2))) {}
    void add(const PackedVoxels::Voxel& s) {
        const double* r = &s.count;  // count, mx, my, mz, xx, xy, xz, yy, yz, zz
        const __m128d wdx = _mm_sub_pd(_mm_loadu_pd(r), p0x);      // (w, dx): w - 0 = w
        const __m128d dyz = _mm_sub_pd(_mm_loadu_pd(r + 2), pyz);  // (dy, dz)
        const __m128d w = _mm_unpacklo_pd(wdx, wdx);
        const __m128d dxy = _mm_shuffle_pd(wdx, dyz, 1);           // (dx, dy)
        const __m128d wxy = _mm_mul_pd(w, dxy);                    // (wx, wy)
        const __m128d wyz = _mm_mul_pd(w, dyz);                    // (wy, wz)
        s1xy = _mm_add_pd(s1xy, wxy);
        s1zn = _mm_add_pd(s1zn, _mm_shuffle_pd(wyz, w, 1));       // += (wz, w)
        sxx_xy = _mm_add_pd(sxx_xy, _mm_add_pd(_mm_loadu_pd(r + 4), _mm_mul_pd(_mm_unpacklo_pd(wxy, wxy), dxy)));  // (xx + wx dx, xy + wx dy)
        sxz_yy = _mm_add_pd(sxz_yy, _mm_add_pd(_mm_loadu_pd(r + 6), _mm_mul_pd(wxy, _mm_shuffle_pd(dyz, dyz, 1))));  // (xz + wx dz, yy + wy dy)
        syz_zz = _mm_add_pd(syz_zz, _mm_add_pd(_mm_loadu_pd(r + 8), _mm_mul_pd(wyz, _mm_unpackhi_pd(dyz, dyz))));  // (yz + wy dz, zz + wz dz)
    }
    void store(Moments& acc) const {  // the scatter is symmetric
        alignas(16) double v[10];
        _mm_store_pd(v, s1xy);
        _mm_store_pd(v + 2, s1zn);
        _mm_store_pd(v + 4, sxx_xy);
        _mm_store_pd(v + 6, sxz_yy);
        _mm_store_pd(v + 8, syz_zz);
        acc.n = v[3];
        acc.s1 = {v[0], v[1], v[2]};
        acc.s2 << v[4], v[5], v[6], v[5], v[7], v[8], v[6], v[8], v[9];
    }
};
// The same sums in 256-bit registers, for the kernels compiled for the Avx2 and Avx512 levels:
// (n, s1x, s1y, s1z), (sxx, sxy, sxz, syy), (syz, szz). Each lane does the operation of the
// SSE2 lane above in the same order (w * w in the first lane is computed and dropped), without
// FMA, so the same bits in 16 instructions per voxel instead of 38.
struct RawSums4 {
    __m256d p4;          // (0, px, py, pz)
    __m256d s1n, s2a;    // (n, s1x, s1y, s1z), (sxx, sxy, sxz, syy)
    __m128d s2b;         // (syz, szz)
    [[gnu::target(LIDARSURF_AVX2_TARGET)]] RawSums4(const Moments& acc, const Eigen::Vector3d& p)
        : p4(_mm256_set_pd(p.z(), p.y(), p.x(), 0.0)), s1n(_mm256_set_pd(acc.s1.z(), acc.s1.y(), acc.s1.x(), acc.n)),
          s2a(_mm256_set_pd(acc.s2(1, 1), acc.s2(0, 2), acc.s2(0, 1), acc.s2(0, 0))), s2b(_mm_set_pd(acc.s2(2, 2), acc.s2(1, 2))) {}
    [[gnu::target(LIDARSURF_AVX2_TARGET)]] void add(const PackedVoxels::Voxel& s) {
        const double* r = &s.count;  // count, mx, my, mz, xx, xy, xz, yy, yz, zz
        const __m256d wd = _mm256_sub_pd(_mm256_loadu_pd(r), p4);                  // (w, dx, dy, dz)
        const __m256d wwd = _mm256_mul_pd(_mm256_permute4x64_pd(wd, 0x00), wd);    // (w w, w dx, w dy, w dz)
        s1n = _mm256_add_pd(s1n, _mm256_blend_pd(wwd, wd, 0x1));                  // += (w, w dx, w dy, w dz)
        const __m256d u = _mm256_permute4x64_pd(wwd, 0x95);                        // (w dx, w dx, w dx, w dy)
        const __m256d v = _mm256_permute4x64_pd(wd, 0xb9);                         // (dx, dy, dz, dy)
        s2a = _mm256_add_pd(s2a, _mm256_add_pd(_mm256_loadu_pd(r + 4), _mm256_mul_pd(u, v)));
        const __m128d dyz = _mm256_extractf128_pd(wd, 1);                          // (dy, dz)
        const __m128d wyz = _mm256_extractf128_pd(wwd, 1);                         // (w dy, w dz)
        s2b = _mm_add_pd(s2b, _mm_add_pd(_mm_loadu_pd(r + 8), _mm_mul_pd(wyz, _mm_unpackhi_pd(dyz, dyz))));
    }
    [[gnu::target(LIDARSURF_AVX2_TARGET)]] void store(Moments& acc) const {  // the scatter is symmetric
        alignas(32) double a[4], b[4], c[2];
        _mm256_store_pd(a, s1n);
        _mm256_store_pd(b, s2a);
        _mm_store_pd(c, s2b);
        acc.n = a[0];
        acc.s1 = {a[1], a[2], a[3]};
        acc.s2 << b[0], b[1], b[2], b[1], b[3], c[0], b[2], c[0], c[1];
    }
};
template <bool Wide>
using SumsFor = std::conditional_t<Wide, RawSums4, RawSums>;
#else
struct RawSums {
    double px, py, pz;
    double n, s1x, s1y, s1z, sxx, sxy, sxz, syy, syz, szz;
    RawSums(const Moments& acc, const Eigen::Vector3d& p)
        : px(p.x()), py(p.y()), pz(p.z()), n(acc.n), s1x(acc.s1.x()), s1y(acc.s1.y()), s1z(acc.s1.z()), sxx(acc.s2(0, 0)),
          sxy(acc.s2(0, 1)), sxz(acc.s2(0, 2)), syy(acc.s2(1, 1)), syz(acc.s2(1, 2)), szz(acc.s2(2, 2)) {}
    void add(const PackedVoxels::Voxel& s) {
        const double w = s.count;
        const double dx = s.mx - px, dy = s.my - py, dz = s.mz - pz;
        const double wx = w * dx, wy = w * dy, wz = w * dz;
        n += w;
        s1x += wx, s1y += wy, s1z += wz;
        sxx += s.xx + wx * dx, sxy += s.xy + wx * dy, sxz += s.xz + wx * dz;
        syy += s.yy + wy * dy, syz += s.yz + wy * dz, szz += s.zz + wz * dz;
    }
    void store(Moments& acc) const {  // the scatter is symmetric
        acc.n = n;
        acc.s1 = {s1x, s1y, s1z};
        acc.s2 << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
    }
};
template <bool Wide>
using SumsFor = RawSums;
#endif

}  // namespace lidarsurf::window
