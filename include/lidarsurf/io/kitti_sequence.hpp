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

#include "lidarsurf/io/point_reader.hpp"

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
    /// or dir/velodyne does not exist, and InvalidInput when a scan is numbered past a gap (it
    /// would be left out silently).
    std::size_t frame_count() const;
};

/// The frames a run takes of a sequence of `available` scans named `name`: from `first`, every
/// `step`-th, at most `frames` of them (0: to the last). Throws InvalidArgument for a negative
/// first or frames, a step below 1, or a first frame past the last.
std::vector<std::size_t> select_frames(std::size_t available, int first, int frames, int step, const std::string& name);

/// Scan `frame` of `seq` moved into the world by its sensor-to-world `pose` (a non-finite point
/// stays non-finite). Throws as read_points.
PointCloud read_world_scan(const KittiSequence& seq, std::size_t frame, const Eigen::Isometry3d& pose,
                           const PointReadOptions& options = {});

/// Where a sequence's poses are, in the layouts users have:
///  - `poses_flag` when given (sensor-to-world lidar poses, e.g. from an odometry such as kiss-icp;
///    camera poses when `calib_flag` is given too);
///  - else DIR/poses.txt (lidar poses, as `lidarsurf simulate` writes);
///  - else the KITTI odometry layout: DIR = dataset/sequences/NN, poses in dataset/poses/NN.txt
///    (the left camera's), converted with `calib_flag` or DIR/calib.txt.
/// Throws IoError naming the places looked at when none holds poses, and when KITTI's camera
/// poses have no calibration to convert them.
struct SequencePoses {
    std::filesystem::path poses;
    std::filesystem::path calib;  ///< empty: the poses are the lidar's
    std::string layout;           ///< "poses.txt", "KITTI odometry" or "--poses", for reports
};
SequencePoses find_sequence_poses(const std::filesystem::path& dir, const std::filesystem::path& poses_flag,
                                  const std::filesystem::path& calib_flag);
/// The lidar poses of find_sequence_poses(...): read, and converted with the calibration if any.
std::vector<Eigen::Isometry3d> read_sequence_poses(const SequencePoses& where);

/// Reads a KITTI poses file. Throws IoError if unreadable and FormatError (with the line number)
/// for a line that is not 12 finite numbers or whose rotation is not orthonormal (1e-3) or is a
/// reflection (determinant -1).
std::vector<Eigen::Isometry3d> read_poses(const std::filesystem::path& path);
/// The same on an in-memory buffer (used by read_poses and by the fuzzers). `name` is for messages.
std::vector<Eigen::Isometry3d> parse_poses(std::string_view data, const std::string& name);

/// The velodyne-to-camera transform `Tr` of a KITTI odometry calib.txt (its "Tr:" line, 12
/// numbers). Throws IoError if unreadable and FormatError if the line is absent or malformed.
Eigen::Isometry3d read_calib_tr(const std::filesystem::path& path);
/// The same on an in-memory buffer. `name` is for messages.
Eigen::Isometry3d parse_calib_tr(std::string_view data, const std::string& name);

/// KITTI's published odometry poses are the left camera's (camera frame i to camera frame 0);
/// with the calibration's Tr (velodyne to camera) the lidar's poses in the velodyne frame of
/// frame 0 are Tr^-1 * P_i * Tr: a scan's points p go to the world as Tr^-1 P_i Tr p.
std::vector<Eigen::Isometry3d> lidar_poses(const std::vector<Eigen::Isometry3d>& camera_poses, const Eigen::Isometry3d& tr);

/// Writes a KITTI poses file atomically (full double precision).
void write_poses(const std::vector<Eigen::Isometry3d>& poses, const std::filesystem::path& path);

}  // namespace lidarsurf
