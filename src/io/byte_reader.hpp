#pragma once
// Internal: bounds-checked reading of binary scalars and text tokens from a buffer.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::detail {

enum class ScalarType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

inline std::size_t scalar_size(ScalarType t) {
    switch (t) {
        case ScalarType::Int8: case ScalarType::UInt8: return 1;
        case ScalarType::Int16: case ScalarType::UInt16: return 2;
        case ScalarType::Int32: case ScalarType::UInt32: case ScalarType::Float32: return 4;
        default: return 8;
    }
}

template <typename T>
T load(const char* p, bool big_endian) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, p, sizeof(T));
    if (big_endian)
        for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
}

/// Reads one scalar of type t at p (little endian unless big_endian) as a double.
inline double load_scalar(const char* p, ScalarType t, bool big_endian) {
    switch (t) {
        case ScalarType::Int8: return load<std::int8_t>(p, false);
        case ScalarType::UInt8: return load<std::uint8_t>(p, false);
        case ScalarType::Int16: return load<std::int16_t>(p, big_endian);
        case ScalarType::UInt16: return load<std::uint16_t>(p, big_endian);
        case ScalarType::Int32: return load<std::int32_t>(p, big_endian);
        case ScalarType::UInt32: return load<std::uint32_t>(p, big_endian);
        case ScalarType::Int64: return static_cast<double>(load<std::int64_t>(p, big_endian));
        case ScalarType::UInt64: return static_cast<double>(load<std::uint64_t>(p, big_endian));
        case ScalarType::Float32: return load<float>(p, big_endian);
        case ScalarType::Float64: return load<double>(p, big_endian);
    }
    return 0;
}

/// A value read as a double, stored as a float attribute (intensity, confidence): NaN where it
/// does not fit a float (converting it would be undefined) or is not a number.
inline float to_float_or_nan(double v) {
    return std::fabs(v) <= std::numeric_limits<float>::max() ? static_cast<float>(v) : std::numeric_limits<float>::quiet_NaN();
}

/// Parses a whole token as a double (accepts nan/inf); false if it is not a number.
inline bool parse_double(std::string_view token, double& out) {
    if (token.empty()) return false;
    if (token.front() == '+') token.remove_prefix(1);
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
    return ec == std::errc() && ptr == token.data() + token.size();
}

/// Splits the next line off `data` (without the '\n' and a trailing '\r').
inline std::string_view next_line(std::string_view& data) {
    const std::size_t nl = data.find('\n');
    std::string_view line = data.substr(0, nl);
    data.remove_prefix(nl == std::string_view::npos ? data.size() : nl + 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
}

/// Cursor over whitespace-separated tokens.
class Tokens {
public:
    explicit Tokens(std::string_view s) : s_(s) {}
    bool next(std::string_view& tok) {
        std::size_t i = 0;
        while (i < s_.size() && is_space(s_[i])) ++i;
        if (i == s_.size()) { s_ = {}; return false; }
        std::size_t j = i;
        while (j < s_.size() && !is_space(s_[j])) ++j;
        tok = s_.substr(i, j - i);
        s_.remove_prefix(j);
        return true;
    }
    std::string_view rest() const { return s_; }

private:
    static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }
    std::string_view s_;
};

/// ASCII lower case (format names, file extensions).
inline std::string lower(std::string_view s) {
    std::string r(s);
    for (char& c : r)
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return r;
}

/// Reads a whole file into memory. Throws IoError when it cannot, and ResourceLimit when it holds
/// more than `max_bytes` (0 = no limit; a stream is read in chunks and stopped there).
std::string read_file(const std::string& path, std::size_t max_bytes = 0);

}  // namespace lidarsurf::detail
