// The rays a scan's pattern fired that returned nothing, against the pattern walked cell by cell.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <tuple>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/map/empty_rays.hpp"

using namespace lidarsurf;

namespace {

Eigen::Vector3d direction(double el_deg, double az_deg) {
    const double e = el_deg * std::numbers::pi / 180, a = az_deg * std::numbers::pi / 180;
    return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

}  // namespace

TEST(EmptyRays, TheCellsNoReturnFellInAndNoOther) {
    const BeamPattern pattern{{2.0, -10.0, -4.0, -1.0}, 7.5};  // beams out of order; 48 steps
    std::vector<Eigen::Vector3d> points;
    std::set<std::pair<int, int>> returned;  // (beam elevation, step)
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 48; ++a) {
            if ((a * 7 + b * 3) % 5 == 0) continue;  // every fifth ray returns nothing
            // A return off the ray's centre by less than half a step and half the beam gap, at 2-60 m.
            const double el = pattern.elevations_deg[static_cast<std::size_t>(b)] + 0.9 * std::sin(a + b);
            const double az = a * 7.5 + 3.0 * std::cos(3 * a + b);
            points.push_back((2.0 + a) * direction(el, az));
            returned.insert({b, a});
        }
    points.push_back(Eigen::Vector3d::Constant(std::nan("")));  // skipped
    points.push_back(Eigen::Vector3d::Zero());
    const std::vector<Eigen::Vector3f> empty = empty_rays(pattern, points);
    std::size_t expected = 0;
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 48; ++a) {
            if (returned.count({b, a})) continue;
            ++expected;
            const Eigen::Vector3f u = direction(pattern.elevations_deg[static_cast<std::size_t>(b)], a * 7.5).cast<float>();
            const auto found = std::find_if(empty.begin(), empty.end(), [&](const Eigen::Vector3f& v) { return (v - u).norm() < 1e-6f; });
            EXPECT_NE(found, empty.end()) << "beam " << b << ", step " << a;
        }
    EXPECT_EQ(empty.size(), expected);
    for (const Eigen::Vector3f& v : empty) EXPECT_NEAR(v.norm(), 1.0f, 1e-6f);
    // Nothing returned: every ray of the pattern.
    EXPECT_EQ(empty_rays(pattern, {}).size(), 4u * 48u);
    EXPECT_THROW(empty_rays(BeamPattern{{}, 1.0}, points), InvalidArgument);
    EXPECT_THROW(empty_rays(BeamPattern{{0.0}, 0.0}, points), InvalidArgument);
    EXPECT_THROW(empty_rays(BeamPattern{{std::nan("")}, 1.0}, points), InvalidArgument);
}
