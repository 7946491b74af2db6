#pragma once
// Spinning multi-beam lidar: one ray per (beam elevation, azimuth step), Gaussian range noise.
#include <cstdint>
#include <vector>

#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"

namespace lidarsurf::sim {

struct SensorModel {
    std::vector<double> elevations_deg;  ///< one per beam
    double azimuth_step_deg = 0.18;
    double min_range = 1.0;
    double max_range = 120.0;
    double range_noise = 0.02;  ///< sigma of the range noise, metres

    /// Velodyne HDL-64E as in KITTI: 64 beams evenly from +2 deg to -24.8 deg, 0.18 deg azimuth
    /// step (2,000 rays per beam per revolution), 120 m range, 2 cm range noise.
    static SensorModel hdl64();

    /// The paper's ground-truth sensor (Sec. IV-A): co-located with the HDL-64E, noise-free, 316
    /// beams over the same elevation span; 0.09 deg azimuth step.
    static SensorModel ground_truth();
};

/// Casts every ray of one revolution from `origin` and returns the noisy hits (world frame).
/// Deterministic for a given seed.
PointCloud simulate_scan(const AnalyticScene& scene, const SensorModel& sensor, const Eigen::Vector3d& origin,
                         std::uint64_t seed);

}  // namespace lidarsurf::sim
