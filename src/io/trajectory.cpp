// Timestamped trajectories (see trajectory.hpp).
#include "lidarsurf/io/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "byte_reader.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"

namespace lidarsurf {
namespace {

std::int64_t to_ns(double seconds, const std::string& where) {
    if (!(std::abs(seconds) < 9e9)) throw FormatError(where + ": a time of " + std::to_string(seconds) + " s");
    return static_cast<std::int64_t>(std::llround(seconds * 1e9));
}

// The numbers of each non-blank, non-comment line.
std::vector<std::vector<double>> number_lines(std::string_view data, const std::string& name, std::vector<std::size_t>& line_numbers) {
    std::vector<std::vector<double>> out;
    std::size_t line_no = 0;
    while (!data.empty()) {
        std::string_view line = detail::next_line(data);
        ++line_no;
        if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
        detail::Tokens tk(line);
        std::string_view tok;
        std::vector<double> v;
        while (tk.next(tok)) {
            double x = 0;
            if (v.size() == 16 || !detail::parse_double(tok, x) || !std::isfinite(x))
                throw FormatError(name + ": line " + std::to_string(line_no) + ": expected finite numbers");
            v.push_back(x);
        }
        if (v.empty()) continue;
        out.push_back(std::move(v));
        line_numbers.push_back(line_no);
    }
    return out;
}

}  // namespace

Trajectory::Trajectory(std::vector<std::int64_t> stamps_ns, std::vector<Eigen::Isometry3d> poses) : stamps_(std::move(stamps_ns)) {
    if (stamps_.size() != poses.size())
        throw InvalidInput("a trajectory of " + std::to_string(stamps_.size()) + " times and " + std::to_string(poses.size()) + " poses");
    for (std::size_t i = 1; i < stamps_.size(); ++i)
        if (stamps_[i] <= stamps_[i - 1]) throw InvalidInput("a trajectory whose time " + std::to_string(i) + " is not after the one before");
    for (const auto& p : poses) {
        positions_.push_back(p.translation());
        rotations_.emplace_back(p.linear());
        rotations_.back().normalize();
    }
    poses_ = std::move(poses);
}

std::optional<Eigen::Isometry3d> Trajectory::at(std::int64_t t) const {
    if (stamps_.empty() || t < stamps_.front() || t > stamps_.back()) return std::nullopt;
    const auto it = std::lower_bound(stamps_.begin(), stamps_.end(), t);
    const std::size_t j = static_cast<std::size_t>(it - stamps_.begin());
    if (*it == t) return poses_[j];
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    const std::size_t i = j - 1;
    const double s = static_cast<double>(t - stamps_[i]) / static_cast<double>(stamps_[j] - stamps_[i]);
    pose.linear() = rotations_[i].slerp(s, rotations_[j]).toRotationMatrix();
    pose.translation() = (1 - s) * positions_[i] + s * positions_[j];
    return pose;
}

Trajectory parse_tum_trajectory(std::string_view data, const std::string& name) {
    std::vector<std::size_t> line_no;
    const auto lines = number_lines(data, name, line_no);
    std::vector<std::int64_t> stamps;
    std::vector<Eigen::Isometry3d> poses;
    for (std::size_t k = 0; k < lines.size(); ++k) {
        const auto& v = lines[k];
        const std::string where = name + ": line " + std::to_string(line_no[k]);
        if (v.size() != 8) throw FormatError(where + ": expected 8 numbers (t x y z qx qy qz qw), got " + std::to_string(v.size()));
        const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
        if (std::abs(q.norm() - 1) > 1e-3) throw FormatError(where + ": the quaternion's length is " + std::to_string(q.norm()) + ", not 1");
        const std::int64_t t = to_ns(v[0], where);
        if (!stamps.empty() && t <= stamps.back()) throw FormatError(where + ": its time is not after the line before's");
        Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
        p.linear() = q.normalized().toRotationMatrix();
        p.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
        stamps.push_back(t);
        poses.push_back(p);
    }
    if (stamps.empty()) throw FormatError(name + ": no pose in the trajectory");
    return Trajectory(std::move(stamps), std::move(poses));
}

std::string format_tum_trajectory(const Trajectory& trajectory) {
    std::string out = "# t x y z qx qy qz qw\n";
    char line[256];
    for (std::size_t i = 0; i < trajectory.size(); ++i) {
        const std::int64_t t = trajectory.stamps_ns()[i];
        const auto& p = trajectory.poses()[i];
        const Eigen::Quaterniond q(p.linear());
        const auto a = static_cast<unsigned long long>(t < 0 ? -t : t);
        std::snprintf(line, sizeof line, "%s%llu.%09llu %.12f %.12f %.12f %.12f %.12f %.12f %.12f\n", t < 0 ? "-" : "", a / 1000000000ull,
                      a % 1000000000ull, p.translation().x(), p.translation().y(), p.translation().z(), q.x(), q.y(),
                      q.z(), q.w());
        out += line;
    }
    return out;
}

Trajectory read_tum_trajectory(const std::filesystem::path& path) { return parse_tum_trajectory(detail::read_file(path.string()), path.string()); }

Trajectory read_kitti_trajectory(const std::filesystem::path& poses_path, const std::filesystem::path& times_path) {
    std::vector<Eigen::Isometry3d> poses = read_poses(poses_path);
    std::vector<std::size_t> line_no;
    const auto lines = number_lines(detail::read_file(times_path.string()), times_path.string(), line_no);
    std::vector<std::int64_t> stamps;
    for (std::size_t k = 0; k < lines.size(); ++k) {
        const std::string where = times_path.string() + ": line " + std::to_string(line_no[k]);
        if (lines[k].size() != 1) throw FormatError(where + ": expected one time (seconds)");
        const std::int64_t t = to_ns(lines[k][0], where);
        if (!stamps.empty() && t <= stamps.back()) throw FormatError(where + ": its time is not after the line before's");
        stamps.push_back(t);
    }
    if (stamps.size() != poses.size())
        throw FormatError(times_path.string() + ": " + std::to_string(stamps.size()) + " times for the " + std::to_string(poses.size()) + " poses of " +
                          poses_path.string());
    if (stamps.empty()) throw FormatError(poses_path.string() + ": no pose in the trajectory");
    return Trajectory(std::move(stamps), std::move(poses));
}

Trajectory read_trajectory(const std::filesystem::path& path, const std::filesystem::path& times) {
    const std::string data = detail::read_file(path.string());
    std::vector<std::size_t> line_no;
    std::string_view first = data;
    std::size_t numbers = 0;
    while (!first.empty() && numbers == 0) {
        std::string_view line = detail::next_line(first);
        if (const auto hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
        detail::Tokens tk(line);
        std::string_view tok;
        while (tk.next(tok)) ++numbers;
    }
    if (numbers == 12) {
        if (times.empty())
            throw InvalidArgument(path.string() + ": KITTI poses have no times: give their times.txt with --times (or a TUM trajectory)");
        return read_kitti_trajectory(path, times);
    }
    return parse_tum_trajectory(data, path.string());
}

}  // namespace lidarsurf
