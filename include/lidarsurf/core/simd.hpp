#pragma once
// Which vector instructions the fast path uses (docs/method.md, "Vector instructions
// chosen at run time"). The build is portable x86-64 (SSE2); the hot code also exists for AVX2
// (with BMI1/2 and POPCNT) and AVX-512, chosen at run time: the voxel lists' scans compare 16, 32
// or 64 entries per instruction, the slab walk ranks records with POPCNT, and the vertex
// evaluation, marching cubes and the insertion loops run as copies compiled for AVX2. Every level
// does the same arithmetic in the same order and none fuses multiply-adds, so every level gives
// the same results (tests/core/test_simd.cpp, tests/surface/test_neighbourhood_window.cpp,
// tests/cli/test_cli.sh, tests/cli/test_no_fma.sh).
#include <utility>
#include <vector>

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
/// Every level from minimum_simd_level() to supported_simd_level(), narrowest first.
std::vector<SimdLevel> available_simd_levels();
/// The level in use: supported_simd_level() unless changed by set_simd_level().
SimdLevel simd_level();
/// Uses `level` from now on, in every thread (tests, and `lidarsurf bench --simd` to compare the
/// levels within one run). Throws InvalidArgument for a level outside [minimum_simd_level(),
/// supported_simd_level()]. Not meant to be changed while a reconstruction runs.
void set_simd_level(SimdLevel level);

const char* to_string(SimdLevel level);
/// "portable", "sse2", "avx2" or "avx512"; throws InvalidArgument for anything else.
SimdLevel simd_level_from_string(const char* name);

#if defined(__SSE2__)
/// The instruction sets of the Avx2 level, for `[[gnu::target(...)]]` (no FMA: see above).
#define LIDARSURF_AVX2_TARGET "avx2,bmi,bmi2,popcnt"
/// And of the Avx512 level.
#define LIDARSURF_AVX512_TARGET "avx512f,avx512bw,avx512vl," LIDARSURF_AVX2_TARGET
#endif

#if defined(__x86_64__) && defined(__GNUC__) && !defined(LIDARSURF_SCALAR)
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

}  // namespace lidarsurf
