#pragma once
// A recording with the sensor's trajectory: each scan with its pose at the scan's stamp, moved
// into the world frame and, when the recording gives per-point times, de-skewed (each point moved
// by the pose at the time it was measured, so a sweep taken while driving is not smeared).
#include <filesystem>
#include <memory>
#include <vector>

#include "lidarsurf/io/recording.hpp"
#include "lidarsurf/io/trajectory.hpp"

namespace lidarsurf {

struct RecordedDriveOptions {
    RecordingOptions recording;
    bool deskew = true;  ///< when the recording has per-point times
};

class RecordedDrive {
public:
    /// Reads the recording once for its scans' stamps (not their points) and keeps the scans whose
    /// sweep lies within the trajectory's span; the others are counted in skipped(), never
    /// extrapolated. Throws as open_recording, and InvalidInput when no scan is within the span.
    RecordedDrive(std::filesystem::path path, Trajectory trajectory, RecordedDriveOptions options = {});
    ~RecordedDrive();
    RecordedDrive(RecordedDrive&&) noexcept;

    std::size_t size() const { return kept_.size(); }
    std::size_t recorded() const { return recorded_; }  ///< scans in the recording
    std::size_t skipped() const { return recorded_ - kept_.size(); }
    std::size_t recording_index(std::size_t k) const { return kept_[k].index; }
    std::int64_t stamp_ns(std::size_t k) const { return kept_[k].stamp_ns; }
    const Eigen::Isometry3d& pose(std::size_t k) const { return kept_[k].pose; }
    /// The rays' start in the sensor frame (the recording's; Ouster: its lidar origin).
    const Eigen::Vector3d& origin() const { return origin_; }
    /// True when the scans carry per-point times and de-skewing is on.
    bool deskews() const { return deskew_; }
    const std::filesystem::path& path() const { return path_; }

    /// Scan k in the sensor frame, as recorded. Read in order, the recording is streamed; an
    /// earlier k opens it again.
    RecordedScan scan(std::size_t k);
    /// Scan k in the world frame: de-skewed when deskews(), else moved by pose(k). `no_return`,
    /// when given, receives the directions of its rays that returned nothing, turned by pose(k)
    /// (RecordedScan::no_return; empty when the recording does not say).
    PointCloud world_scan(std::size_t k, std::vector<Eigen::Vector3f>* no_return = nullptr);
    /// Scan k in the sensor frame at its stamp: de-skewed when deskews() (each point moved by
    /// pose(k)^-1 times the pose at its time), else as recorded.
    RecordedScan sensor_scan(std::size_t k);

private:
    // Moves each point of `scan` by to(pose at its time), `to` applied to each distinct time once.
    template <typename To>
    void move_by_time(RecordedScan& scan, const Eigen::Isometry3d& fallback, To&& to) const;
    struct Kept {
        std::size_t index = 0;
        std::int64_t stamp_ns = 0;
        Eigen::Isometry3d pose;
    };
    std::filesystem::path path_;
    Trajectory trajectory_;
    RecordedDriveOptions options_;
    std::vector<Kept> kept_;
    std::size_t recorded_ = 0;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    bool deskew_ = false;
    std::unique_ptr<ScanSource> source_;
    std::size_t next_index_ = 0;  // the recording's index of the scan source_ gives next
};

}  // namespace lidarsurf
