#include "lidarsurf/surface/neighbourhood_window.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <memory>
#include <new>
#include <string>

// The SSE2 code (x86-64's baseline) unless LIDARSURF_SCALAR asks for the portable code.
#if defined(__SSE2__) && !defined(LIDARSURF_SCALAR)
#define LIDARSURF_SSE2 1
#include <immintrin.h>
#endif

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"

namespace lidarsurf {

VoxelStats Moments::to_stats(const Eigen::Vector3d& p) const {
    VoxelStats s;
    if (n <= 0) return s;
    s.count = static_cast<std::uint64_t>(n);
    const Eigen::Vector3d d = s1 / n;
    s.mean = p + d;
    s.scatter = SymmetricMatrix3::upper_of(s2 - s1 * d.transpose());  // sum (x-p)(x-p)^T - n d d^T = sum (x-mu)(x-mu)^T
    return s;
}

namespace {
using Map = BlockMap<std::int32_t>;

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

// Padding of the voxel list: a coordinate whose level, at least max(v, 201) - min(v, 200) >=
// 201 - 71 for any vertex coordinate v <= K + 7 <= 71 (K <= 64), exceeds every level asked; real
// coordinates are < 2 K + 7 <= 135.
constexpr std::uint8_t kPad = 200;
constexpr std::size_t kLanes = 16;
// Whether the box [l, h] (window coordinates) leaves the window [0, size)^3: one test rather than
// Eigen's any(), which branches per coordinate.
inline bool outside_window(const VoxelKey& l, const VoxelKey& h, int size) {
    return ((l.x() | l.y() | l.z()) < 0) | (std::max({h.x(), h.y(), h.z()}) >= size);
}
// A layer of a window block that holds voxels of the list's region (build_list).
struct LayerBits {
    const PackedVoxels::Block* block;
    int bx, by, z;
    std::uint64_t bits;
};
// What a window block that holds no voxel points to: no layer holds a voxel, so the walks skip it
// with the test of its layers they make anyway (a separate test for an absent block mispredicted
// as often).
const PackedVoxels::Block kNoVoxels{};

#if defined(LIDARSURF_SSE2)
// L_a = max(v, i + 1) - min(v, i) for 16 coordinates i (unsigned bytes, no wrap: i + 1 <= 201).
inline __m128i axis_level(const std::uint8_t* i, __m128i v) {
    const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(i));
    return _mm_sub_epi8(_mm_max_epu8(v, _mm_add_epi8(c, _mm_set1_epi8(1))), _mm_min_epu8(v, c));
}
inline __m128i bytes(int value) { return _mm_set1_epi8(static_cast<char>(value)); }
#else
inline int axis_level(int i, int v) { return std::max(v, i + 1) - std::min(v, i); }
#endif

// The two scans of a voxel list (NeighbourhoodWindow::levels and add_listed), one kernel per
// SimdLevel (core/simd.hpp). The arrays come as local pointers: a byte store may alias anything,
// so through the vectors the compiler would reload every data pointer in each iteration.
struct ListArrays {
    const std::uint8_t *x, *y, *z, *weight;
    const PackedVoxels::Voxel* const* records;
    std::size_t count;  // a multiple of kLanes
};
ListArrays arrays_of(const NeighbourhoodWindow::VoxelList& l) { return {l.x, l.y, l.z, l.weight, l.records, l.size}; }
// The points (weights saturated at 255) of the entries with level 1 and with level <= 2.
struct LevelCounts {
    int in1 = 0, in2 = 0;
};

#if defined(LIDARSURF_SSE2)
// Weights are added with unsigned saturation per byte lane: a lane that saturates holds >= 255
// points, so a count compared with n_min <= 255 is exact, whatever the lanes' number.
inline int sum_bytes(__m128i v) {
    const __m128i s = _mm_sad_epu8(v, _mm_setzero_si128());
    return _mm_cvtsi128_si32(s) + _mm_extract_epi16(s, 4);
}
// Levels of the 16 entries at c into out + c; their weights into in1 (level 1), in2 (level <= 2).
inline void levels16(const ListArrays& l, std::size_t c, const VoxelKey& r, std::uint8_t* out, __m128i& in1, __m128i& in2) {
    const __m128i level = _mm_max_epu8(axis_level(l.x + c, bytes(r.x())), _mm_max_epu8(axis_level(l.y + c, bytes(r.y())), axis_level(l.z + c, bytes(r.z()))));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + c), level);
    const __m128i weight = _mm_loadu_si128(reinterpret_cast<const __m128i*>(l.weight + c));
    in1 = _mm_adds_epu8(in1, _mm_and_si128(_mm_cmpeq_epi8(level, bytes(1)), weight));
    in2 = _mm_adds_epu8(in2, _mm_and_si128(_mm_cmpeq_epi8(_mm_min_epu8(level, bytes(2)), level), weight));
}
LevelCounts levels_sse2(const ListArrays& l, const VoxelKey& r, std::uint8_t* out) {
    __m128i in1 = _mm_setzero_si128(), in2 = _mm_setzero_si128();
    for (std::size_t c = 0; c < l.count; c += kLanes) levels16(l, c, r, out, in1, in2);
    return {sum_bytes(in1), sum_bytes(in2)};
}
// Bit i set for the entry c + i with lo <= level <= k (lo: 1 for the whole cube, k for the
// shell), i.e. whose level is unchanged when clamped to [lo, k]: one test for both cases. The
// kernels add the entries in list order.
inline unsigned hits16(const std::uint8_t* levels, std::size_t c, int lo, int k) {
    const __m128i level = _mm_loadu_si128(reinterpret_cast<const __m128i*>(levels + c));
    return static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_min_epu8(_mm_max_epu8(level, bytes(lo)), bytes(k)), level)));
}
void add_listed_sse2(const ListArrays& l, const std::uint8_t* levels, int lo, int k, const Eigen::Vector3d& p, Moments& acc) {
    RawSums sums(acc, p);
    for (std::size_t c = 0; c < l.count; c += kLanes)
        for (unsigned bits = hits16(levels, c, lo, k); bits; bits &= bits - 1) sums.add(*l.records[c + static_cast<std::size_t>(std::countr_zero(bits))]);
    sums.store(acc);
}

// The same 32 entries per compare; a list of an odd number of 16-entry chunks ends with one
// chunk of the SSE2 code. Integer compares only, and the additions are RawSums' in list order:
// the same bits as the SSE2 kernels (no FMA is enabled here).
[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline __m256i bytes32(int value) { return _mm256_set1_epi8(static_cast<char>(value)); }
[[gnu::target(LIDARSURF_AVX2_TARGET)]] inline __m256i axis_level32(const std::uint8_t* i, __m256i v) {
    const __m256i c = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(i));
    return _mm256_sub_epi8(_mm256_max_epu8(v, _mm256_add_epi8(c, bytes32(1))), _mm256_min_epu8(v, c));
}
[[gnu::target(LIDARSURF_AVX2_TARGET)]] LevelCounts levels_avx2(const ListArrays& l, const VoxelKey& r, std::uint8_t* out) {
    const __m256i vx = bytes32(r.x()), vy = bytes32(r.y()), vz = bytes32(r.z()), one = bytes32(1), two = bytes32(2);
    __m256i in1 = _mm256_setzero_si256(), in2 = _mm256_setzero_si256();
    std::size_t c = 0;
    for (; c + 2 * kLanes <= l.count; c += 2 * kLanes) {
        const __m256i level = _mm256_max_epu8(axis_level32(l.x + c, vx), _mm256_max_epu8(axis_level32(l.y + c, vy), axis_level32(l.z + c, vz)));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + c), level);
        const __m256i weight = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(l.weight + c));
        in1 = _mm256_adds_epu8(in1, _mm256_and_si256(_mm256_cmpeq_epi8(level, one), weight));
        in2 = _mm256_adds_epu8(in2, _mm256_and_si256(_mm256_cmpeq_epi8(_mm256_min_epu8(level, two), level), weight));
    }
    __m128i tail1 = _mm_setzero_si128(), tail2 = _mm_setzero_si128();
    if (c < l.count) levels16(l, c, r, out, tail1, tail2);
    return {sum_bytes(_mm256_castsi256_si128(in1)) + sum_bytes(_mm256_extracti128_si256(in1, 1)) + sum_bytes(tail1),
            sum_bytes(_mm256_castsi256_si128(in2)) + sum_bytes(_mm256_extracti128_si256(in2, 1)) + sum_bytes(tail2)};
}
[[gnu::target(LIDARSURF_AVX2_TARGET)]] void add_listed_avx2(const ListArrays& l, const std::uint8_t* levels, int lo, int k, const Eigen::Vector3d& p, Moments& acc) {
    RawSums4 sums(acc, p);
    const __m256i lo32 = bytes32(lo), k32 = bytes32(k);
    std::size_t c = 0;
    for (; c + 2 * kLanes <= l.count; c += 2 * kLanes) {
        const __m256i level = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(levels + c));
        const __m256i hit = _mm256_cmpeq_epi8(_mm256_min_epu8(_mm256_max_epu8(level, lo32), k32), level);
        for (auto bits = static_cast<unsigned>(_mm256_movemask_epi8(hit)); bits; bits &= bits - 1)
            sums.add(*l.records[c + static_cast<std::size_t>(std::countr_zero(bits))]);
    }
    if (c < l.count)
        for (unsigned bits = hits16(levels, c, lo, k); bits; bits &= bits - 1) sums.add(*l.records[c + static_cast<std::size_t>(std::countr_zero(bits))]);
    sums.store(acc);
}

// 64 entries per compare with AVX-512BW: compares give bit masks directly, and the last, partial
// step loads and stores under a mask (a list holds a multiple of 16 entries). AVX-512F brings
// fused multiply-adds, which the compiler would use for RawSums' products and sums: this file is
// compiled with -ffp-contract=off (CMakeLists.txt), so the additions keep their bits.
[[gnu::target(LIDARSURF_AVX512_TARGET)]] inline __mmask64 lanes_below(std::size_t n) { return n >= 64 ? ~__mmask64{0} : (__mmask64{1} << n) - 1; }
[[gnu::target(LIDARSURF_AVX512_TARGET)]] inline __m512i axis_level64(const std::uint8_t* i, __m512i v, __mmask64 m) {
    const __m512i c = _mm512_maskz_loadu_epi8(m, i);
    return _mm512_sub_epi8(_mm512_max_epu8(v, _mm512_add_epi8(c, _mm512_set1_epi8(1))), _mm512_min_epu8(v, c));
}
[[gnu::target(LIDARSURF_AVX512_TARGET)]] LevelCounts levels_avx512(const ListArrays& l, const VoxelKey& r, std::uint8_t* out) {
    const __m512i vx = _mm512_set1_epi8(static_cast<char>(r.x())), vy = _mm512_set1_epi8(static_cast<char>(r.y())),
                  vz = _mm512_set1_epi8(static_cast<char>(r.z())), one = _mm512_set1_epi8(1), two = _mm512_set1_epi8(2);
    __m512i in1 = _mm512_setzero_si512(), in2 = _mm512_setzero_si512();
    for (std::size_t c = 0; c < l.count; c += 64) {
        const __mmask64 m = lanes_below(l.count - c);
        const __m512i level = _mm512_max_epu8(axis_level64(l.x + c, vx, m), _mm512_max_epu8(axis_level64(l.y + c, vy, m), axis_level64(l.z + c, vz, m)));
        _mm512_mask_storeu_epi8(out + c, m, level);
        const __m512i weight = _mm512_maskz_loadu_epi8(m, l.weight + c);  // 0 beyond the list: adds nothing
        in1 = _mm512_mask_adds_epu8(in1, _mm512_cmpeq_epi8_mask(level, one), in1, weight);
        in2 = _mm512_mask_adds_epu8(in2, _mm512_cmple_epu8_mask(level, two), in2, weight);
    }
    // The lanes' sums through memory (GCC 12's _mm512_reduce_add_epi64 warns inside its header).
    alignas(64) std::uint64_t sums1[8], sums2[8];
    _mm512_store_si512(sums1, _mm512_sad_epu8(in1, _mm512_setzero_si512()));
    _mm512_store_si512(sums2, _mm512_sad_epu8(in2, _mm512_setzero_si512()));
    LevelCounts n;
    for (int i = 0; i < 8; ++i) n.in1 += static_cast<int>(sums1[i]), n.in2 += static_cast<int>(sums2[i]);
    return n;
}
[[gnu::target(LIDARSURF_AVX512_TARGET)]] void add_listed_avx512(const ListArrays& l, const std::uint8_t* levels, int lo, int k, const Eigen::Vector3d& p, Moments& acc) {
    RawSums4 sums(acc, p);
    const __m512i lo64 = _mm512_set1_epi8(static_cast<char>(lo)), k64 = _mm512_set1_epi8(static_cast<char>(k));
    for (std::size_t c = 0; c < l.count; c += 64) {
        const __mmask64 m = lanes_below(l.count - c);
        const __m512i level = _mm512_maskz_loadu_epi8(m, levels + c);  // 0 beyond the list: below lo >= 1
        for (std::uint64_t bits = _mm512_mask_cmpge_epu8_mask(_mm512_cmple_epu8_mask(level, k64), level, lo64); bits; bits &= bits - 1)
            sums.add(*l.records[c + static_cast<std::size_t>(std::countr_zero(bits))]);
    }
    sums.store(acc);
}
#else
LevelCounts levels_portable(const ListArrays& l, const VoxelKey& r, std::uint8_t* out) {
    LevelCounts n;
    for (std::size_t c = 0; c < l.count; ++c) {
        const int level = std::max({axis_level(l.x[c], r.x()), axis_level(l.y[c], r.y()), axis_level(l.z[c], r.z())});
        out[c] = static_cast<std::uint8_t>(level);
        if (level == 1) n.in1 += l.weight[c];
        if (level <= 2) n.in2 += l.weight[c];
    }
    return n;
}
void add_listed_portable(const ListArrays& l, const std::uint8_t* levels, int lo, int k, const Eigen::Vector3d& p, Moments& acc) {
    RawSums sums(acc, p);
    for (std::size_t c = 0; c < l.count; ++c)
        if (levels[c] >= lo && levels[c] <= k) sums.add(*l.records[c]);
    sums.store(acc);
}
#endif
}  // namespace

NeighbourhoodWindow::NeighbourhoodWindow(const PackedVoxels& voxels, const VoxelKey& vertex_block, int max_level, int cube_level)
    : voxels_(&voxels), alpha_(voxels.grid().voxel_size()), cube_level_(cube_level < 0 ? max_level : cube_level) {
    if (max_level < 1 || max_level > 64 || cube_level_ < 1 || cube_level_ > max_level)
        throw InvalidArgument("neighbourhood window: need 1 <= cube_level <= max_level <= 64 (got cube_level " + std::to_string(cube_level_) +
                              ", max_level " + std::to_string(max_level) + ")");
    // H^k(v) = voxels [v-k, v+k-1]: for v in [8b, 8b+7] that is [8b-k, 8b+6+k], within
    // radius ceil(k/8) blocks of b.
    radius_ = (max_level + Map::kSize - 1) / Map::kSize;
    side_ = 2 * radius_ + 1;
    reset(vertex_block);
}

void NeighbourhoodWindow::reset(const VoxelKey& vertex_block) {
    vertex_block_ = vertex_block;
    first_voxel_ = (vertex_block.array() - radius_) * Map::kSize;
    // Every block "not looked up yet": a new stamp (a window is reset ~12k times per KITTI frame;
    // writing its 125 entries each time was 12 MB of stores), the entries once when it wraps.
    const auto volume = static_cast<std::size_t>(side_ * side_ * side_);
    if (blocks_.size() != volume || ++stamp_ == 0) {
        blocks_.assign(volume, WindowBlock{});
        stamp_ = 1;
    }
    simd_ = simd_level();
    shared_ = nullptr;
    arena_ = nullptr;
    list_ = nullptr;
    levels_valid_ = false;
}

void NeighbourhoodWindow::share_list(SharedList* list, ListArena* arena) {
    shared_ = list;
    arena_ = arena;
    list_ = nullptr;
    levels_valid_ = false;
}

inline const PackedVoxels::Block* NeighbourhoodWindow::block(int bx, int by, int bz) const {
    WindowBlock& b = blocks_[static_cast<std::size_t>(bx + side_ * (by + side_ * bz))];
    if (b.stamp != stamp_) [[unlikely]]
        b = {look_up(bx, by, bz), stamp_};
    return b.block;
}

const PackedVoxels::Block* NeighbourhoodWindow::look_up(int bx, int by, int bz) const {
    const PackedVoxels::Block* b = voxels_->find(Map::block_of(first_voxel_) + VoxelKey(bx, by, bz));
    return b ? b : &kNoVoxels;
}

template <typename F>
void NeighbourhoodWindow::for_each_block(const VoxelKey& l, const VoxelKey& h, F&& f) const {
    constexpr int B = Map::kSize, m = B - 1;
    for (int bz = l.z() / B; bz <= h.z() / B; ++bz)
        for (int by = l.y() / B; by <= h.y() / B; ++by)
            for (int bx = l.x() / B; bx <= h.x() / B; ++bx) {
                const PackedVoxels::Block* block = this->block(bx, by, bz);
                // The box's layers within this block that hold a voxel (most blocks of a lidar
                // frame hold a few layers of ground or facade): the others are skipped.
                const int z0 = std::max(l.z(), bz * B), z1 = std::min(h.z(), bz * B + m);
                const unsigned layers = block->layers & ((0xffu >> (m - ((z1 - z0) & m))) << (z0 & m));
                if (!layers) continue;
                // The box within this block, as an 8x8 layer mask.
                const int x0 = std::max(l.x(), bx * B), x1 = std::min(h.x(), bx * B + m);
                const int y0 = std::max(l.y(), by * B), y1 = std::min(h.y(), by * B + m);
                f(*block, VoxelKey(bx, by, bz), layers, layer_mask(x0 & m, x1 & m, y0 & m, y1 & m));
            }
}

void NeighbourhoodWindow::add_shell(const VoxelKey& lo, const VoxelKey& hi, int inset, const Eigen::Vector3d& p,
                                    Moments& acc) const {
    constexpr int B = Map::kSize, m = B - 1;
    const VoxelKey l = lo - first_voxel_, h = hi - first_voxel_;  // window coordinates
    if (outside_window(l, h, side_ * B))
        throw InvalidArgument("neighbourhood box beyond the window's blocks: build the window with the configuration's max_reach()");
    // The hole: [l + inset, h - inset] in x and y, on the layers strictly inside [l.z, h.z].
    const VoxelKey il = l.array() + inset, ih = h.array() - inset;
    RawSums sums(acc, p);
    for_each_block(l, h, [&](const PackedVoxels::Block& block, const VoxelKey& b, unsigned layers, std::uint64_t full) {
        std::uint64_t ring = full;
        const int hx0 = std::max(il.x(), b.x() * B), hx1 = std::min(ih.x(), b.x() * B + m);
        const int hy0 = std::max(il.y(), b.y() * B), hy1 = std::min(ih.y(), b.y() * B + m);
        if (inset > 0 && hx0 <= hx1 && hy0 <= hy1) ring &= ~layer_mask(hx0 & m, hx1 & m, hy0 & m, hy1 & m);
        for (; layers; layers &= layers - 1) {
            const int layer = std::countr_zero(layers), z = b.z() * B + layer;
            const bool cap = inset == 0 || z == l.z() || z == h.z();
            for (std::uint64_t bits = (*block.occupancy)[static_cast<std::size_t>(layer)] & (cap ? full : ring); bits; bits &= bits - 1)
                sums.add(block.at(std::countr_zero(bits) | (layer << 6)));
        }
    });
    sums.store(acc);
}

void NeighbourhoodWindow::add_slab(const VoxelKey& lo, const VoxelKey& hi, bool ring, const Eigen::Vector3d& p, Moments& acc) const {
#if defined(LIDARSURF_SSE2)
    if (simd_ >= SimdLevel::Avx2) return add_slab_v3(lo, hi, ring, p, acc);
#endif
    add_slab_walk<false>(lo, hi, ring, p, acc);
}

#if defined(LIDARSURF_SSE2)
// flatten: the walk and RawSums4's methods (which need AVX2) are inlined here, where it is on.
[[gnu::target(LIDARSURF_AVX2_TARGET), gnu::flatten]] void NeighbourhoodWindow::add_slab_v3(const VoxelKey& lo, const VoxelKey& hi, bool ring,
                                                                             const Eigen::Vector3d& p, Moments& acc) const {
    add_slab_walk<true>(lo, hi, ring, p, acc);
}
#endif

template <bool Popcount>
[[gnu::always_inline]] inline void NeighbourhoodWindow::add_slab_walk(const VoxelKey& lo, const VoxelKey& hi, bool ring, const Eigen::Vector3d& p,
                                                                      Moments& acc) const {
    constexpr int B = Map::kSize, m = B - 1;
    const VoxelKey l = lo - first_voxel_, h = hi - first_voxel_;  // window coordinates
    if (outside_window(l, h, side_ * B))
        throw InvalidArgument("neighbourhood box beyond the window's blocks: build the window with the configuration's max_reach()");
    SumsFor<Popcount> sums(acc, p);
    const int bx0 = l.x() / B, bx1 = h.x() / B;
    for (int bz = l.z() / B; bz <= h.z() / B; ++bz) {
        // The slab's layers in this block, as a bit mask of layer indices.
        const int z0 = std::max(l.z(), bz * B) & m, z1 = std::min(h.z(), bz * B + m) & m;
        const unsigned slab_layers = (0xffu >> (m - (z1 - z0))) << z0;
        for (int by = l.y() / B; by <= h.y() / B; ++by) {
            const std::uint64_t rows = layer_rows(std::max(l.y(), by * B) & m, std::min(h.y(), by * B + m) & m);
            const int hy0 = std::max(l.y() + 1, by * B), hy1 = std::min(h.y() - 1, by * B + m);
            const std::uint64_t hole_rows = ring && hy0 <= hy1 ? layer_rows(hy0 & m, hy1 & m) : 0;
            for (int bx = bx0; bx <= bx1; ++bx) {
                const PackedVoxels::Block* block = this->block(bx, by, bz);
                unsigned layers = block->layers & slab_layers;
                if (!layers) continue;
                std::uint64_t mask = layer_columns(std::max(l.x(), bx * B) & m, std::min(h.x(), bx * B + m) & m) & rows;
                const int hx0 = std::max(l.x() + 1, bx * B), hx1 = std::min(h.x() - 1, bx * B + m);
                if (hole_rows && hx0 <= hx1) mask &= ~(layer_columns(hx0 & m, hx1 & m) & hole_rows);
                for (; layers; layers &= layers - 1) {
                    const int layer = std::countr_zero(layers);
                    for (std::uint64_t bits = (*block->occupancy)[static_cast<std::size_t>(layer)] & mask; bits; bits &= bits - 1) {
                        if constexpr (Popcount)
                            sums.add(block->at_layer_bit(layer, std::countr_zero(bits)));
                        else
                            sums.add(block->at(std::countr_zero(bits) | (layer << 6)));
                    }
                }
            }
        }
    }
    sums.store(acc);
}

void* NeighbourhoodWindow::ListArena::allocate(std::size_t bytes) {
    constexpr std::size_t kAlign = alignof(std::max_align_t), kChunk = std::size_t{1} << 18;
    bytes = (bytes + kAlign - 1) / kAlign * kAlign;
    if (bytes > left_) {
        // A new chunk (new[] aligns for any type); a request of over a quarter chunk gets its own,
        // so a chunk's unused tail stays under a quarter of it.
        const std::size_t size = bytes > kChunk / 4 ? bytes : kChunk;
        chunks_.push_back(std::make_unique_for_overwrite<std::byte[]>(size));
        if (size != kChunk) return chunks_.back().get();  // the current chunk stays current
        next_ = chunks_.back().get();
        left_ = size;
    }
    void* at = next_;
    next_ += bytes;
    left_ -= bytes;
    return at;
}

NeighbourhoodWindow::VoxelList NeighbourhoodWindow::VoxelList::padding(std::size_t size, std::uint8_t pad, ListArena* arena) {
    VoxelList l;
    l.size = size;
    const std::size_t bytes = size * (sizeof(const PackedVoxels::Voxel*) + 4);
    std::byte* storage;
    if (arena) {
        storage = static_cast<std::byte*>(arena->allocate(bytes));
        l.in_arena_ = true;
    } else {
        l.storage_ = std::make_unique_for_overwrite<std::byte[]>(bytes);
        storage = l.storage_.get();
    }
    l.records = reinterpret_cast<const PackedVoxels::Voxel**>(storage);  // at the allocation's start: aligned
    std::fill_n(l.records, size, nullptr);
    l.x = reinterpret_cast<std::uint8_t*>(l.records + size);
    l.y = l.x + size;
    l.z = l.y + size;
    l.weight = l.z + size;
    std::fill_n(l.x, 3 * size, pad);
    std::fill_n(l.weight, size, std::uint8_t{0});
    return l;
}

NeighbourhoodWindow::VoxelList NeighbourhoodWindow::build_list(ListArena* arena) const {
    constexpr int B = Map::kSize, m = B - 1;
    // The region [8b - K, 8b + 6 + K]^3, in window coordinates.
    const VoxelKey first = vertex_block_ * B - first_voxel_;  // the vertex block's first vertex
    const VoxelKey l = first.array() - cube_level_, h = first.array() + (6 + cube_level_);
    // The region's layers (one pass over the blocks), then their voxels (one allocation for all the
    // arrays, in `arena` when given).
    // A scratch array per thread, reused from list to list: a vector per list, grown by doubling,
    // was about five allocations per list, half of a KITTI frame's allocations.
    thread_local std::vector<LayerBits> layers;
    layers.clear();
    std::size_t count = 0;
    for_each_block(l, h, [&](const PackedVoxels::Block& block, const VoxelKey& b, unsigned in_box, std::uint64_t full) {
        for (; in_box; in_box &= in_box - 1) {
            const int layer = std::countr_zero(in_box);
            if (const std::uint64_t bits = (*block.occupancy)[static_cast<std::size_t>(layer)] & full) {
                layers.push_back({&block, b.x(), b.y(), b.z() * B + layer, bits});
                count += static_cast<std::size_t>(std::popcount(bits));
            }
        }
    });
    VoxelList list = VoxelList::padding((count + kLanes - 1) / kLanes * kLanes, kPad, arena);
    std::size_t at = 0;
    for (const LayerBits& layer : layers) {
        const auto z = static_cast<std::uint8_t>(layer.z - l.z());
        const int x0 = layer.bx * B - l.x(), y0 = layer.by * B - l.y(), offset = (layer.z & m) << 6;
        for (std::uint64_t bits = layer.bits; bits; bits &= bits - 1, ++at) {
            const int bit = std::countr_zero(bits);
            list.x[at] = static_cast<std::uint8_t>(x0 + (bit & m));
            list.y[at] = static_cast<std::uint8_t>(y0 + (bit >> 3));
            list.z[at] = z;
            list.records[at] = &layer.block->at(bit | offset);
            list.weight[at] = static_cast<std::uint8_t>(std::min(list.records[at]->count, 255.0));
        }
    }
    return list;
}

inline const NeighbourhoodWindow::VoxelList& NeighbourhoodWindow::list() const {
    if (list_) [[likely]]
        return *list_;
    return first_list();
}

const NeighbourhoodWindow::VoxelList& NeighbourhoodWindow::first_list() const {
    if (!shared_) {
        own_ = build_list();
        list_ = &own_;
        return own_;
    }
    const VoxelList* published = shared_->list_.load(std::memory_order_acquire);
    if (!published) {
        // In the arena (the list's header too) when there is one, else on the heap.
        const VoxelList* mine = arena_ ? new (arena_->allocate(sizeof(VoxelList))) VoxelList(build_list(arena_)) : new VoxelList(build_list());
        if (shared_->list_.compare_exchange_strong(published, mine, std::memory_order_acq_rel, std::memory_order_acquire))
            published = mine;
        else if (!mine->in_arena())  // `published` is another thread's identical list; a copy in the arena stays there unused
            delete mine;
    }
    list_ = published;
    return *list_;
}

bool NeighbourhoodWindow::listed(const VoxelKey& v, int k) const {
    return k >= 1 && k <= cube_level_ && same_key(Map::block_of(v), vertex_block_);
}

const std::uint8_t* NeighbourhoodWindow::levels(const VoxelKey& v) const {
    const VoxelList& list = this->list();
    if (levels_valid_ && same_key(level_vertex_, v)) return levels_.data();
    const VoxelKey r = (v - vertex_block_ * Map::kSize).array() + cube_level_;  // region coordinates, in [K, K + 7]
    const ListArrays arrays = arrays_of(list);
    if (levels_.size() < arrays.count) levels_.resize(arrays.count);
    // With the levels, the points of H^1(v) and H^2(v) (first_counted_level).
#if defined(LIDARSURF_SSE2)
    const LevelCounts n = simd_ == SimdLevel::Avx512 ? levels_avx512(arrays, r, levels_.data())
                          : simd_ == SimdLevel::Avx2 ? levels_avx2(arrays, r, levels_.data())
                                                     : levels_sse2(arrays, r, levels_.data());
#else
    const LevelCounts n = levels_portable(arrays, r, levels_.data());
#endif
    count1_ = n.in1;
    count2_ = n.in2;
    level_vertex_ = v;
    levels_valid_ = true;
    return levels_.data();
}

int NeighbourhoodWindow::first_counted_level(const VoxelKey& v, int n_min) const {
    if (n_min > 255) return 1;  // the weights saturate at 255
    levels(v);
    if (count1_ >= n_min) return 1;
    if (count2_ >= n_min || cube_level_ < 2) return 2;
    return 3;
}

void NeighbourhoodWindow::add_listed(const VoxelKey& v, int k, bool whole, Moments& acc) const {
    const std::uint8_t* levels = this->levels(v);
    const ListArrays arrays = arrays_of(list());
    const Eigen::Vector3d p = v.cast<double>() * alpha_;
    const int lo = whole ? 1 : k;
#if defined(LIDARSURF_SSE2)
    if (simd_ == SimdLevel::Avx512)
        add_listed_avx512(arrays, levels, lo, k, p, acc);
    else if (simd_ == SimdLevel::Avx2)
        add_listed_avx2(arrays, levels, lo, k, p, acc);
    else
        add_listed_sse2(arrays, levels, lo, k, p, acc);
#else
    add_listed_portable(arrays, levels, lo, k, p, acc);
#endif
}

void NeighbourhoodWindow::grow(const VoxelKey& v, int k, Moments& acc) const {
    // H^k \ H^{k-1} = {L = k} (every listed voxel has L >= 1, so k = 1 gives H^1).
    if (listed(v, k)) return add_listed(v, k, false, acc);
    // Otherwise: the box [v-k, v+k-1] without its interior [v-k+1, v+k-2] (empty for k = 1).
    add_shell(v.array() - k, v.array() + (k - 1), k > 1 ? 1 : 0, v.cast<double>() * alpha_, acc);
}

Moments NeighbourhoodWindow::box(const VoxelKey& v, int k) const {
    Moments acc;
    if (listed(v, k))
        add_listed(v, k, true, acc);
    else
        add_shell(v.array() - k, v.array() + (k - 1), 0, v.cast<double>() * alpha_, acc);
    return acc;
}

Moments NeighbourhoodWindow::slab(const VoxelKey& v, int k, SlabExtension e) const {
    Moments acc;
    const VoxelBox b = slab_box(v, k, e);
    add_slab(b.lo, b.hi, false, v.cast<double>() * alpha_, acc);
    return acc;
}

Moments NeighbourhoodWindow::sum_box(const VoxelBox& b, const VoxelKey& v) const {
    Moments acc;
    add_slab(b.lo, b.hi, false, v.cast<double>() * alpha_, acc);
    return acc;
}

void NeighbourhoodWindow::grow_slab(const VoxelKey& v, int k, Moments& acc, SlabExtension e) const {
    // S^k \ S^{k-1}: the x-y ring of width one around S^{k-1}'s x-y range, on both layers.
    const VoxelBox b = slab_box(v, k, e);
    add_slab(b.lo, b.hi, true, v.cast<double>() * alpha_, acc);
}

}  // namespace lidarsurf
