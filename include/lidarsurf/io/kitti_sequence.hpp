#pragma once
// The KITTI odometry layout of a sequence directory, as `lidarsurf simulate` writes it and
// `lidarsurf benchmark` reads it:
//   velodyne/000000.bin ...   scans in the sensor frame (float32 x, y, z, intensity)
//   gt/000000.bin ...         the co-located ground-truth scans, same frame
//   poses.txt                 one sensor-to-world pose per frame: 3x4 row-major, 12 numbers a line
//   scene.ply                 the static scene mesh (world frame), when known
//   objects/000000.ply ...    the moving objects at each frame's time (world frame), when any
//   sensor.json               the sensor that made the scans
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

namespace lidarsurf {

struct KittiSequence {
    std::filesystem::path dir;

    static std::string frame_name(std::size_t index);  ///< "000042"
    std::filesystem::path scan(std::size_t index) const { return dir / "velodyne" / (frame_name(index) + ".bin"); }
    std::filesystem::path ground_truth(std::size_t index) const { return dir / "gt" / (frame_name(index) + ".bin"); }
    std::filesystem::path objects(std::size_t index) const { return dir / "objects" / (frame_name(index) + ".ply"); }
    std::filesystem::path poses() const { return dir / "poses.txt"; }
    std::filesystem::path scene() const { return dir / "scene.ply"; }
    std::filesystem::path sensor() const { return dir / "sensor.json"; }

    /// Number of consecutive scans velodyne/000000.bin, 000001.bin, ... Throws IoError if `dir`
    /// or dir/velodyne does not exist.
    std::size_t frame_count() const;
};

/// Reads a KITTI poses file. Throws IoError if unreadable and FormatError (with the line number)
/// for a line that is not 12 finite numbers or whose rotation is not orthonormal (1e-3).
std::vector<Eigen::Isometry3d> read_poses(const std::filesystem::path& path);
/// The same on an in-memory buffer (used by read_poses and by the fuzzers). `name` is for messages.
std::vector<Eigen::Isometry3d> parse_poses(std::string_view data, const std::string& name);

/// Writes a KITTI poses file atomically (full double precision).
void write_poses(const std::vector<Eigen::Isometry3d>& poses, const std::filesystem::path& path);

}  // namespace lidarsurf
