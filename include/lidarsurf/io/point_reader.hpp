#pragma once
// Point cloud readers: KITTI .bin, PLY (ascii / binary little and big endian), PCD v0.7 (ascii,
// binary, binary_compressed) and XYZ/CSV text. Every reader bounds its allocations by the file's
// size and throws FormatError (malformed) or IoError (cannot open) with the file name.
#include <filesystem>
#include <string>
#include <string_view>

#include "lidarsurf/io/point_cloud.hpp"

namespace lidarsurf {

enum class PointFormat { Auto, KittiBin, Ply, Pcd, Text };

/// "auto", "bin", "ply", "pcd", "xyz" (also "csv", "txt"); throws InvalidArgument otherwise.
PointFormat parse_point_format(std::string_view name);

struct PointReadOptions {
    PointFormat format = PointFormat::Auto;  ///< Auto: chosen by the file extension.
    int bin_fields = 4;  ///< float32 values per point in .bin files (KITTI: 4, nuScenes: 5).
    /// Index of the float32 that holds the ring number in .bin records (nuScenes: 4), read into
    /// PointCloud::rings; -1: none. Ring values must be whole numbers in [0, 4095].
    int ring_field = -1;
    /// Index of the float32 that holds the intensity in .bin records (KITTI's reflectance and
    /// nuScenes' intensity: 3), read into PointCloud::intensities; -1, or a field the records do
    /// not have: none. A field that is 0 at every point counts as none (files written without
    /// intensity). PLY and PCD files give theirs by the field `intensity` (or `reflectivity`,
    /// `reflectance`, `remission`); -1 drops those too.
    int intensity_field = 3;
    /// The most bytes the file may hold (0 = no limit): a larger file, or a stream (a pipe, a
    /// device) that runs past it, throws ResourceLimit instead of being read on without end.
    std::size_t max_bytes = 0;
};

/// Reads the x, y, z of every point. Non-finite points are kept (see drop_non_finite).
PointCloud read_points(const std::filesystem::path& path, const PointReadOptions& options = {});

/// Parsers on an in-memory buffer (used by read_points and by the fuzzers). `name` is for messages.
PointCloud parse_kitti_bin(std::string_view data, int fields, const std::string& name, int ring_field = -1, int intensity_field = -1);
PointCloud parse_ply_points(std::string_view data, const std::string& name);
PointCloud parse_pcd_points(std::string_view data, const std::string& name);
PointCloud parse_text_points(std::string_view data, const std::string& name);

}  // namespace lidarsurf
