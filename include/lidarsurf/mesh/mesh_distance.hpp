#pragma once
// Exact distance from points to the surface of a triangle mesh: closest point on a triangle
// (Ericson, Real-Time Collision Detection, 5.1.5) behind a bounding-volume hierarchy.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

/// Closest point to p on triangle (a, b, c); handles degenerate triangles.
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c);

struct SurfacePoint {
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< closest point on the surface
    double distance = 0;
    std::uint32_t triangle = 0;
};

class MeshDistance {
public:
    /// Builds the hierarchy over the triangles of `mesh` (copied). Throws InvalidInput if the
    /// mesh has no triangle.
    explicit MeshDistance(const Mesh& mesh);

    /// Closest surface point to p.
    SurfacePoint closest(const Eigen::Vector3d& p) const;
    double distance(const Eigen::Vector3d& p) const { return closest(p).distance; }

private:
    struct Node {
        Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
        std::uint32_t first = 0, count = 0;  ///< leaf: triangles [first, first+count); inner: count == 0
        std::uint32_t left = 0, right = 0;
    };
    std::uint32_t build(std::uint32_t first, std::uint32_t count);

    std::vector<Eigen::Vector3d> a_, b_, c_;  ///< triangle corners in BVH order
    std::vector<std::uint32_t> original_;     ///< BVH order -> mesh triangle index
    std::vector<Node> nodes_;
};

}  // namespace lidarsurf
