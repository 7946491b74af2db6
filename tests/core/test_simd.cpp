// The SIMD level switch (core/simd.hpp): the levels a build can run, and refusals. That the levels
// give the same sums is checked where the kernels are used (surface/test_neighbourhood_window.cpp).
#include <gtest/gtest.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/simd.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

TEST(Simd, LevelsRangeFromTheBuildsMinimumToTheCpusMaximum) {
    const std::vector<SimdLevel> levels = test::simd_levels();
    ASSERT_FALSE(levels.empty());
    EXPECT_EQ(levels.front(), minimum_simd_level());
    EXPECT_EQ(levels.back(), supported_simd_level());
    EXPECT_EQ(simd_level(), supported_simd_level());  // the default: the widest available
#if defined(LIDARSURF_SCALAR)
    EXPECT_EQ(supported_simd_level(), SimdLevel::Portable);
#elif defined(__SSE2__)
    EXPECT_EQ(minimum_simd_level(), SimdLevel::Sse2);
#endif
    for (SimdLevel level : levels) {
        const test::ScopedSimdLevel scoped(level);
        EXPECT_EQ(simd_level(), level);
    }
    EXPECT_EQ(simd_level(), supported_simd_level());  // restored
}

TEST(Simd, RefusesALevelTheBuildOrCpuLacks) {
    for (SimdLevel level : {SimdLevel::Portable, SimdLevel::Sse2, SimdLevel::Avx2, SimdLevel::Avx512}) {
        const bool available = static_cast<int>(level) >= static_cast<int>(minimum_simd_level()) &&
                               static_cast<int>(level) <= static_cast<int>(supported_simd_level());
        if (available) {
            EXPECT_NO_THROW(set_simd_level(level));
        } else {
            EXPECT_THROW(set_simd_level(level), InvalidArgument) << to_string(level);
        }
    }
    set_simd_level(supported_simd_level());
}

TEST(Simd, NamesRoundTrip) {
    for (SimdLevel level : {SimdLevel::Portable, SimdLevel::Sse2, SimdLevel::Avx2, SimdLevel::Avx512})
        EXPECT_EQ(simd_level_from_string(to_string(level)), level);
    EXPECT_THROW(simd_level_from_string("avx1024"), InvalidArgument);
    EXPECT_THROW(simd_level_from_string(""), InvalidArgument);
}
