#pragma once
// Seconds since a steady-clock time point: the stage times of the summaries.
#include <chrono>

namespace lidarsurf {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace lidarsurf
