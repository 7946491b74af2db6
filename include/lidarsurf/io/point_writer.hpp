#pragma once
// Writes point clouds: KITTI .bin (float32 x, y, z, intensity = 0) or PLY; atomic.
#include <filesystem>

#include "lidarsurf/io/point_cloud.hpp"

namespace lidarsurf {

void write_points(const PointCloud& cloud, const std::filesystem::path& path);

}  // namespace lidarsurf
