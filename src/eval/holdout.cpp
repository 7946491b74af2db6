#include "lidarsurf/eval/holdout.hpp"

#include <cmath>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"

namespace lidarsurf {
namespace {
// Uniform integer in [0, n) without modulo bias (rejection), independent of the standard library.
std::uint64_t bounded(std::mt19937_64& rng, std::uint64_t n) {
    const std::uint64_t limit = ~std::uint64_t{0} - (~std::uint64_t{0} % n);
    std::uint64_t x;
    do x = rng();
    while (x >= limit);
    return x % n;
}
}  // namespace

HoldoutSplit split_holdout(const PointCloud& cloud, double fraction, std::uint64_t seed) {
    if (!std::isfinite(fraction) || fraction <= 0 || fraction >= 1)
        throw InvalidArgument("hold-out fraction must be in (0, 1) (got " + format_value(fraction) + ")");
    const std::size_t n = cloud.points.size();
    const auto held = static_cast<std::size_t>(std::llround(fraction * static_cast<double>(n)));
    if (held == 0 || held == n)
        throw InvalidInput("hold-out of " + format_value(fraction) + " of " + format_value(n) + " points leaves one part empty");
    // Partial Fisher-Yates: the first `held` entries of the permutation are held out.
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::mt19937_64 rng(seed);
    for (std::size_t i = 0; i < held; ++i) std::swap(order[i], order[i + bounded(rng, n - i)]);
    std::vector<char> is_held(n, 0);
    for (std::size_t i = 0; i < held; ++i) is_held[order[i]] = 1;
    HoldoutSplit split;
    split.kept.points.reserve(n - held);
    split.held_out.points.reserve(held);
    for (std::size_t i = 0; i < n; ++i) (is_held[i] ? split.held_out : split.kept).points.push_back(cloud.points[i]);
    return split;
}

}  // namespace lidarsurf
