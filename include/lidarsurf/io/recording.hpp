#pragma once
// Recordings of a robot's drive as scans: an Ouster pcap (with the sensor's metadata JSON), a
// Velodyne pcap (with its calibration, or a fixed-angle model's built-in one), a
// ROS 1 bag of sensor_msgs/PointCloud2 or of the Ouster driver's raw packets, and a ROS 2 bag
// (rosbag2's directory, a .db3 or an .mcap) of sensor_msgs/msg/PointCloud2. Scans are read one
// at a time (memory does not grow with the recording's length), in the recording's order.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "lidarsurf/io/ouster.hpp"
#include "lidarsurf/io/recorded_scan.hpp"

namespace lidarsurf {

struct RecordingOptions {
    /// The topic the scans are on (bags). Empty: the bag's only PointCloud2 topic, else its Ouster
    /// lidar packets.
    std::string topic;
    /// The Ouster metadata JSON, or a Velodyne calibration YAML. Empty: beside the pcap under its
    /// base name (X.pcap -> X.json, X.yaml), the built-in angles of a VLP-16, VLP-32C or HDL-32E,
    /// or the bag's Ouster metadata topic.
    std::filesystem::path metadata;
    OusterReturns returns = OusterReturns::First;
};

class ScanSource {
public:
    virtual ~ScanSource() = default;
    /// The next scan; false at the end. Throws FormatError naming the file and the message or
    /// packet where the recording is malformed.
    virtual bool next(RecordedScan& scan) = 0;
    /// What the scans come from, for reports: "Ouster OS-1-64, LEGACY, 64 x 1024, pcap".
    virtual std::string description() const = 0;
};

/// True for the names of the recordings lidarsurf reads: .pcap, .pcapng, .bag, .db3, .mcap and a
/// directory holding metadata.yaml (a ROS 2 bag).
bool is_recording(const std::filesystem::path& path);

/// Opens a recording. Throws IoError (missing, unreadable), FormatError (malformed),
/// InvalidArgument (a topic that is not there, several candidate topics, no metadata) and
/// InvalidInput (a kind of recording this build does not read).
std::unique_ptr<ScanSource> open_recording(const std::filesystem::path& path, const RecordingOptions& options = {});

/// The scan numbered `index` (from 0) of a recording. Throws InvalidArgument when it has fewer.
RecordedScan read_recorded_scan(const std::filesystem::path& path, std::size_t index, const RecordingOptions& options = {});

/// The scan whose stamp is nearest `seconds` after the first scan's stamp (the first of two as
/// near). Throws InvalidArgument when `seconds` is negative or not finite, or lies more than a
/// second past the last scan.
RecordedScan read_recorded_scan_at(const std::filesystem::path& path, double seconds, const RecordingOptions& options = {});

struct TopicSummary {
    std::string name;   ///< topic, or "udp:PORT" in a pcap
    std::string type;   ///< message type, or what the port carries
    std::size_t messages = 0;
    std::int64_t first_ns = 0, last_ns = 0;
};

struct RecordingSummary {
    std::string container;              ///< "pcap", "ROS 1 bag", "ROS 2 bag"
    std::vector<TopicSummary> topics;
    std::string source;                 ///< ScanSource::description() of what scans are read from
    std::size_t scans = 0;
    std::size_t points = 0;
    std::size_t partial_scans = 0;      ///< scans with less than a whole revolution
    std::int64_t first_ns = 0, last_ns = 0;  ///< the scans' stamps
    std::vector<std::int64_t> stamps_ns;     ///< each scan's
    std::string frame_id;                    ///< the first scan's
    bool per_point_times = false;
};

/// What `lidarsurf info` prints: the recording's topics and the scans it gives.
RecordingSummary summarize_recording(const std::filesystem::path& path, const RecordingOptions& options = {});

}  // namespace lidarsurf
