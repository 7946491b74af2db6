#pragma once
// How far a live mesh (Reconstructor::update_mesh) is behind the exact mesh of the same moment:
// the share of the live mesh's area near the sensor that lies farther than a tolerance from the
// exact mesh (what a planner would see that is no longer there, or not there yet where it moved).
// Surface the live mesh lacks is not stale (it has not been meshed yet): the coverage counts it.
#include <cstddef>

#include <Eigen/Core>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

struct Staleness {
    double live_area = 0;   ///< m^2 of live triangles within the radius
    double stale_area = 0;  ///< m^2 of those farther than the tolerance from the exact mesh
    std::size_t triangles = 0;
    double exact_area = 0;    ///< m^2 of exact triangles within the radius
    double covered_area = 0;  ///< m^2 of those within the tolerance of the live mesh
    /// stale_area / live_area (0 when there is no live area).
    double share() const { return live_area > 0 ? stale_area / live_area : 0.0; }
    /// covered_area / exact_area: how much of the exact surface the live mesh has (1 when none).
    double covered_share() const { return exact_area > 0 ? covered_area / exact_area : 1.0; }
};

/// The live triangles whose centroid lies within `radius` of `centre` (world), each stale when
/// its centroid is farther than `tolerance` from the exact mesh (triangles are under a voxel
/// across: the centroid stands for the triangle), by area. An empty exact mesh makes every live
/// triangle stale. The other way, the exact triangles within the radius are covered when their
/// centroid lies within the tolerance of the live mesh.
Staleness measure_staleness(const Mesh& live, const Mesh& exact, const Eigen::Vector3d& centre, double radius, double tolerance);

}  // namespace lidarsurf
