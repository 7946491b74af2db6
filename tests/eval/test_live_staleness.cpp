// The live mesh's staleness measure (eval/live_staleness.hpp) on flat meshes whose answer is known
// by hand: areas, the radius, the tolerance, an empty exact mesh.
#include <gtest/gtest.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/live_staleness.hpp"

using namespace lidarsurf;

namespace {

// The rectangle [x0, x1] x [0, 10] at height z, in 0.5 m squares of two triangles.
Mesh rectangle(double x0, double x1, double z) {
    Mesh m;
    const int nx = static_cast<int>((x1 - x0) / 0.5), ny = 20;
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) m.vertices.emplace_back(x0 + 0.5 * i, 0.5 * j, z);
    auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    return m;
}
Mesh join(const Mesh& a, const Mesh& b) {
    Mesh m = a;
    const auto base = static_cast<std::uint32_t>(a.vertices.size());
    m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
    for (const auto& t : b.triangles) m.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    return m;
}

}  // namespace

TEST(LiveStaleness, AreasByHand) {
    // Exact: [0, 20] x [0, 10] at z = 0. Live: its first half, and the second half 10 cm up.
    const Mesh exact = rectangle(0, 20, 0);
    const Mesh live = join(rectangle(0, 10, 0), rectangle(10, 20, 0.1));
    const Staleness all = measure_staleness(live, exact, {10, 5, 0}, 100, 0.05);
    EXPECT_NEAR(all.live_area, 200, 1e-9);
    EXPECT_NEAR(all.stale_area, 100, 1e-9);
    EXPECT_NEAR(all.share(), 0.5, 1e-12);
    EXPECT_NEAR(all.exact_area, 200, 1e-9);
    EXPECT_NEAR(all.covered_share(), 0.5, 1e-12);
    EXPECT_EQ(all.triangles, live.triangles.size());
    // 10 cm is within a 15 cm tolerance: nothing stale, everything covered.
    const Staleness loose = measure_staleness(live, exact, {10, 5, 0}, 100, 0.15);
    EXPECT_NEAR(loose.share(), 0, 1e-12);
    EXPECT_NEAR(loose.covered_share(), 1, 1e-12);
    // Within 4 m of (5, 5): the flat half only (centroids at most 4 m away).
    const Staleness near = measure_staleness(live, exact, {5, 5, 0}, 4, 0.05);
    EXPECT_GT(near.live_area, 40);
    EXPECT_EQ(near.stale_area, 0);
    EXPECT_NEAR(near.covered_share(), 1, 1e-12);
    // Half the live mesh missing: not stale, but half the exact area is not covered.
    const Staleness half = measure_staleness(rectangle(0, 10, 0), exact, {10, 5, 0}, 100, 0.05);
    EXPECT_EQ(half.stale_area, 0);
    EXPECT_NEAR(half.covered_share(), 0.5, 1e-12);
    // No exact mesh: all of the live mesh is stale.
    EXPECT_NEAR(measure_staleness(live, Mesh{}, {10, 5, 0}, 100, 0.05).share(), 1, 1e-12);
    EXPECT_THROW(measure_staleness(live, exact, {10, 5, 0}, 0, 0.05), InvalidArgument);
}
