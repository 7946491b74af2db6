#include "lidarsurf/io/kitti_sequence.hpp"

#include <cstdio>
#include <system_error>

#include "byte_reader.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/point_reader.hpp"

namespace lidarsurf {

std::string KittiSequence::frame_name(std::size_t index) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%06zu", index);
    return buf;
}

std::size_t KittiSequence::frame_count() const {
    std::error_code ec;
    if (!std::filesystem::is_directory(dir / "velodyne", ec))
        throw IoError(dir.string() + ": not a sequence directory (no velodyne/ folder)");
    std::size_t n = 0;
    while (std::filesystem::exists(scan(n), ec)) ++n;
    // A scan numbered past a gap would be silently left out: name the first missing one.
    for (std::filesystem::directory_iterator it(dir / "velodyne", ec), end; !ec && it != end; it.increment(ec)) {
        const std::string file = it->path().filename().string();
        if (file.size() != 10 || !file.ends_with(".bin") || file.find_first_not_of("0123456789") != 6) continue;
        if (static_cast<std::size_t>(std::stoull(file.substr(0, 6))) > n)
            throw InvalidInput((dir / "velodyne").string() + ": scan " + scan(n).filename().string() + " is missing but " + file +
                               " exists (a gap in the numbering; renumber the scans or move the later ones away)");
    }
    return n;
}

SequencePoses find_sequence_poses(const std::filesystem::path& dir, const std::filesystem::path& poses_flag,
                                  const std::filesystem::path& calib_flag) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!poses_flag.empty()) return {poses_flag, calib_flag, "--poses"};
    if (fs::exists(dir / "poses.txt", ec)) return {dir / "poses.txt", calib_flag, "poses.txt"};
    // KITTI odometry: dataset/sequences/NN and dataset/poses/NN.txt.
    const fs::path seq = fs::weakly_canonical(dir, ec);
    const std::string name = seq.filename().string();
    const fs::path kitti = seq.parent_path().parent_path() / "poses" / (name + ".txt");
    if (!name.empty() && seq.parent_path().filename() == "sequences" && fs::exists(kitti, ec)) {
        fs::path calib = calib_flag.empty() ? dir / "calib.txt" : calib_flag;
        if (!fs::exists(calib, ec))
            throw IoError(kitti.string() + ": KITTI's poses are the left camera's and " + calib.string() +
                          " is missing (give the sequence's calib.txt with --calib)");
        return {kitti, calib, "KITTI odometry"};
    }
    throw IoError(dir.string() + ": no poses (looked for " + (dir / "poses.txt").string() + " and " + kitti.string() +
                  "; give a sensor-to-world pose file with --poses)");
}

std::vector<Eigen::Isometry3d> read_sequence_poses(const SequencePoses& where) {
    std::vector<Eigen::Isometry3d> poses = read_poses(where.poses);
    if (!where.calib.empty()) poses = lidar_poses(poses, read_calib_tr(where.calib));
    return poses;
}

std::vector<Eigen::Isometry3d> read_poses(const std::filesystem::path& path) {
    return parse_poses(detail::read_file(path.string()), path.string());
}

std::vector<Eigen::Isometry3d> parse_poses(std::string_view data, const std::string& name) {
    std::string_view rest = data;
    std::vector<Eigen::Isometry3d> poses;
    std::size_t line_no = 0;
    while (!rest.empty()) {
        const std::string_view line = detail::next_line(rest);
        ++line_no;
        detail::Tokens tk(line);
        std::string_view tok;
        double v[12];
        int n = 0;
        while (tk.next(tok)) {
            if (n == 12 || !detail::parse_double(tok, v[n]) || !std::isfinite(v[n]))
                throw FormatError(name + ": line " + std::to_string(line_no) + ": expected 12 finite numbers");
            ++n;
        }
        if (n == 0) continue;  // blank line
        if (n != 12) throw FormatError(name + ": line " + std::to_string(line_no) + ": expected 12 numbers, got " + std::to_string(n));
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) pose.linear()(r, c) = v[4 * r + c];
            pose.translation()[r] = v[4 * r + 3];
        }
        if (!(pose.linear().transpose() * pose.linear()).isApprox(Eigen::Matrix3d::Identity(), 1e-3))
            throw FormatError(name + ": line " + std::to_string(line_no) + ": the rotation is not orthonormal");
        if (pose.linear().determinant() < 0)
            throw FormatError(name + ": line " + std::to_string(line_no) + ": the rotation is a reflection (determinant -1): a mirrored frame, not a pose");
        poses.push_back(pose);
    }
    return poses;
}

Eigen::Isometry3d read_calib_tr(const std::filesystem::path& path) { return parse_calib_tr(detail::read_file(path.string()), path.string()); }

Eigen::Isometry3d parse_calib_tr(std::string_view data, const std::string& name) {
    std::string_view rest = data;
    while (!rest.empty()) {
        std::string_view line = detail::next_line(rest);
        while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
        if (line.substr(0, 3) != "Tr:") continue;
        const std::vector<Eigen::Isometry3d> tr = parse_poses(line.substr(3), name + " (its Tr: line)");
        if (tr.size() != 1) throw FormatError(name + ": the Tr: line holds no transform");
        return tr.front();
    }
    throw FormatError(name + ": no 'Tr:' line (KITTI's calib.txt gives the velodyne-to-camera transform there)");
}

std::vector<Eigen::Isometry3d> lidar_poses(const std::vector<Eigen::Isometry3d>& camera_poses, const Eigen::Isometry3d& tr) {
    std::vector<Eigen::Isometry3d> out;
    out.reserve(camera_poses.size());
    // The general inverse: KITTI's Tr is orthonormal only to ~1e-7, and Isometry3d::inverse()
    // would transpose its rotation.
    Eigen::Isometry3d tr_inv;
    tr_inv.matrix() = tr.matrix().inverse();
    for (const Eigen::Isometry3d& p : camera_poses) out.push_back(tr_inv * p * tr);
    return out;
}

void write_poses(const std::vector<Eigen::Isometry3d>& poses, const std::filesystem::path& path) {
    AtomicFile file(path);
    auto& out = file.stream();
    char buf[64];
    for (const auto& pose : poses) {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) {
                const double x = c < 3 ? pose.linear()(r, c) : pose.translation()[r];
                std::snprintf(buf, sizeof(buf), "%.17g", x);
                out << buf << ((r == 2 && c == 3) ? '\n' : ' ');
            }
    }
    file.commit();
}

std::vector<std::size_t> select_frames(std::size_t available, int first, int frames, int step, const std::string& name) {
    if (first < 0 || frames < 0 || step < 1) throw InvalidArgument("--first and --frames must be >= 0, --step >= 1");
    if (static_cast<std::size_t>(first) >= available)
        throw InvalidArgument("--first " + std::to_string(first) + ": the sequence " + name + " has " + std::to_string(available) + " scans");
    std::vector<std::size_t> out;
    for (auto i = static_cast<std::size_t>(first); i < available && (frames == 0 || out.size() < static_cast<std::size_t>(frames));
         i += static_cast<std::size_t>(step))
        out.push_back(i);
    return out;
}

PointCloud read_world_scan(const KittiSequence& seq, std::size_t frame, const Eigen::Isometry3d& pose, const PointReadOptions& options) {
    PointCloud cloud = read_points(seq.scan(frame), options);
    for (Eigen::Vector3d& p : cloud.points) p = pose * p;  // NaN stays NaN
    return cloud;
}

}  // namespace lidarsurf
