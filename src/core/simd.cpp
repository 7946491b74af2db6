#include "lidarsurf/core/simd.hpp"

#include <atomic>
#include <cstring>
#include <string>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

namespace {

SimdLevel detect() {
#if defined(LIDARSURF_SCALAR) || !defined(__SSE2__)
    return SimdLevel::Portable;
#elif defined(__GNUC__)
    // The compiler's CPU check also asks the OS whether it saves the AVX registers.
    const bool v3 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2") &&
                    __builtin_cpu_supports("popcnt");
    if (!v3) return SimdLevel::Sse2;
    const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
    return avx512 ? SimdLevel::Avx512 : SimdLevel::Avx2;
#else
    return SimdLevel::Sse2;
#endif
}

std::atomic<SimdLevel>& current() {
    static std::atomic<SimdLevel> level{supported_simd_level()};
    return level;
}

}  // namespace

SimdLevel supported_simd_level() {
    static const SimdLevel level = detect();
    return level;
}

SimdLevel minimum_simd_level() {
#if defined(LIDARSURF_SCALAR) || !defined(__SSE2__)
    return SimdLevel::Portable;
#else
    return SimdLevel::Sse2;
#endif
}

std::vector<SimdLevel> available_simd_levels() {
    std::vector<SimdLevel> out;
    for (int l = static_cast<int>(minimum_simd_level()); l <= static_cast<int>(supported_simd_level()); ++l)
        out.push_back(static_cast<SimdLevel>(l));
    return out;
}

SimdLevel simd_level() { return current().load(std::memory_order_relaxed); }

void set_simd_level(SimdLevel level) {
    if (static_cast<int>(level) < static_cast<int>(minimum_simd_level()) || static_cast<int>(level) > static_cast<int>(supported_simd_level()))
        throw InvalidArgument(std::string("SIMD level ") + to_string(level) + " is not available here (this build and CPU have " +
                              to_string(minimum_simd_level()) + " to " + to_string(supported_simd_level()) + ")");
    current().store(level, std::memory_order_relaxed);
}

const char* to_string(SimdLevel level) {
    switch (level) {
        case SimdLevel::Portable: return "portable";
        case SimdLevel::Sse2: return "sse2";
        case SimdLevel::Avx2: return "avx2";
        case SimdLevel::Avx512: return "avx512";
    }
    return "?";
}

SimdLevel simd_level_from_string(const char* name) {
    for (SimdLevel level : {SimdLevel::Portable, SimdLevel::Sse2, SimdLevel::Avx2, SimdLevel::Avx512})
        if (std::strcmp(name, to_string(level)) == 0) return level;
    throw InvalidArgument(std::string("unknown SIMD level '") + name + "' (portable, sse2, avx2, avx512)");
}

}  // namespace lidarsurf
