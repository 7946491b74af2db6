#pragma once
// Ouster lidar packets: the sensor's metadata JSON and the UDP lidar packets of every profile
// the SDK records (LEGACY, RNG19_RFL8_SIG16_NIR16 and its _DUAL, RNG15_RFL8_NIR8,
// FUSA_RNG15_RFL8_NIR8_DUAL), assembled into sweeps. The pixel-to-point model is the one of
// Ouster's firmware manual: a beam leaves its origin on a circle of radius
// lidar_origin_to_beam_origin around the encoder axis, at the beam's altitude and azimuth offset.
// Each point keeps its pixel's calibrated reflectivity as its intensity (0-255; LEGACY: 16 bits).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/io/recorded_scan.hpp"

namespace lidarsurf {

enum class OusterProfile { Legacy, Single, Dual, LowData, FusaDual };

/// "LEGACY", "RNG19_RFL8_SIG16_NIR16", ... (the metadata's udp_profile_lidar).
std::string_view ouster_profile_name(OusterProfile profile);

struct OusterMetadata {
    OusterProfile profile = OusterProfile::Legacy;
    int pixels_per_column = 0;
    int columns_per_packet = 16;
    int columns_per_frame = 0;
    int column_first = 0;  ///< column_window: the columns the sensor sends
    int column_last = 0;
    double frequency_hz = 10;
    std::vector<double> altitude_deg;  ///< per beam
    std::vector<double> azimuth_deg;   ///< per beam
    double beam_offset_x_mm = 0;       ///< beam origin: distance from the encoder axis
    double beam_offset_z_mm = 0;       ///< beam origin: height above the lidar origin
    Eigen::Matrix4d lidar_to_sensor = Eigen::Matrix4d::Identity();  ///< translation in mm
    int udp_port_lidar = 7502;
    std::string prod_line;

    /// Bytes of one lidar packet of this profile.
    std::size_t packet_size() const;
    /// Columns of one sweep (the column window's).
    int window_columns() const;
    /// Returns per pixel: 2 for the dual-return profiles, else 1.
    int returns() const;
};

/// Parses the metadata JSON of the sensor (the SDK's flat layout of firmware 2.x and the nested
/// layout of firmware 3.x). Throws FormatError naming `name` when a field is missing or
/// inconsistent (beam counts, column window, profile unknown).
OusterMetadata parse_ouster_metadata(std::string_view json, const std::string& name);
OusterMetadata read_ouster_metadata(const std::filesystem::path& path);

enum class OusterReturns { First, Both };

/// "first" or "both"; throws InvalidArgument otherwise.
OusterReturns parse_ouster_returns(std::string_view name);
/// "Ouster OS-1-64, LEGACY, 64 x 1024": the sensor, for reports.
std::string describe_ouster(const OusterMetadata& metadata);

/// Turns the lidar packets of one sensor into sweeps. A sweep ends when a packet of another
/// frame id arrives (or at finish()); the partial sweeps at a recording's ends are kept, with
/// their completeness.
class OusterSweeps {
public:
    explicit OusterSweeps(OusterMetadata metadata, OusterReturns returns = OusterReturns::First);
    /// Adds one lidar packet. `where` names it in errors (file and packet index). Returns true
    /// when the packet closed a sweep, which take() then gives. Throws FormatError for a packet
    /// of the wrong size or a column outside the frame.
    bool add(std::span<const std::uint8_t> packet, const std::string& where);
    /// Closes the sweep in progress; true if it had any column.
    bool finish();
    RecordedScan take();
    const OusterMetadata& metadata() const { return meta_; }

private:
    void close_sweep();
    void convert_column(const std::uint8_t* column, int measurement_id, std::uint64_t stamp_ns);

    OusterMetadata meta_;
    OusterReturns returns_;
    std::vector<Eigen::Vector3d> direction_;  ///< per (column, beam): unit ray in the sensor frame
    std::vector<Eigen::Vector3d> offset_;     ///< per (column, beam): the ray's start (m)
    std::optional<std::uint32_t> frame_id_;
    std::vector<std::uint64_t> column_stamp_;  ///< per point of the sweep in progress: its column's time (ns)
    std::vector<std::uint8_t> seen_;          ///< per column of the frame
    int columns_seen_ = 0;
    RecordedScan sweep_;
    std::optional<RecordedScan> done_;
    std::size_t count_ = 0;
};

}  // namespace lidarsurf
