#pragma once
// Velodyne lidar packets: the sensors' calibration (the YAML of the ROS velodyne driver, or the
// factory angles of the fixed-angle models built in) and the 1206-byte data packets of VLP-16,
// VLP-16 Hi-Res, VLP-32C, HDL-32E and HDL-64E (S2, S3), strongest, last and dual returns,
// assembled into sweeps cut where the azimuth wraps. The point model is the one of the sensors'
// manuals: a laser at its vertical angle and azimuth offset, with the HDL-64E's per-laser distance,
// vertical and horizontal offsets and its two-point distance correction. Each point keeps its
// channel's calibrated reflectivity byte (0-255) as its intensity.
#include <array>
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

/// The models lidarsurf decodes. The product byte of a packet (byte 1205) names the first four;
/// HDL-64E packets carry status bytes there and are known by their calibration's 64 lasers.
enum class VelodyneModel { VLP16, VLP16HiRes, VLP32C, HDL32E, HDL64E };

std::string_view velodyne_model_name(VelodyneModel model);

/// One laser's calibration, as the ROS velodyne driver's YAML gives it (angles in radians,
/// distances in metres).
struct VelodyneLaser {
    double vert_correction = 0;         ///< elevation
    double rot_correction = 0;          ///< azimuth offset (subtracted from the block's azimuth)
    double dist_correction = 0;         ///< added to every range
    double dist_correction_x = 0;       ///< two-point correction (HDL-64E): at 2.4 m in x ...
    double dist_correction_y = 0;       ///< ... and 1.93 m in y; dist_correction holds at 25.04 m
    bool two_pt_correction = false;
    double vert_offset_correction = 0;  ///< the laser's height above the sensor's origin
    double horiz_offset_correction = 0; ///< the laser's sideways offset from the spin axis
};

struct VelodyneCalibration {
    std::vector<VelodyneLaser> lasers;  ///< by laser id: channel j of a block is laser j (+32 for 0xDDFF blocks)
    double distance_resolution = 0.002; ///< metres per count
    std::string name;                   ///< the file, or "built-in VLP-16"

    /// Ring of each laser: its rank by elevation, 0 at the top (as Ouster beams are numbered).
    std::vector<std::uint16_t> rings() const;
};

/// Parses the ROS velodyne driver's calibration YAML (`lasers:` with laser_id, vert_correction,
/// rot_correction, ...; `distance_resolution`; `num_lasers`). Throws FormatError naming `name` when
/// the YAML is malformed, a laser id repeats or is missing, or a value is out of range.
VelodyneCalibration parse_velodyne_calibration(std::string_view yaml, const std::string& name);
VelodyneCalibration read_velodyne_calibration(const std::filesystem::path& path);
/// The manuals' factory angles of the fixed-angle models (VLP-16, VLP-16 Hi-Res, VLP-32C,
/// HDL-32E); nullopt for the HDL-64E, whose angles are measured per unit.
std::optional<VelodyneCalibration> velodyne_factory_calibration(VelodyneModel model);

/// The model a data packet's product byte names; nullopt for another byte (HDL-64E status bytes,
/// VLS-128, Velarray).
std::optional<VelodyneModel> velodyne_model_of_packet(std::span<const std::uint8_t> packet);
/// True when the datagram has a Velodyne data packet's size and block flags.
bool is_velodyne_data_packet(std::span<const std::uint8_t> packet);

/// Which returns of a dual-return recording are kept: the sensor's first block of each firing
/// (the last return on the VLP and HDL-32E models), or both (a second return that repeats the
/// first is dropped).
enum class VelodyneReturns { First, Both };

/// Turns the data packets of one sensor into sweeps. A sweep ends where the azimuth wraps past
/// 360 degrees (or at finish()); the partial sweeps at a recording's ends are kept, with their
/// completeness. Channels of range 0 are kept as rays that returned nothing.
class VelodyneSweeps {
public:
    /// Throws FormatError when the calibration's laser count does not fit the model. `return_mode`:
    /// byte 1204 of the recording's first packet, for description() before any packet is added.
    VelodyneSweeps(VelodyneModel model, VelodyneCalibration calibration, VelodyneReturns returns = VelodyneReturns::First,
                   int return_mode = 0);
    /// Adds one data packet captured at `capture_ns` (host clock). `where` names it in errors.
    /// Returns true when the packet closed a sweep, which take() then gives. Throws FormatError for
    /// a packet of the wrong size, a block flag the model does not send, an azimuth past 359.99
    /// degrees, or a product byte that names another model.
    bool add(std::span<const std::uint8_t> packet, std::int64_t capture_ns, const std::string& where);
    /// Closes the sweep in progress; true if it had any firing.
    bool finish();
    RecordedScan take();
    VelodyneModel model() const { return model_; }
    const VelodyneCalibration& calibration() const { return cal_; }
    /// "Velodyne VLP-16, strongest return, 16 lasers (built-in VLP-16)": for reports.
    std::string description() const;

private:
    struct Firing;
    void close_sweep();
    void add_firing(const Firing& f);
    const std::array<double, 2>* advance(int step);
    std::int64_t packet_time_ns(std::uint32_t stamp_us, std::int64_t capture_ns);

    VelodyneModel model_;
    VelodyneCalibration cal_;
    VelodyneReturns returns_;
    std::vector<std::uint16_t> ring_;
    std::vector<double> cos_vert_, sin_vert_;
    std::vector<std::array<double, 2>> turn_;  ///< advance(): per step, per (bank, channel)
    std::vector<char> turn_ready_;
    int return_mode_ = 0;  ///< the last packet's byte 1204 (0x37 strongest, 0x38 last, 0x39 dual), 0 unknown
    // The sensor's clock: its microseconds past the hour, unwrapped, and where they start.
    std::optional<std::uint32_t> last_stamp_us_;
    std::int64_t last_time_ns_ = 0;
    // The sweep in progress.
    std::optional<int> last_azimuth_;  ///< hundredths of a degree
    double covered_ = 0;               ///< hundredths of a degree the sweep's firings span
    double last_step_ = 0;             ///< the last firing's azimuth step
    std::size_t firings_ = 0;          ///< firings in the sweep
    std::vector<std::int64_t> point_time_;
    RecordedScan sweep_;
    std::optional<RecordedScan> done_;
    std::size_t count_ = 0;
};

}  // namespace lidarsurf
