#pragma once
// Writes point clouds, atomically, in the format the extension names (any case): KITTI .bin
// (float32 x, y, z, and the cloud's intensity or 0), binary PLY, binary PCD (float32 x, y, z), or text .xyz, .txt,
// .csv (x y z a line, full precision). Any other extension throws InvalidArgument.
#include <filesystem>

#include "lidarsurf/io/point_cloud.hpp"

namespace lidarsurf {

void write_points(const PointCloud& cloud, const std::filesystem::path& path);

/// Whether write_points writes this extension (".bin", ".ply", ".pcd", ".xyz", ".txt", ".csv").
bool is_point_extension(const std::filesystem::path& path);

}  // namespace lidarsurf
