#pragma once
// What a simulated sensor needs from a world: the first hit along a ray, and what the surface
// there reflects.
#include <limits>
#include <optional>

#include <Eigen/Core>

namespace lidarsurf::sim {

struct RayReturn {
    double range = 0;  ///< distance along the unit direction
    /// The surface's reflectivity in [0, 1] (the share of the sensor's light it sends back, as a
    /// calibrated lidar reports it); NaN when the scene has none.
    float reflectivity = std::numeric_limits<float>::quiet_NaN();
};

class RayScene {
public:
    virtual ~RayScene() = default;
    /// The first surface hit from `origin` along the unit direction `dir` within (0, max_range]:
    /// its range and reflectivity, or nullopt. Safe to call from several threads at once.
    virtual std::optional<RayReturn> first_return(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                                  double max_range) const = 0;
    /// The range of first_return alone.
    std::optional<double> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range) const {
        const auto hit = first_return(origin, dir, max_range);
        if (!hit) return std::nullopt;
        return hit->range;
    }
};

}  // namespace lidarsurf::sim
