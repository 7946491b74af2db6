#pragma once
// A point cloud as read from a file: positions, and the ring of each point when asked for
// (other fields are ignored by the readers).
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

struct PointCloud {
    std::vector<Eigen::Vector3d> points;
    std::vector<std::uint16_t> rings = {};  ///< empty, or the laser ring of each point
};

/// Removes points with a NaN or infinite coordinate (and their rings); returns how many were removed.
std::size_t drop_non_finite(PointCloud& cloud);

}  // namespace lidarsurf
