#pragma once
// A small world of analytic primitives (finite ground rectangle, axis-aligned boxes, vertical
// cylinders) with exact ray casting and exact point-to-surface distance: the ground truth for
// end-to-end tests and the built-in demo scan.
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/sim/ray_scene.hpp"

namespace lidarsurf::sim {

struct GroundRect {  ///< horizontal rectangle z = height, |x - cx| <= hx, |y - cy| <= hy
    double height = 0, cx = 0, cy = 0, hx = 1, hy = 1;
};
struct Box {  ///< axis-aligned solid box
    Eigen::Vector3d lo, hi;
};
struct Cylinder {  ///< vertical solid cylinder with caps
    double cx = 0, cy = 0, radius = 1, z0 = 0, z1 = 1;
};

class AnalyticScene final : public RayScene {
public:
    std::vector<GroundRect> grounds;
    std::vector<Box> boxes;
    std::vector<Cylinder> cylinders;

    /// The first primitive hit along the unit direction `dir` from `origin` within (0, max_range];
    /// the analytic world has no reflectivity (NaN).
    std::optional<RayReturn> first_return(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                          double max_range) const override;

    /// Unsigned distance from p to the nearest primitive surface.
    double distance(const Eigen::Vector3d& p) const;

    /// The demo world: a 60 m x 60 m ground 1.73 m below the sensor, a car-sized box, a wall,
    /// a pole and a tree-trunk-sized cylinder.
    static AnalyticScene demo();
};

}  // namespace lidarsurf::sim
