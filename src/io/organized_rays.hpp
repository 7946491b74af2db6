#pragma once
// Internal: the directions of the rays an organized cloud marks as returning nothing (NaN or zero
// points), from its grid: each row a beam (one elevation and one azimuth offset), each column one
// azimuth, both fitted on the rays that returned.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf::detail {

/// `points[i]` returned at grid cell `cells[i]` (row * width + column), `empty` are the cells that
/// did not. Returns the unit direction (sensor frame) of each empty cell whose row and column the
/// returns place, or nothing when the grid is not one of beams by azimuths (fewer than 95 % of the
/// far returns within 0.5 degree of their row's elevation and their column's azimuth plus their
/// row's offset: another organization).
std::vector<Eigen::Vector3f> organized_no_return_directions(std::uint32_t height, std::uint32_t width, const std::vector<Eigen::Vector3d>& points,
                                                            const std::vector<std::uint32_t>& cells, const std::vector<std::uint32_t>& empty);

}  // namespace lidarsurf::detail
