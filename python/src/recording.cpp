// lidarsurf.read_recording: the scans of a recording (pcap, ROS 1 bag, ROS 2 bag) for users' own pipelines,
// one at a time, with their poses when a trajectory is given.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>

#include "lidarsurf/io/recorded_drive.hpp"
#include "lidarsurf/io/recorded_poses.hpp"
#include "lidarsurf/io/recording.hpp"
#include "numpy_views.hpp"

namespace py = pybind11;

namespace lidarsurf::python {
namespace {

// Iterates a recording: every scan (no trajectory), or the scans within the trajectory's span.
class RecordingScans {
public:
    RecordingScans(const std::string& path, const RecordingOptions& o, const std::optional<std::string>& poses, const std::optional<std::string>& times,
                   bool deskew, const RecordedPosesOptions& recorded) {
        py::gil_scoped_release release;
        if (poses) {
            RecordedDriveOptions d;
            d.recording = o;
            d.deskew = deskew;
            Trajectory trajectory = *poses == "recording" ? read_recorded_poses(path, recorded, o).trajectory : read_trajectory(*poses, times.value_or(""));
            drive_ = std::make_unique<RecordedDrive>(path, std::move(trajectory), d);
        } else {
            source_ = open_recording(path, o);
        }
    }

    py::tuple next() {
        RecordedScan scan;
        std::optional<Eigen::Isometry3d> pose;
        {
            py::gil_scoped_release release;
            if (drive_) {
                if (k_ < drive_->size()) {
                    scan = drive_->sensor_scan(k_);
                    pose = drive_->pose(k_);
                    ++k_;
                } else {
                    ended_ = true;
                }
            } else {
                ended_ = !source_->next(scan);
            }
        }
        if (ended_) throw py::stop_iteration();
        py::object times = py::none();
        if (!scan.times.empty()) {
            py::array_t<float> t(static_cast<py::ssize_t>(scan.times.size()));
            std::copy(scan.times.begin(), scan.times.end(), t.mutable_data());
            times = std::move(t);
        }
        py::object pose_array = py::none();
        if (pose) {
            py::array_t<double> m({4, 4});
            for (int r = 0; r < 4; ++r)
                for (int c = 0; c < 4; ++c) m.mutable_at(r, c) = pose->matrix()(r, c);
            pose_array = std::move(m);
        }
        return py::make_tuple(scan.stamp_ns, points_to_numpy(std::move(scan.cloud.points)), times, pose_array);
    }

private:
    std::unique_ptr<ScanSource> source_;
    std::unique_ptr<RecordedDrive> drive_;
    std::size_t k_ = 0;
    bool ended_ = false;
};

}  // namespace

void bind_recording(py::module_& m) {
    py::class_<RecordingScans>(m, "RecordingScans", "The scans of a recording, one at a time (see read_recording).")
        .def("__iter__", [](RecordingScans& r) -> RecordingScans& { return r; })
        .def("__next__", &RecordingScans::next);
    m.def(
        "read_recording",
        [](const std::string& path, const std::optional<std::string>& topic, const std::optional<std::string>& poses,
           const std::optional<std::string>& metadata, const std::optional<std::string>& times, bool deskew, const std::string& returns,
           const std::string& pose_topic, const std::string& fixed_frame, const std::string& sensor_frame) {
            RecordingOptions o;
            o.topic = topic.value_or("");
            o.metadata = metadata.value_or("");
            o.returns = parse_ouster_returns(returns);
            RecordedPosesOptions r;
            r.pose_topic = pose_topic;
            r.fixed_frame = fixed_frame;
            r.sensor_frame = sensor_frame;
            return std::make_unique<RecordingScans>(path, o, poses, times, deskew, r);
        },
        py::arg("path"), py::arg("topic") = py::none(), py::arg("poses") = py::none(), py::arg("metadata") = py::none(),
        py::arg("times") = py::none(), py::arg("deskew") = true, py::arg("returns") = "first", py::arg("pose_topic") = "",
        py::arg("fixed_frame") = "", py::arg("sensor_frame") = "",
        "The scans of a recording (an Ouster .pcap with its metadata JSON beside it or `metadata`, a Velodyne .pcap\n"
        "(VLP-16, VLP-32C, HDL-32E with their built-in angles, HDL-64E with its calibration YAML beside it or `metadata`), a ROS 1 .bag of\n"
        "PointCloud2 or Ouster packets on `topic`, a ROS 2 bag of PointCloud2: its directory, a .db3 or a .mcap), one at a time, as tuples (stamp_ns, points, times, pose):\n"
        "points (N, 3) float64 in the sensor frame; times (N,) float32 seconds after stamp_ns, or None when the\n"
        "recording has none; pose the 4x4 sensor-to-world matrix at stamp_ns from the trajectory `poses` (TUM, or\n"
        "KITTI poses with their `times`; \"recording\": the bag's own /tf, or `pose_topic`, from `fixed_frame` to\n"
        "`sensor_frame`, as `lidarsurf fuse` takes them), or None without one. With `poses`, only the scans within its span come,\n"
        "de-skewed to stamp_ns when they have per-point times (deskew=False: as recorded). ValueError for a\n"
        "malformed recording (naming the packet or message), OSError when it cannot be read.");
}

}  // namespace lidarsurf::python
