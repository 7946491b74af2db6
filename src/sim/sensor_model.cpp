#include "lidarsurf/sim/sensor_model.hpp"

#include <cmath>
#include <numbers>
#include <random>

namespace lidarsurf::sim {

SensorModel SensorModel::hdl64() {
    SensorModel s;
    for (int i = 0; i < 64; ++i) s.elevations_deg.push_back(2.0 - 26.8 * i / 63.0);
    return s;
}

SensorModel SensorModel::ground_truth() {
    SensorModel s;
    for (int i = 0; i < 316; ++i) s.elevations_deg.push_back(2.0 - 26.8 * i / 315.0);
    s.azimuth_step_deg = 0.09;
    s.range_noise = 0.0;
    return s;
}

PointCloud simulate_scan(const AnalyticScene& scene, const SensorModel& sensor, const Eigen::Vector3d& origin,
                         std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, sensor.range_noise);
    PointCloud cloud;
    const int steps = static_cast<int>(std::lround(360.0 / sensor.azimuth_step_deg));
    const double deg = std::numbers::pi / 180.0;
    for (int a = 0; a < steps; ++a) {
        const double az = a * sensor.azimuth_step_deg * deg;
        for (double el_deg : sensor.elevations_deg) {
            const double el = el_deg * deg;
            const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
            const auto range = scene.intersect(origin, dir, sensor.max_range);
            const double n = sensor.range_noise > 0 ? noise(rng) : 0.0;  // drawn for every ray: stable stream
            if (!range || *range < sensor.min_range) continue;
            cloud.points.push_back(origin + (*range + n) * dir);
        }
    }
    return cloud;
}

}  // namespace lidarsurf::sim
