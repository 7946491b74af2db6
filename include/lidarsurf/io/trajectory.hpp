#pragma once
// A timestamped trajectory of the sensor (sensor-to-world poses), interpolated at any time within
// its span: position linearly, rotation by slerp. Read from a TUM file (`t x y z qx qy qz qw`, t in
// seconds, as odometries such as KISS-ICP write), or from KITTI poses with their times.txt.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

namespace lidarsurf {

class Trajectory {
public:
    Trajectory() = default;
    /// Stamps in ns, strictly increasing; throws InvalidInput otherwise (or on a size mismatch).
    Trajectory(std::vector<std::int64_t> stamps_ns, std::vector<Eigen::Isometry3d> poses);
    bool empty() const { return stamps_.empty(); }
    std::size_t size() const { return stamps_.size(); }
    std::int64_t first_ns() const { return stamps_.front(); }
    std::int64_t last_ns() const { return stamps_.back(); }
    /// The pose at `t_ns`; nullopt outside [first_ns, last_ns] (never extrapolated). At a stamp
    /// of the trajectory, its pose as given, bit for bit.
    std::optional<Eigen::Isometry3d> at(std::int64_t t_ns) const;
    const std::vector<std::int64_t>& stamps_ns() const { return stamps_; }
    const std::vector<Eigen::Isometry3d>& poses() const { return poses_; }

private:
    std::vector<std::int64_t> stamps_;
    std::vector<Eigen::Isometry3d> poses_;
    std::vector<Eigen::Vector3d> positions_;
    std::vector<Eigen::Quaterniond> rotations_;
};

/// A TUM trajectory file: one pose a line, `#` comments. Throws IoError if unreadable and
/// FormatError naming the line for a line that is not 8 finite numbers, a quaternion far from
/// unit length, or a time not after the previous line's.
Trajectory read_tum_trajectory(const std::filesystem::path& path);
Trajectory parse_tum_trajectory(std::string_view data, const std::string& name);
/// The trajectory as a TUM file's text: seconds with 9 decimals (exact to the ns), positions and
/// quaternions to 1e-12.
std::string format_tum_trajectory(const Trajectory& trajectory);
/// KITTI poses (12 numbers a line) with their times.txt (seconds, one a line).
Trajectory read_kitti_trajectory(const std::filesystem::path& poses, const std::filesystem::path& times);
/// A trajectory file by its content: 8 numbers a line is TUM; 12 is KITTI, which needs `times`.
Trajectory read_trajectory(const std::filesystem::path& path, const std::filesystem::path& times = {});

}  // namespace lidarsurf
