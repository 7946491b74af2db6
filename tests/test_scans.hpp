#pragma once
// Scans shared by the end-to-end tests, simulated once per test binary.
#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"

namespace lidarsurf::test {

/// One HDL-64E revolution (2 cm noise, seed 1) of the analytic demo scene from the origin.
inline const PointCloud& demo_scan() {
    static const PointCloud cloud = sim::simulate_scan(sim::AnalyticScene::demo(), sim::SensorModel::hdl64(), Eigen::Vector3d::Zero(), 1);
    return cloud;
}

}  // namespace lidarsurf::test
