#include "list_kernels.hpp"

#include <algorithm>
#include <bit>

namespace lidarsurf::window {

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

}  // namespace lidarsurf::window
