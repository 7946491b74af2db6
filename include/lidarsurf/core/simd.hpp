#pragma once
// Which vector instructions the fast path's byte scans use (issue 5). The voxel lists' level pass
// and their per-level scans (NeighbourhoodWindow) compare 16 list entries per instruction with
// SSE2, x86-64's baseline; on a CPU with AVX2 the same loops compare 32 (64 with AVX-512BW), chosen at run time, so
// one portable binary runs the wider code where it can. The scans compare bytes and select
// records (the slab walk also ranks a voxel's record with POPCNT where it can, instead of a byte
// table); the additions of the records are the same operations in the same order whatever the
// level, so every level gives the same bits (tests/core/test_simd.cpp,
// tests/surface/test_neighbourhood_window.cpp).
#include <utility>

namespace lidarsurf {

enum class SimdLevel {
    Portable,  ///< the scalar code (non-x86 CPUs, and builds with LIDARSURF_SCALAR)
    Sse2,      ///< 16 bytes per compare
    Avx2,      ///< 32 bytes per compare; with the BMI1, BMI2 and POPCNT instructions every AVX2 CPU has
    Avx512,    ///< 64 bytes per compare (AVX-512 F, BW and VL, with the Avx2 level's instructions)
};

/// The widest level this build can run on this CPU.
SimdLevel supported_simd_level();
/// The narrowest level this build has: Portable with LIDARSURF_SCALAR (or off x86), else Sse2.
SimdLevel minimum_simd_level();
/// The level in use: supported_simd_level() unless changed by set_simd_level().
SimdLevel simd_level();
/// Uses `level` from now on, in every thread (tests, and `lidarsurf bench --simd` to compare the
/// levels within one run). Throws InvalidArgument for a level outside [minimum_simd_level(),
/// supported_simd_level()]. Not meant to be changed while a reconstruction runs.
void set_simd_level(SimdLevel level);

const char* to_string(SimdLevel level);

#if defined(__x86_64__) && defined(__GNUC__) && !defined(LIDARSURF_SCALAR)
/// The instruction sets of the Avx2 level, for `[[gnu::target(...)]]` (no FMA: see above).
#define LIDARSURF_AVX2_TARGET "avx2,bmi,bmi2,popcnt"
/// And of the Avx512 level.
#define LIDARSURF_AVX512_TARGET "avx512f,avx512bw,avx512vl," LIDARSURF_AVX2_TARGET
namespace simd_detail {
// f(args...) with everything it calls inlined (flatten) into a function compiled for AVX2 with
// BMI1/2 and POPCNT: scalar double code in VEX encoding, SSE4.1's roundsd for floor. No FMA.
template <typename F, typename... Args>
[[gnu::target(LIDARSURF_AVX2_TARGET), gnu::flatten]] inline void call_avx2(F& f, Args&... args) {
    f(args...);
}
}  // namespace simd_detail
#endif

/// Calls f(args...) as compiled for the Avx2 level when simd_level() is at least that (the same
/// operations, so the same results), else as it is: for hot loops of scalar arithmetic, which
/// the portable x86-64 build cannot give AVX2's instructions. One check per call: call it per
/// chunk of work, not per element.
template <typename F, typename... Args>
void call_at_simd_level(F&& f, Args&&... args) {
#if defined(__x86_64__) && defined(__GNUC__) && !defined(LIDARSURF_SCALAR)
    if (simd_level() >= SimdLevel::Avx2) return simd_detail::call_avx2(f, args...);
#endif
    f(args...);
}
/// "portable", "sse2", "avx2" or "avx512"; throws InvalidArgument for anything else.
SimdLevel simd_level_from_string(const char* name);

}  // namespace lidarsurf
