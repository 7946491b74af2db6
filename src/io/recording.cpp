// Recordings (see recording.hpp): which reader a file goes to, the Ouster and Velodyne pcap
// sources, and the summary `lidarsurf info` prints.
#include "lidarsurf/io/recording.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/pcap.hpp"
#include "lidarsurf/io/velodyne.hpp"
#include "recording_sources.hpp"

namespace lidarsurf {
namespace {

std::string joined(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

// Feeds a capture's datagrams to `port` into `sweeps` (through `add`, true when a sweep closed)
// until a sweep is done or the capture ends; then the last sweep.
template <typename Sweeps, typename Add>
bool next_sweep(PcapUdpReader& pcap, Sweeps& sweeps, std::uint16_t port, bool& ended, RecordedScan& scan, Add&& add) {
    UdpDatagram d;
    while (!ended && pcap.next(d)) {
        if (d.destination_port != port) continue;
        if (add(d, pcap.name() + ": packet " + std::to_string(d.packet))) {
            scan = sweeps.take();
            return true;
        }
    }
    ended = true;
    if (sweeps.finish()) {
        scan = sweeps.take();
        return true;
    }
    return false;
}

class OusterPcapSource final : public ScanSource {
public:
    OusterPcapSource(const std::filesystem::path& path, OusterMetadata metadata, OusterReturns returns)
        : pcap_(path), sweeps_(std::move(metadata), returns) {}

    bool next(RecordedScan& scan) override {
        // Other ports: IMU packets, other traffic.
        return next_sweep(pcap_, sweeps_, static_cast<std::uint16_t>(sweeps_.metadata().udp_port_lidar), ended_, scan,
                          [&](const UdpDatagram& d, const std::string& where) { return sweeps_.add(d.payload, where); });
    }

    std::string description() const override {
        return describe_ouster(sweeps_.metadata()) + ", UDP port " + std::to_string(sweeps_.metadata().udp_port_lidar) + ", pcap";
    }

private:
    PcapUdpReader pcap_;
    OusterSweeps sweeps_;
    bool ended_ = false;
};

class VelodynePcapSource final : public ScanSource {
public:
    VelodynePcapSource(const std::filesystem::path& path, VelodyneModel model, VelodyneCalibration calibration, OusterReturns returns,
                       std::uint16_t port, int return_mode)
        : pcap_(path),
          sweeps_(model, std::move(calibration), returns == OusterReturns::Both ? VelodyneReturns::Both : VelodyneReturns::First, return_mode),
          port_(port) {}

    bool next(RecordedScan& scan) override {
        // Other ports: position packets (8308), other traffic.
        return next_sweep(pcap_, sweeps_, port_, ended_, scan,
                          [&](const UdpDatagram& d, const std::string& where) { return sweeps_.add(d.payload, d.stamp_ns, where); });
    }

    std::string description() const override { return sweeps_.description() + ", UDP port " + std::to_string(port_) + ", pcap"; }

private:
    PcapUdpReader pcap_;
    VelodyneSweeps sweeps_;
    std::uint16_t port_;
    bool ended_ = false;
};

// The first Velodyne data packet among a capture's first datagrams, and its port.
std::optional<std::pair<std::vector<std::uint8_t>, std::uint16_t>> first_velodyne_packet(const std::filesystem::path& path) {
    PcapUdpReader pcap(path);
    UdpDatagram d;
    for (int i = 0; i < 4096 && pcap.next(d); ++i) {
        if (is_velodyne_data_packet(d.payload)) return std::make_pair(std::move(d.payload), d.destination_port);
        if (d.payload.size() >= 1200 && d.payload[0] == 0xFF && d.payload[1] == 0xEE)
            throw FormatError(pcap.name() + ": packet " + std::to_string(d.packet) + ": " + std::to_string(d.payload.size()) +
                              "-byte datagrams to port " + std::to_string(d.destination_port) +
                              " with Velodyne block flags, where a Velodyne data packet has 1206 bytes (not a layout lidarsurf reads)");
    }
    return std::nullopt;
}

bool is_yaml(const std::filesystem::path& p) {
    const std::string e = detail::lower_extension(p);
    return e == ".yaml" || e == ".yml";
}

std::unique_ptr<ScanSource> open_velodyne_pcap(const std::filesystem::path& path, const RecordingOptions& options,
                                               const std::vector<std::uint8_t>& packet, std::uint16_t port) {
    std::optional<VelodyneCalibration> calibration;
    std::filesystem::path file = options.metadata;
    std::error_code ec;
    if (file.empty())
        for (const char* e : {".yaml", ".yml"})
            if (std::filesystem::exists(std::filesystem::path(path).replace_extension(e), ec)) {
                file = std::filesystem::path(path).replace_extension(e);
                break;
            }
    if (!file.empty()) calibration = read_velodyne_calibration(file);
    std::optional<VelodyneModel> model = velodyne_model_of_packet(packet);
    if (!model) {
        // No product byte (the HDL-64E sends status bytes there): the calibration says which.
        if (!calibration)
            throw InvalidArgument(path.string() + ": Velodyne packets without a product id (an HDL-64E?) need the sensor's calibration: "
                                  "give the ROS velodyne driver's YAML with --metadata, or put it beside the pcap as " +
                                  std::filesystem::path(path).replace_extension(".yaml").string());
        const std::size_t n = calibration->lasers.size();
        model = n == 64 ? VelodyneModel::HDL64E : n == 32 ? VelodyneModel::HDL32E : VelodyneModel::VLP16;
    }
    if (!calibration) calibration = velodyne_factory_calibration(*model);
    if (!calibration)
        throw InvalidArgument(path.string() + ": a Velodyne " + std::string(velodyne_model_name(*model)) + " needs its calibration (--metadata FILE.yaml)");
    return std::make_unique<VelodynePcapSource>(path, *model, std::move(*calibration), options.returns, port, packet[1204]);
}

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

std::unique_ptr<ScanSource> open_pcap(const std::filesystem::path& path, const RecordingOptions& options) {
    std::filesystem::path metadata = options.metadata;
    std::error_code ec;
    if (metadata.empty() || is_yaml(metadata)) {
        const std::filesystem::path beside = std::filesystem::path(path).replace_extension(".json");
        if (metadata.empty() && std::filesystem::exists(beside, ec)) {
            metadata = beside;
        } else {
            if (auto velodyne = first_velodyne_packet(path)) return open_velodyne_pcap(path, options, velodyne->first, velodyne->second);
            if (!metadata.empty()) throw InvalidInput(path.string() + ": a Velodyne calibration (" + metadata.string() + ") but no Velodyne data packet in the capture");
            throw InvalidArgument(path.string() + ": no Velodyne data packet, and no sensor metadata: " + beside.string() +
                                  " is absent (an Ouster pcap needs the sensor's metadata JSON; give it with --metadata)");
        }
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
    if (e == ".pcap" || e == ".pcapng") return detail::open_pcap(path, options);
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
