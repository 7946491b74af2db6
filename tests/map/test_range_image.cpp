// The range image carving tests voxels against (map/range_image.hpp), against a brute-force
// oracle: points placed at the centres of known pixels (azimuth and elevation from std::atan2's
// definition of the grid), the nearest return of each pixel found by scanning every point.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include "lidarsurf/map/range_image.hpp"

using namespace lidarsurf;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The unit direction at the centre of pixel (row, col) of an image whose first row starts at
// elevation `el_min` (degrees); row -0.5: on that first row's lower edge.
Eigen::Vector3d centre(double row, int col, double el_min) {
    const double el = (el_min + (row + 0.5) * RangeImage::kElevationStep) * kDeg;
    const double az = (-180.0 + (col + 0.5) * RangeImage::kAzimuthStep) * kDeg;
    return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

}  // namespace

TEST(RangeImage, EachPixelHoldsItsNearestReturnInTheGridsFrame) {
    const Eigen::Vector3d viewpoint(10, -5, 2), origin(3, 4, 5);
    const double el_min = -20.0;
    std::mt19937 rng(7);
    std::uniform_int_distribution<int> row_of(1, 30), col_of(0, RangeImage::kColumns - 1);
    std::uniform_real_distribution<double> range_of(2, 60);
    // The lowest return sets the first row's start: exactly at el_min, in column 0.
    const double low = el_min * kDeg;
    std::vector<Eigen::Vector3d> points = {viewpoint + 5.0 * Eigen::Vector3d(std::cos(low) * -1.0, 0.0, std::sin(low))};
    std::map<std::uint32_t, std::pair<double, std::uint32_t>> nearest;  // the oracle: pixel -> (range, point)
    double farthest = 5;
    for (int i = 0; i < 3000; ++i) {
        const int row = row_of(rng), col = col_of(rng);
        const double r = range_of(rng);
        farthest = std::max(farthest, r);
        points.push_back(viewpoint + r * centre(row, col, el_min));
        const std::uint32_t q = static_cast<std::uint32_t>(row * RangeImage::kColumns + col);
        const auto it = nearest.find(q);
        if (it == nearest.end() || r < it->second.first) nearest[q] = {r, static_cast<std::uint32_t>(points.size() - 1)};
    }
    points.push_back(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));  // no return: in no pixel
    RangeImage image;
    image.build(origin, points, viewpoint, {}, 0);
    ASSERT_FALSE(image.empty());
    EXPECT_EQ(image.origin(), origin);
    EXPECT_TRUE(image.sensor().isApprox(viewpoint - origin));
    std::size_t held = 0;
    for (std::size_t q = 0; q < image.pixels(); ++q) {
        if (image.nearest(q) == RangeImage::kNoPixel) continue;
        ++held;
        const std::uint32_t target = image.nearest(q);
        EXPECT_FALSE(image.no_surface(target));
        EXPECT_TRUE(image.return_point(target).isApprox(points[target] - origin));
        if (target == 0) continue;  // the lowest return, placed on the first row's edge
        const auto it = nearest.find(static_cast<std::uint32_t>(q));
        ASSERT_NE(it, nearest.end()) << "pixel " << q << " holds a return none was placed in";
        EXPECT_EQ(target, it->second.second) << "pixel " << q << ": not its nearest return";
        EXPECT_NEAR(std::sqrt(image.depth2(q)), it->second.first, 1e-4);
    }
    EXPECT_EQ(held, nearest.size() + 1) << "every pixel with a return, and only those";
    EXPECT_NEAR(image.farthest(), farthest, 1e-3);
}

TEST(RangeImage, ARunOfRaysThatReturnedNothingSeesToTheEmptyRangeAndOneLostRayDoesNot) {
    const Eigen::Vector3d viewpoint(0, 0, 1.8), origin = Eigen::Vector3d::Zero();
    const double el_min = -10.0;
    std::vector<Eigen::Vector3d> points;
    // Returns at 20 m on the first row's lower edge, every column: the image's rows start there.
    for (int col = 0; col < RangeImage::kColumns; ++col) points.push_back(viewpoint + 20.0 * centre(-0.5, col, el_min));
    // Row 20: returns everywhere but a run of 9 columns, whose rays returned nothing, and one
    // column lost at random between returns.
    std::vector<Eigen::Vector3f> no_return;
    const int run = 600, lost = 1200;
    for (int col = 0; col < RangeImage::kColumns; ++col) {
        const Eigen::Vector3d u = centre(20, col, el_min);
        if ((col >= run && col < run + 9) || col == lost) no_return.push_back(u.cast<float>());
        else if (std::abs(col - run - 4) > 12) points.push_back(viewpoint + 15.0 * u);  // nothing near the run
    }
    RangeImage image;
    image.build(origin, points, viewpoint, no_return, 30.0);
    ASSERT_FALSE(image.empty());
    const auto pixel = [](int row, int col) { return static_cast<std::size_t>(row * RangeImage::kColumns + col); };
    // The run's ends have a column without a ray beside them: only its 7 inner pixels count.
    EXPECT_EQ(image.empty_pixels(), 7u);
    for (int col = run; col < run + 9; ++col) {
        const std::uint32_t target = image.nearest(pixel(20, col));
        if (col == run || col == run + 8) {
            EXPECT_EQ(target, RangeImage::kNoPixel) << "column " << col;
            continue;
        }
        ASSERT_NE(target, RangeImage::kNoPixel) << "column " << col;
        EXPECT_TRUE(image.no_surface(target));
        const Eigen::Vector3d p = image.return_point(target);
        EXPECT_NEAR((p - image.sensor()).norm(), 30.0, 1e-3) << "free space up to the empty range";
        EXPECT_NEAR((p - image.sensor()).normalized().dot(centre(20, col, el_min)), 1.0, 1e-6) << "along its ray";
    }
    EXPECT_EQ(image.nearest(pixel(20, lost)), RangeImage::kNoPixel) << "one ray lost between returns is not free space";
}
