#pragma once
// Spinning multi-beam lidars as data: one ray per (beam elevation, azimuth step), Gaussian range
// noise, random dropouts. Presets for common sensors; any sensor can be read from JSON.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/map/empty_rays.hpp"
#include "lidarsurf/sim/ray_scene.hpp"

namespace lidarsurf::sim {

struct SensorModel {
    std::string name = "custom";
    std::vector<double> elevations_deg;  ///< one per beam
    double azimuth_step_deg = 0.18;
    double min_range = 1.0;
    double max_range = 120.0;
    double range_noise = 0.02;  ///< sigma of the range noise, metres
    double dropout = 0.0;       ///< probability that a return is lost
    /// sigma of the noise on each return's intensity (the surface's reflectivity, clamped to [0, 1])
    double intensity_noise = 0.02;
    double mount_height = 1.73; ///< metres above the ground where the rig carries it

    /// Throws InvalidArgument for an empty beam list, non-finite values, steps outside
    /// (0, 360], ranges not 0 <= min < max, noise < 0, intensity noise outside [0, 1] or dropout
    /// outside [0, 1).
    void validate() const;
    std::size_t rays_per_revolution() const;

    /// Velodyne HDL-64E as in KITTI: 64 beams evenly from +2 deg to -24.8 deg, 0.18 deg azimuth
    /// step (2,000 rays per beam per revolution), 120 m range, 2 cm range noise, 2 % dropouts.
    static SensorModel hdl64();
    /// Velodyne VLP-16: 16 beams +-15 deg, 0.2 deg step, 100 m, 3 cm noise.
    static SensorModel vlp16();
    /// Velodyne HDL-32E: 32 beams +10.67 to -30.67 deg, 0.16 deg step, 100 m, 2 cm noise.
    static SensorModel hdl32();
    /// Ouster OS1-128: 128 beams +-22.5 deg, 2048 columns, 120 m, 3 cm noise.
    static SensorModel os1_128();
    /// The paper's ground-truth sensor (Sec. IV-A): co-located with the HDL-64E, noise-free, 316
    /// beams over the same elevation span; 0.09 deg azimuth step.
    static SensorModel ground_truth();
    /// A ground-truth sensor for any sensor: same elevation span and range, `beams` beams,
    /// half its azimuth step (at most 0.09 deg), no noise (range or intensity), no dropout.
    static SensorModel ground_truth_for(const SensorModel& sensor, int beams = 316);

    /// A preset by name: hdl64, vlp16, hdl32, os1-128, gt316. Throws InvalidArgument otherwise.
    static SensorModel preset(std::string_view name);
    static std::vector<std::string> preset_names();

    /// JSON: {"name", "elevations_deg": [...] or "beams" + "elevation_max_deg" + "elevation_min_deg",
    /// "azimuth_step_deg", "min_range", "max_range", "range_noise", "intensity_noise", "dropout",
    /// "mount_height"};
    /// missing fields keep the defaults above. Throws FormatError on malformed JSON and
    /// InvalidArgument on bad values.
    static SensorModel from_json(std::string_view text);
    std::string to_json() const;

    /// Its firing pattern: the beams' elevations and the azimuth step.
    BeamPattern pattern() const { return {elevations_deg, azimuth_step_deg}; }
};

/// The pattern of the sensor of a drive `simulate` wrote, from its sensor.json (`path`); nullopt
/// when there is no such file. Throws FormatError / InvalidArgument as from_json, IoError when it
/// cannot be read.
std::optional<BeamPattern> drive_pattern(const std::filesystem::path& path);

/// Casts every ray of one revolution from a sensor at `pose` (sensor-to-world) and returns the
/// noisy hits in the sensor frame (x forward, y left, z up), with their intensities when the scene
/// knows its reflectivity everywhere a ray hit. Deterministic for a given seed, whatever the number
/// of threads: the noise of each ray is drawn from its own counter.
PointCloud simulate_scan(const RayScene& scene, const SensorModel& sensor, const Eigen::Isometry3d& pose,
                         std::uint64_t seed);

/// One revolution of a sensor that moves while it turns: azimuth step a (of rays_per_revolution()
/// / beams, counter-clockwise from x, the seam at azimuth 0) is cast from `step_poses[a]`. The hits
/// are in the sensor frame of their own step, as a spinning lidar reports them; `steps`, when
/// given, receives each point's step (its time is step / steps of the revolution).
PointCloud simulate_sweep(const RayScene& scene, const SensorModel& sensor, const std::vector<Eigen::Isometry3d>& step_poses,
                          std::uint64_t seed, std::vector<std::uint32_t>* steps = nullptr);
/// Azimuth steps of one revolution.
std::size_t azimuth_steps(const SensorModel& sensor);

/// Same, with the sensor axis-aligned at `origin`; returns world coordinates.
PointCloud simulate_scan(const RayScene& scene, const SensorModel& sensor, const Eigen::Vector3d& origin,
                         std::uint64_t seed);

}  // namespace lidarsurf::sim
