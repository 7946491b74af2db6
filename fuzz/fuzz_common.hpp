#pragma once
// Shared by the libFuzzer harnesses. The contract under test: on any input a parser either
// returns or throws a lidarsurf::Error. Anything else (another exception, a crash, a leak, a
// sanitizer report, a hang, an allocation beyond -rss_limit_mb) is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <string>
#include <string_view>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::fuzz {

inline std::string_view as_view(const std::uint8_t* data, std::size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

/// Aborts (a finding) with a message when an invariant of a successful parse is broken.
inline void require(bool ok, const char* what) {
    if (!ok) {
        std::fprintf(stderr, "invariant broken: %s\n", what);
        std::abort();
    }
}

/// Runs `parse`, accepting only success or a lidarsurf::Error.
template <typename F>
void expect_typed(F&& parse) {
    try {
        parse();
    } catch (const Error&) {
        // A typed, documented refusal: fine.
    }
}

}  // namespace lidarsurf::fuzz
