#pragma once
// Internal: splitmix64, the counter-based generator of the simulator. The same numbers on every
// platform and for any evaluation order (std:: distributions differ between standard libraries).
#include <cstdint>

namespace lidarsurf::sim::detail {

/// The splitmix64 output for counter x (Steele, Lea and Flood 2014).
inline std::uint64_t splitmix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

/// Uniform in [0, 1) from the top 53 bits.
inline double unit_interval(std::uint64_t x) { return static_cast<double>(x >> 11) * 0x1.0p-53; }

}  // namespace lidarsurf::sim::detail
