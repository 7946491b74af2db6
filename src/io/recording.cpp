// Recordings (see recording.hpp): which reader a file goes to, the Ouster pcap source, and the
// summary `lidarsurf info` prints.
#include "lidarsurf/io/recording.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/pcap.hpp"
#include "recording_sources.hpp"

namespace lidarsurf {
namespace {

std::string joined(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
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

std::string lower_extension(const std::filesystem::path& path) {
    std::string e = path.extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e;
}

std::string type_of(const std::vector<TopicType>& topics, const std::string& topic) {
    for (const auto& t : topics)
        if (t.name == topic) return t.type;
    return {};
}

std::string choose_scan_topic(const std::vector<TopicType>& topics, const std::string& requested, const std::string& cloud_type,
                              const std::string& packet_type, const std::string& where) {
    const auto of_type = [&](const std::string& type) {
        std::vector<std::string> out;
        for (const auto& t : topics)
            if (t.type == type && t.name.find("imu") == std::string::npos && std::find(out.begin(), out.end(), t.name) == out.end())
                out.push_back(t.name);
        return out;
    };
    if (!requested.empty()) {
        const std::string type = type_of(topics, requested);
        if (type.empty()) throw InvalidArgument(where + ": no topic " + requested + " in the recording");
        if (type != cloud_type && type != packet_type)
            throw InvalidArgument(where + ": topic " + requested + " carries " + type + ", not " + cloud_type + (packet_type.empty() ? "" : " or Ouster packets"));
        return requested;
    }
    const auto clouds = of_type(cloud_type);
    const auto packets = packet_type.empty() ? std::vector<std::string>{} : of_type(packet_type);
    if (clouds.size() > 1) throw InvalidArgument(where + ": several " + cloud_type + " topics (" + joined(clouds) + "): choose one with --topic");
    if (clouds.size() == 1) return clouds.front();
    if (packets.size() > 1) throw InvalidArgument(where + ": several Ouster packet topics (" + joined(packets) + "): choose one with --topic");
    if (packets.size() == 1) return packets.front();
    throw InvalidArgument(where + ": no " + cloud_type + (packet_type.empty() ? "" : " or Ouster packet") + " topic in the recording");
}

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
    const std::string e = detail::lower_extension(path);
    return e == ".pcap" || e == ".pcapng" || e == ".bag" || detail::is_ros2_bag(path);
}

std::unique_ptr<ScanSource> open_recording(const std::filesystem::path& path, const RecordingOptions& options) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) throw IoError(path.string() + ": no such file");
    const std::string e = detail::lower_extension(path);
    if (e == ".pcap" || e == ".pcapng") return detail::open_ouster_pcap(path, options);
    if (e == ".bag") return detail::open_ros1_bag(path, options);
    if (detail::is_ros2_bag(path)) return detail::open_ros2_bag(path, options);
    throw InvalidInput(path.string() + ": not a recording lidarsurf reads (pcap, ROS 1 bag, ROS 2 bag: a directory with metadata.yaml, .db3 or .mcap)");
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

RecordedScan read_recorded_scan_at(const std::filesystem::path& path, double seconds, const RecordingOptions& options) {
    if (!(seconds >= 0) || !std::isfinite(seconds)) throw InvalidArgument(path.string() + ": a time of " + std::to_string(seconds) + " s (it must be >= 0)");
    auto source = open_recording(path, options);
    RecordedScan scan, best;
    std::int64_t first = 0;
    double best_gap = 0, last = 0;
    std::size_t count = 0;
    for (; source->next(scan); ++count) {
        if (count == 0) first = scan.stamp_ns;
        last = 1e-9 * static_cast<double>(scan.stamp_ns - first);
        const double gap = std::abs(last - seconds);
        if (count == 0 || gap < best_gap) {
            best = std::move(scan);
            best_gap = gap;
        } else if (last > seconds) {
            break;  // the stamps grow: no nearer scan follows
        }
    }
    if (count == 0) throw InvalidArgument(path.string() + ": the recording holds no scan");
    if (seconds > last + 1)
        throw InvalidArgument(path.string() + ": " + std::to_string(seconds) + " s asked for, but the scans span " + std::to_string(last) + " s");
    return best;
}

RecordingSummary summarize_recording(const std::filesystem::path& path, const RecordingOptions& options) {
    RecordingSummary s;
    const std::string e = detail::lower_extension(path);
    auto source = open_recording(path, options);
    if (e == ".bag") {
        s.container = "ROS 1 bag";
        s.topics = detail::ros1_bag_topics(path);
    } else if (detail::is_ros2_bag(path)) {
        s.container = "ROS 2 bag";
        s.topics = detail::ros2_bag_topics(path);
    } else {
        s.container = "pcap";
        s.topics = detail::pcap_topics(path);
    }
    s.source = source->description();
    RecordedScan scan;
    bool times = true;
    while (source->next(scan)) {
        if (s.scans++ == 0) {
            s.first_ns = scan.stamp_ns;
            s.frame_id = scan.frame_id;
        }
        s.last_ns = scan.stamp_ns;
        s.stamps_ns.push_back(scan.stamp_ns);
        s.points += scan.cloud.points.size();
        if (scan.completeness < 0.999) ++s.partial_scans;
        times = times && !scan.times.empty();
    }
    s.per_point_times = s.scans > 0 && times;
    return s;
}

}  // namespace lidarsurf
