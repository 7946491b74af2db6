#pragma once
// Angles of directions, in degrees, for the range images of a scan (free_space, empty_rays).
#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace lidarsurf::detail {

// atan2 in degrees to within 0.001 degree (an 11th-order odd polynomial of atan on [0, 1]),
// several times faster than std::atan2: the range images' bins are 0.2 degree wide.
inline float atan2_deg(float y, float x) {
    const float ax = std::fabs(x), ay = std::fabs(y);
    const float mx = std::max(ax, ay), mn = std::min(ax, ay);
    if (mx == 0) return 0;
    const float a = mn / mx, a2 = a * a;
    float r = a * (0.99997726f + a2 * (-0.33262347f + a2 * (0.19354346f + a2 * (-0.11643287f + a2 * (0.05265332f - 0.01172120f * a2)))));
    if (ay > ax) r = 1.57079637f - r;
    if (x < 0) r = 3.14159274f - r;
    if (y < 0) r = -r;
    return r * 57.2957795f;
}
inline float azimuth_deg(const Eigen::Vector3d& d) { return atan2_deg(static_cast<float>(d.y()), static_cast<float>(d.x())); }
inline float elevation_deg(const Eigen::Vector3d& d) {
    return atan2_deg(static_cast<float>(d.z()), static_cast<float>(std::sqrt(d.x() * d.x() + d.y() * d.y())));
}

}  // namespace lidarsurf::detail
