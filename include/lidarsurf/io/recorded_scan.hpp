#pragma once
// One sweep of a lidar as a recording holds it: the returns in the sensor's frame, when each was
// measured, and the rays that returned nothing.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/io/point_cloud.hpp"

namespace lidarsurf {

struct RecordedScan {
    std::size_t index = 0;        ///< the scan's number in the recording, from 0
    std::int64_t stamp_ns = 0;    ///< the sweep's reference time (ns): its first measurement
    std::string frame_id;         ///< the frame the points are in (ROS frame_id, or "os_sensor")
    PointCloud cloud;             ///< returns in the sensor frame; rings when the sensor numbers them
    /// Per point: seconds after stamp_ns at which it was measured; empty when the recording
    /// does not say.
    std::vector<float> times;
    /// Unit directions (sensor frame) of the rays that returned nothing: an Ouster pixel of
    /// range 0, a Velodyne channel of range 0, an organized PointCloud2's NaN or zero point (its
    /// direction from the cloud's rows and columns). Empty when the recording does not say which
    /// rays those were.
    std::vector<Eigen::Vector3f> no_return;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< where the rays start, sensor frame
    /// Fraction of the sweep's columns the recording holds (1: a whole revolution); a recording
    /// that starts or ends mid-sweep has a partial first or last scan.
    double completeness = 1.0;
};

}  // namespace lidarsurf
