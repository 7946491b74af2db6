// Ouster metadata and lidar packets (see ouster.hpp). Byte layouts: Ouster's firmware user
// manual, "Lidar Data Format" (all fields little endian).
#include "lidarsurf/io/ouster.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include <Eigen/LU>
#include <nlohmann/json.hpp>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

using Json = nlohmann::json;

struct ProfileLayout {
    std::string_view name;
    OusterProfile profile;
    std::size_t pixel_bytes;
};

constexpr ProfileLayout kProfiles[] = {
    {"LEGACY", OusterProfile::Legacy, 12},
    {"RNG19_RFL8_SIG16_NIR16", OusterProfile::Single, 12},
    {"RNG19_RFL8_SIG16_NIR16_DUAL", OusterProfile::Dual, 16},
    {"RNG15_RFL8_NIR8", OusterProfile::LowData, 4},
    {"FUSA_RNG15_RFL8_NIR8_DUAL", OusterProfile::FusaDual, 8},
};

const ProfileLayout& layout_of(OusterProfile p) {
    for (const auto& l : kProfiles)
        if (l.profile == p) return l;
    return kProfiles[0];
}

// The firmware's defaults for metadata that predates a field (firmware 1.x / 2.0).
constexpr double kGen1BeamOffsetMm = 12.163;
constexpr double kDefaultLidarHeightMm = 36.180;
constexpr std::size_t kPacketHeader = 32, kPacketFooter = 32;
constexpr std::size_t kLegacyColumnHeader = 16, kColumnHeader = 12, kLegacyColumnFooter = 4;

template <typename T>
T get_le(const std::uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);  // x86 and every target we build for are little endian
    return v;
}

const Json* find(const Json& j, std::initializer_list<const char*> path) {
    const Json* at = &j;
    for (const char* key : path) {
        if (!at->is_object()) return nullptr;
        auto it = at->find(key);
        if (it == at->end()) return nullptr;
        at = &*it;
    }
    return at;
}

// A field in the flat layout (firmware 2.x) or under `section` (firmware 3.x).
const Json* field(const Json& j, const char* section, const char* key) {
    if (const Json* v = find(j, {section, key})) return v;
    return find(j, {key});
}

std::vector<double> numbers(const Json* v, const std::string& what, const std::string& name) {
    if (!v || !v->is_array()) throw FormatError(name + ": Ouster metadata has no " + what);
    std::vector<double> out;
    for (const Json& x : *v) {
        if (!x.is_number() || !std::isfinite(x.get<double>())) throw FormatError(name + ": Ouster metadata: " + what + " holds a value that is not a finite number");
        out.push_back(x.get<double>());
    }
    return out;
}

int integer(const Json* v, int fallback, const std::string& what, const std::string& name) {
    if (!v) return fallback;
    if (!v->is_number_integer() || v->get<std::int64_t>() < -65536 || v->get<std::int64_t>() > 65536)
        throw FormatError(name + ": Ouster metadata: " + what + " is not an integer in [-65536, 65536]");
    return static_cast<int>(v->get<std::int64_t>());
}

}  // namespace

std::string_view ouster_profile_name(OusterProfile profile) { return layout_of(profile).name; }

std::size_t OusterMetadata::packet_size() const {
    const auto& l = layout_of(profile);
    const std::size_t column = profile == OusterProfile::Legacy
                                   ? kLegacyColumnHeader + pixels_per_column * l.pixel_bytes + kLegacyColumnFooter
                                   : kColumnHeader + pixels_per_column * l.pixel_bytes;
    const std::size_t frame = profile == OusterProfile::Legacy ? 0 : kPacketHeader + kPacketFooter;
    return frame + columns_per_packet * column;
}

int OusterMetadata::window_columns() const {
    return column_last >= column_first ? column_last - column_first + 1 : columns_per_frame - column_first + column_last + 1;
}

int OusterMetadata::returns() const { return profile == OusterProfile::Dual || profile == OusterProfile::FusaDual ? 2 : 1; }

OusterMetadata parse_ouster_metadata(std::string_view text, const std::string& name) {
    Json j = Json::parse(text.begin(), text.end(), nullptr, false);
    if (j.is_discarded() || !j.is_object()) throw FormatError(name + ": not a JSON object (Ouster metadata)");
    OusterMetadata m;
    m.altitude_deg = numbers(field(j, "beam_intrinsics", "beam_altitude_angles"), "beam_altitude_angles", name);
    m.azimuth_deg = numbers(field(j, "beam_intrinsics", "beam_azimuth_angles"), "beam_azimuth_angles", name);
    if (m.altitude_deg.empty() || m.altitude_deg.size() != m.azimuth_deg.size() || m.altitude_deg.size() > 512)
        throw FormatError(name + ": Ouster metadata: " + std::to_string(m.altitude_deg.size()) + " beam altitudes and " +
                          std::to_string(m.azimuth_deg.size()) + " azimuths (must match, 1 to 512)");
    for (std::size_t i = 0; i < m.altitude_deg.size(); ++i)
        if (std::abs(m.altitude_deg[i]) > 90 || std::abs(m.azimuth_deg[i]) > 45)
            throw FormatError(name + ": Ouster metadata: beam " + std::to_string(i) + " has an angle out of range");

    const Json* mode = field(j, "config_params", "lidar_mode");
    int mode_columns = 0;
    if (mode && mode->is_string()) {
        const std::string s = mode->get<std::string>();
        const auto x = s.find('x');
        try {
            mode_columns = std::stoi(s.substr(0, x));
            if (x != std::string::npos) m.frequency_hz = std::stoi(s.substr(x + 1));
        } catch (const std::exception&) {
            throw FormatError(name + ": Ouster metadata: lidar_mode '" + s + "' is not COLUMNSxHZ");
        }
    }
    const Json* format = find(j, {"lidar_data_format"});
    if (!format) format = find(j, {"data_format"});
    const Json empty = Json::object();
    const Json& f = format ? *format : empty;
    m.pixels_per_column = integer(find(f, {"pixels_per_column"}), static_cast<int>(m.altitude_deg.size()), "pixels_per_column", name);
    m.columns_per_packet = integer(find(f, {"columns_per_packet"}), 16, "columns_per_packet", name);
    m.columns_per_frame = integer(find(f, {"columns_per_frame"}), mode_columns, "columns_per_frame", name);
    m.column_first = 0;
    m.column_last = m.columns_per_frame - 1;
    if (const Json* w = find(f, {"column_window"})) {
        const auto v = numbers(w, "column_window", name);
        if (v.size() != 2 || !(v[0] >= 0 && v[0] <= 65536 && v[1] >= 0 && v[1] <= 65536))
            throw FormatError(name + ": Ouster metadata: column_window is not two column numbers");
        m.column_first = static_cast<int>(v[0]);
        m.column_last = static_cast<int>(v[1]);
    }
    if (const Json* p = find(f, {"udp_profile_lidar"})) {
        const std::string s = p->is_string() ? p->get<std::string>() : std::string{};
        const auto* it = std::find_if(std::begin(kProfiles), std::end(kProfiles), [&](const ProfileLayout& l) { return l.name == s; });
        if (it == std::end(kProfiles)) throw FormatError(name + ": Ouster metadata: udp_profile_lidar '" + s + "' is not a profile lidarsurf reads");
        m.profile = it->profile;
    }
    if (m.pixels_per_column != static_cast<int>(m.altitude_deg.size()))
        throw FormatError(name + ": Ouster metadata: " + std::to_string(m.pixels_per_column) + " pixels per column but " +
                          std::to_string(m.altitude_deg.size()) + " beams");
    if (m.columns_per_frame < 16 || m.columns_per_frame > 8192 || m.columns_per_packet < 1 || m.columns_per_packet > 64 ||
        m.column_first < 0 || m.column_last < 0 || m.column_first >= m.columns_per_frame || m.column_last >= m.columns_per_frame ||
        !(m.frequency_hz > 0 && m.frequency_hz <= 100))
        throw FormatError(name + ": Ouster metadata: columns per frame " + std::to_string(m.columns_per_frame) + ", per packet " +
                          std::to_string(m.columns_per_packet) + ", window [" + std::to_string(m.column_first) + ", " +
                          std::to_string(m.column_last) + "] or lidar_mode out of range");
    if (m.packet_size() > 65507) throw FormatError(name + ": Ouster metadata: a packet would exceed a UDP datagram");

    if (const Json* t = find(j, {"beam_intrinsics", "beam_to_lidar_transform"})) {
        const auto v = numbers(t, "beam_to_lidar_transform", name);
        if (v.size() != 16) throw FormatError(name + ": Ouster metadata: beam_to_lidar_transform is not 16 numbers");
        m.beam_offset_x_mm = v[3];
        m.beam_offset_z_mm = v[11];
    } else if (const Json* o = field(j, "beam_intrinsics", "lidar_origin_to_beam_origin_mm")) {
        if (!o->is_number()) throw FormatError(name + ": Ouster metadata: lidar_origin_to_beam_origin_mm is not a number");
        m.beam_offset_x_mm = o->get<double>();
    } else {
        m.beam_offset_x_mm = kGen1BeamOffsetMm;
    }
    if (const Json* t = field(j, "lidar_intrinsics", "lidar_to_sensor_transform")) {
        const auto v = numbers(t, "lidar_to_sensor_transform", name);
        if (v.size() != 16) throw FormatError(name + ": Ouster metadata: lidar_to_sensor_transform is not 16 numbers");
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) m.lidar_to_sensor(r, c) = v[static_cast<std::size_t>(4 * r + c)];
        const Eigen::Matrix3d rot = m.lidar_to_sensor.topLeftCorner<3, 3>();
        if (!((rot * rot.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-3) || rot.determinant() < 0)
            throw FormatError(name + ": Ouster metadata: lidar_to_sensor_transform's rotation is not a rotation");
    } else {
        m.lidar_to_sensor << -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, kDefaultLidarHeightMm, 0, 0, 0, 1;
    }
    m.udp_port_lidar = integer(field(j, "config_params", "udp_port_lidar"), 7502, "udp_port_lidar", name);
    if (const Json* p = field(j, "sensor_info", "prod_line"); p && p->is_string()) m.prod_line = p->get<std::string>();
    return m;
}

OusterReturns parse_ouster_returns(std::string_view name) {
    if (name == "first") return OusterReturns::First;
    if (name == "both") return OusterReturns::Both;
    throw InvalidArgument("returns must be first or both, not '" + std::string(name) + "'");
}

std::string describe_ouster(const OusterMetadata& m) {
    return "Ouster " + (m.prod_line.empty() ? std::string("sensor") : m.prod_line) + ", " + std::string(ouster_profile_name(m.profile)) + ", " +
           std::to_string(m.pixels_per_column) + " x " + std::to_string(m.columns_per_frame);
}

OusterMetadata read_ouster_metadata(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path.string() + ": cannot open the Ouster metadata");
    std::ostringstream s;
    s << in.rdbuf();
    return parse_ouster_metadata(s.str(), path.string());
}

OusterSweeps::OusterSweeps(OusterMetadata metadata, OusterReturns returns) : meta_(std::move(metadata)), returns_(returns) {
    const int w = meta_.columns_per_frame, h = meta_.pixels_per_column;
    direction_.resize(static_cast<std::size_t>(w) * h);
    offset_.resize(direction_.size());
    const Eigen::Matrix3d rot = meta_.lidar_to_sensor.topLeftCorner<3, 3>();
    const Eigen::Vector3d shift = meta_.lidar_to_sensor.topRightCorner<3, 1>() * 1e-3;
    const double bx = meta_.beam_offset_x_mm * 1e-3, bz = meta_.beam_offset_z_mm * 1e-3;
    const double beam_length = std::hypot(bx, bz);
    for (int c = 0; c < w; ++c) {
        const double encoder = 2 * M_PI * (1.0 - static_cast<double>(c) / w);  // the encoder turns clockwise
        for (int b = 0; b < h; ++b) {
            const double azimuth = encoder - meta_.azimuth_deg[b] * M_PI / 180;
            const double altitude = meta_.altitude_deg[b] * M_PI / 180;
            const Eigen::Vector3d dir(std::cos(azimuth) * std::cos(altitude), std::sin(azimuth) * std::cos(altitude), std::sin(altitude));
            // The beam leaves its origin, on the circle of radius bx at height bz; the range is
            // measured from the lidar origin, so the point is origin + (range - |b|) * dir.
            const Eigen::Vector3d start(bx * std::cos(encoder) - beam_length * dir.x(), bx * std::sin(encoder) - beam_length * dir.y(),
                                        bz - beam_length * dir.z());
            const std::size_t i = static_cast<std::size_t>(c) * h + b;
            direction_[i] = rot * dir;
            offset_[i] = rot * start + shift;
        }
    }
    sweep_.origin = shift;
}

bool OusterSweeps::add(std::span<const std::uint8_t> packet, const std::string& where) {
    const std::size_t expected = meta_.packet_size();
    if (packet.size() != expected)
        throw FormatError(where + ": an Ouster lidar packet of " + std::to_string(packet.size()) + " bytes where the metadata's " +
                          std::string(ouster_profile_name(meta_.profile)) + " profile with " + std::to_string(meta_.pixels_per_column) +
                          " beams makes " + std::to_string(expected) + " (metadata of another sensor or mode?)");
    const bool legacy = meta_.profile == OusterProfile::Legacy;
    const std::size_t column_bytes = (packet.size() - (legacy ? 0 : kPacketHeader + kPacketFooter)) / meta_.columns_per_packet;
    const std::uint8_t* first = packet.data() + (legacy ? 0 : kPacketHeader);
    std::uint32_t frame = 0;
    if (legacy)
        frame = get_le<std::uint16_t>(first + 10);
    else if (meta_.profile == OusterProfile::FusaDual)
        frame = get_le<std::uint32_t>(packet.data() + 4);
    else
        frame = get_le<std::uint16_t>(packet.data() + 2);
    bool closed = false;
    if (frame_id_ && *frame_id_ != frame) {
        close_sweep();
        closed = true;
    }
    frame_id_ = frame;
    for (int c = 0; c < meta_.columns_per_packet; ++c) {
        const std::uint8_t* col = first + c * column_bytes;
        const auto stamp = get_le<std::uint64_t>(col);
        const int id = get_le<std::uint16_t>(col + 8);
        const bool valid = legacy ? get_le<std::uint32_t>(col + column_bytes - kLegacyColumnFooter) == 0xffffffffu
                                  : (get_le<std::uint16_t>(col + 10) & 1u) != 0;
        if (!valid) continue;  // a column the sensor did not fire (outside the window, or dropped)
        if (id >= meta_.columns_per_frame)
            throw FormatError(where + ": Ouster column " + std::to_string(c) + " has measurement id " + std::to_string(id) +
                              " in a frame of " + std::to_string(meta_.columns_per_frame) + " columns");
        if (seen_.empty()) seen_.assign(static_cast<std::size_t>(meta_.columns_per_frame), 0);
        if (seen_[id]) continue;  // a repeated column (a packet sent twice)
        seen_[id] = 1;
        ++columns_seen_;
        convert_column(col + (legacy ? kLegacyColumnHeader : kColumnHeader), id, stamp);
    }
    return closed;
}

void OusterSweeps::convert_column(const std::uint8_t* pixels, int id, std::uint64_t stamp_ns) {
    const auto& l = layout_of(meta_.profile);
    const int h = meta_.pixels_per_column;
    const int returns = returns_ == OusterReturns::Both ? meta_.returns() : 1;
    for (int b = 0; b < h; ++b) {
        const std::uint8_t* px = pixels + b * l.pixel_bytes;
        const std::size_t i = static_cast<std::size_t>(id) * h + b;
        for (int r = 0; r < returns; ++r) {
            // Range and calibrated reflectivity, where each profile puts them (Ouster's firmware
            // user manual, "Lidar Data Format").
            std::uint32_t range_mm = 0, reflectivity = 0;
            switch (meta_.profile) {
                case OusterProfile::Legacy:
                    range_mm = get_le<std::uint32_t>(px) & 0xfffffu, reflectivity = get_le<std::uint16_t>(px + 4);
                    break;
                case OusterProfile::Single: range_mm = get_le<std::uint32_t>(px) & 0x7ffffu, reflectivity = px[4]; break;
                case OusterProfile::Dual: range_mm = get_le<std::uint32_t>(px + 4 * r) & 0x7ffffu, reflectivity = px[4 * r + 3]; break;
                case OusterProfile::LowData: range_mm = (get_le<std::uint16_t>(px) & 0x7fffu) << 3, reflectivity = px[2]; break;
                case OusterProfile::FusaDual:
                    range_mm = (get_le<std::uint16_t>(px + 4 * r) & 0x7fffu) << 3, reflectivity = px[4 * r + 2];
                    break;
            }
            if (range_mm == 0) {
                if (r == 0) sweep_.no_return.push_back(direction_[i].cast<float>());
                continue;
            }
            sweep_.cloud.points.push_back(offset_[i] + 1e-3 * range_mm * direction_[i]);
            sweep_.cloud.rings.push_back(static_cast<std::uint16_t>(b));
            sweep_.cloud.intensities.push_back(static_cast<float>(reflectivity));
            column_stamp_.push_back(stamp_ns);
        }
    }
}

void OusterSweeps::close_sweep() {
    if (columns_seen_ == 0) return;
    const std::uint64_t first = column_stamp_.empty() ? 0 : *std::min_element(column_stamp_.begin(), column_stamp_.end());
    sweep_.stamp_ns = static_cast<std::int64_t>(first);  // ns since the sensor's epoch (2^63 ns is 292 years)
    sweep_.times.resize(column_stamp_.size());
    for (std::size_t i = 0; i < column_stamp_.size(); ++i) sweep_.times[i] = static_cast<float>(1e-9 * static_cast<double>(column_stamp_[i] - first));
    sweep_.frame_id = "os_sensor";
    sweep_.index = count_++;
    sweep_.completeness = std::min(1.0, static_cast<double>(columns_seen_) / meta_.window_columns());
    done_ = std::move(sweep_);
    sweep_ = RecordedScan{};
    sweep_.origin = meta_.lidar_to_sensor.topRightCorner<3, 1>() * 1e-3;
    column_stamp_.clear();
    std::fill(seen_.begin(), seen_.end(), 0);
    columns_seen_ = 0;
}

bool OusterSweeps::finish() {
    close_sweep();
    frame_id_.reset();
    return done_.has_value();
}

RecordedScan OusterSweeps::take() {
    RecordedScan out = std::move(*done_);
    done_.reset();
    return out;
}

}  // namespace lidarsurf
