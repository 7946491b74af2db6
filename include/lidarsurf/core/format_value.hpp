#pragma once
// Numbers in messages: integers as they are, floating-point values with six significant digits
// ("1e-09", "0.2"), never "0.000000" for a small value as std::to_string would print.
#include <concepts>
#include <cstdio>
#include <string>

namespace lidarsurf {

template <std::integral T>
std::string format_value(T value) {
    return std::to_string(value);
}

inline std::string format_value(double value) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", value);
    return buf;
}

inline std::string format_value(float value) { return format_value(static_cast<double>(value)); }

}  // namespace lidarsurf
