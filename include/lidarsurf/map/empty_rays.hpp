#pragma once
// The rays of a scan that returned nothing, from the sensor's firing pattern: a spinning lidar fires
// each beam at its elevation once per azimuth step; the cells of that pattern no return fell in are
// the rays that saw nothing (the sky, beyond the range, a surface too dark to return). Free-space
// carving takes them as free space (map/free_space.hpp).
#include <span>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

struct BeamPattern {
    std::vector<double> elevations_deg;  ///< one per beam, any order
    double azimuth_step_deg = 0.18;      ///< the first step at azimuth 0 (x), counter-clockwise

    /// Throws InvalidArgument for no beam, a non-finite elevation or a step outside (0, 360].
    void validate() const;
};

/// The unit directions (sensor frame) of the cells of `pattern` that none of `points` (sensor
/// frame, returns from the origin; non-finite ones skipped) falls in: each point counts for the beam
/// of the nearest elevation and the nearest azimuth step.
std::vector<Eigen::Vector3f> empty_rays(const BeamPattern& pattern, std::span<const Eigen::Vector3d> points);
/// The same, each direction turned by `turn` (a scan's pose: the directions in the world frame).
std::vector<Eigen::Vector3f> empty_rays(const BeamPattern& pattern, std::span<const Eigen::Vector3d> points, const Eigen::Matrix3d& turn);

}  // namespace lidarsurf
