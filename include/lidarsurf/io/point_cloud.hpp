#pragma once
// A point cloud as read from a file: positions only (extra fields are ignored by the readers).
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

struct PointCloud {
    std::vector<Eigen::Vector3d> points;
};

/// Removes points with a NaN or infinite coordinate; returns how many were removed.
std::size_t drop_non_finite(PointCloud& cloud);

}  // namespace lidarsurf
