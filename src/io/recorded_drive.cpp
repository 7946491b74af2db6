// A recording with its trajectory (see recorded_drive.hpp).
#include "lidarsurf/io/recorded_drive.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

// A point's time (s after the stamp) in ns; FormatError for times no sweep has (over an hour).
std::int64_t offset_ns(double seconds, const std::filesystem::path& path) {
    if (!(std::abs(seconds) <= 3600)) throw FormatError(path.string() + ": a point measured " + std::to_string(seconds) + " s from its scan's stamp");
    return static_cast<std::int64_t>(std::llround(1e9 * seconds));
}

// stamp + offset, FormatError past the clock's range.
std::int64_t at_offset(std::int64_t stamp, double seconds, const std::filesystem::path& path) {
    std::int64_t t = 0;
    if (__builtin_add_overflow(stamp, offset_ns(seconds, path), &t)) throw FormatError(path.string() + ": a stamp past the clock's range");
    return t;
}

}  // namespace

RecordedDrive::RecordedDrive(std::filesystem::path path, Trajectory trajectory, RecordedDriveOptions options)
    : path_(std::move(path)), trajectory_(std::move(trajectory)), options_(std::move(options)) {
    auto source = open_recording(path_, options_.recording);
    RecordedScan scan;
    bool times = true;
    while (source->next(scan)) {
        ++recorded_;
        times = times && !scan.times.empty();
        if (recorded_ == 1) origin_ = scan.origin;
        // The whole sweep must lie within the trajectory when it is de-skewed.
        std::int64_t first = scan.stamp_ns, last = scan.stamp_ns;
        if (options_.deskew && !scan.times.empty()) {
            const auto [lo, hi] = std::minmax_element(scan.times.begin(), scan.times.end());
            first = at_offset(scan.stamp_ns, *lo, path_);
            last = at_offset(scan.stamp_ns, *hi, path_);
        }
        const auto pose = trajectory_.at(scan.stamp_ns);
        if (!pose || !trajectory_.at(first) || !trajectory_.at(last)) continue;
        kept_.push_back({scan.index, scan.stamp_ns, *pose});
    }
    deskew_ = options_.deskew && times && recorded_ > 0;
    if (kept_.empty())
        throw InvalidInput(path_.string() + ": none of its " + std::to_string(recorded_) +
                           " scans lies within the trajectory's span (its times and the recording's stamps must share one clock)");
}

RecordedDrive::~RecordedDrive() = default;
RecordedDrive::RecordedDrive(RecordedDrive&&) noexcept = default;

RecordedScan RecordedDrive::scan(std::size_t k) {
    const std::size_t want = kept_.at(k).index;
    if (!source_ || next_index_ > want) {
        source_ = open_recording(path_, options_.recording);
        next_index_ = 0;
    }
    RecordedScan scan;
    while (source_->next(scan)) {
        ++next_index_;
        if (scan.index == want) return scan;
    }
    throw FormatError(path_.string() + ": scan " + std::to_string(want) + " was there on the first reading and is not now (the file changed?)");
}

template <typename To>
void RecordedDrive::move_by_time(RecordedScan& s, const Eigen::Isometry3d& fallback, To&& to) const {
    // Points of one column share a time: the pose is looked up once per distinct time in a row.
    float last_time = std::numeric_limits<float>::quiet_NaN();
    Eigen::Isometry3d by = to(fallback);
    for (std::size_t i = 0; i < s.cloud.points.size(); ++i) {
        if (s.times[i] != last_time) {
            last_time = s.times[i];
            const auto p = trajectory_.at(at_offset(s.stamp_ns, last_time, path_));
            by = to(p ? *p : fallback);  // within the span: checked on the first reading
        }
        s.cloud.points[i] = by * s.cloud.points[i];
    }
}

PointCloud RecordedDrive::world_scan(std::size_t k, std::vector<Eigen::Vector3f>* no_return) {
    RecordedScan s = scan(k);
    const Eigen::Isometry3d& pose = kept_[k].pose;
    if (no_return) {
        const Eigen::Matrix3f turn = pose.linear().cast<float>();
        no_return->clear();
        no_return->reserve(s.no_return.size());
        for (const Eigen::Vector3f& u : s.no_return) no_return->push_back(turn * u);
    }
    if (deskew_ && s.times.size() == s.cloud.points.size()) {
        move_by_time(s, pose, [](const Eigen::Isometry3d& at) { return at; });
    } else {
        for (auto& p : s.cloud.points) p = pose * p;
    }
    return std::move(s.cloud);
}

RecordedScan RecordedDrive::sensor_scan(std::size_t k) {
    RecordedScan s = scan(k);
    if (deskew_ && s.times.size() == s.cloud.points.size()) {
        const Eigen::Isometry3d to_sensor = kept_[k].pose.inverse();
        move_by_time(s, kept_[k].pose, [&](const Eigen::Isometry3d& at) { return Eigen::Isometry3d(to_sensor * at); });
    }
    return s;
}

}  // namespace lidarsurf
