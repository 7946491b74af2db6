// Recordings (see recording.hpp): which reader a file goes to, the Ouster pcap source, and the
// summary `lidarsurf info` prints.
#include "lidarsurf/io/recording.hpp"

#include <algorithm>
#include <map>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/pcap.hpp"
#include "recording_sources.hpp"

namespace lidarsurf {
namespace {

std::string lower_extension(const std::filesystem::path& path) {
    std::string e = path.extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e;
}

bool is_ros2_bag_directory(const std::filesystem::path& path) {
    std::error_code ec;
    return std::filesystem::is_directory(path, ec) && std::filesystem::exists(path / "metadata.yaml", ec);
}

class OusterPcapSource final : public ScanSource {
public:
    OusterPcapSource(const std::filesystem::path& path, OusterMetadata metadata, OusterReturns returns)
        : pcap_(path), sweeps_(std::move(metadata), returns) {}

    bool next(RecordedScan& scan) override {
        UdpDatagram d;
        while (!ended_ && pcap_.next(d)) {
            if (d.destination_port != sweeps_.metadata().udp_port_lidar) continue;  // IMU packets, other traffic
            if (sweeps_.add(d.payload, pcap_.name() + ": packet " + std::to_string(d.packet))) {
                scan = sweeps_.take();
                return true;
            }
        }
        ended_ = true;
        if (sweeps_.finish()) {
            scan = sweeps_.take();
            return true;
        }
        return false;
    }

    std::string description() const override {
        return describe_ouster(sweeps_.metadata()) + ", UDP port " + std::to_string(sweeps_.metadata().udp_port_lidar) + ", pcap";
    }

private:
    PcapUdpReader pcap_;
    OusterSweeps sweeps_;
    bool ended_ = false;
};

}  // namespace

namespace detail {

std::unique_ptr<ScanSource> open_ouster_pcap(const std::filesystem::path& path, const RecordingOptions& options) {
    std::filesystem::path metadata = options.metadata;
    if (metadata.empty()) {
        metadata = std::filesystem::path(path).replace_extension(".json");
        std::error_code ec;
        if (!std::filesystem::exists(metadata, ec))
            throw InvalidArgument(path.string() + ": no sensor metadata: " + metadata.string() +
                                  " is absent (an Ouster pcap needs the sensor's metadata JSON; give it with --metadata)");
    }
    return std::make_unique<OusterPcapSource>(path, read_ouster_metadata(metadata), options.returns);
}

std::vector<TopicSummary> pcap_topics(const std::filesystem::path& path) {
    PcapUdpReader pcap(path);
    std::map<std::uint16_t, TopicSummary> ports;
    UdpDatagram d;
    while (pcap.next(d)) {
        auto& t = ports[d.destination_port];
        if (t.messages++ == 0) {
            t.name = "udp:" + std::to_string(d.destination_port);
            t.type = std::to_string(d.payload.size()) + "-byte datagrams";
            t.first_ns = d.stamp_ns;
        }
        t.last_ns = d.stamp_ns;
    }
    std::vector<TopicSummary> out;
    for (auto& [port, t] : ports) out.push_back(std::move(t));
    return out;
}

}  // namespace detail

bool is_recording(const std::filesystem::path& path) {
    const std::string e = lower_extension(path);
    return e == ".pcap" || e == ".pcapng" || e == ".bag" || e == ".mcap" || e == ".db3" || is_ros2_bag_directory(path);
}

std::unique_ptr<ScanSource> open_recording(const std::filesystem::path& path, const RecordingOptions& options) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw IoError(path.string() + ": no such file");
    const std::string e = lower_extension(path);
    if (e == ".pcap" || e == ".pcapng") return detail::open_ouster_pcap(path, options);
    if (e == ".bag") return detail::open_ros1_bag(path, options);
    throw InvalidInput(path.string() + ": a ROS 2 bag (MCAP or sqlite3): lidarsurf reads ROS 1 bags and pcaps so far; " +
                       "convert it with `rosbags-convert` or `ros2 bag convert` to a ROS 1 bag");
}

RecordedScan read_recorded_scan(const std::filesystem::path& path, std::size_t index, const RecordingOptions& options) {
    auto source = open_recording(path, options);
    RecordedScan scan;
    std::size_t count = 0;
    for (; source->next(scan); ++count)
        if (count == index) return scan;
    throw InvalidArgument(path.string() + ": scan " + std::to_string(index) + " asked for, but the recording holds " + std::to_string(count) +
                          " (numbered from 0)");
}

RecordingSummary summarize_recording(const std::filesystem::path& path, const RecordingOptions& options) {
    RecordingSummary s;
    const std::string e = lower_extension(path);
    auto source = open_recording(path, options);
    s.container = e == ".bag" ? "ROS 1 bag" : "pcap";
    s.topics = e == ".bag" ? detail::ros1_bag_topics(path) : detail::pcap_topics(path);
    s.source = source->description();
    RecordedScan scan;
    bool times = true;
    while (source->next(scan)) {
        if (s.scans++ == 0) s.first_ns = scan.stamp_ns;
        s.last_ns = scan.stamp_ns;
        s.points += scan.cloud.points.size();
        if (scan.completeness < 0.999) ++s.partial_scans;
        times = times && !scan.times.empty();
    }
    s.per_point_times = s.scans > 0 && times;
    return s;
}

}  // namespace lidarsurf
