#pragma once
// What a simulated sensor needs from a world: the first hit along a ray.
#include <optional>

#include <Eigen/Core>

namespace lidarsurf::sim {

class RayScene {
public:
    virtual ~RayScene() = default;
    /// Range along the unit direction `dir` to the first surface hit from `origin` within
    /// (0, max_range], or nullopt. Safe to call from several threads at once.
    virtual std::optional<double> intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                            double max_range) const = 0;
};

}  // namespace lidarsurf::sim
