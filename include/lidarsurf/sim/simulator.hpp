#pragma once
// Drives a sensor through a World: frame i of n is taken at the fraction i / (n - 1) of the drive
// (the paper's "100 equi-sampled frames"), with the moving objects where they are at that time.
// Each frame has the noisy scan and, optionally, the co-located noise-free ground-truth scan.
#include <optional>
#include <cstdint>
#include <vector>

#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/sim/mesh_scene.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"

namespace lidarsurf::sim {

struct SimulatorConfig {
    int frames = 100;
    SensorModel sensor = SensorModel::hdl64();
    int gt_beams = 316;          ///< beams of the ground-truth sensor (0 = no ground truth)
    std::uint64_t seed = 1;      ///< noise seed; frame i uses a seed derived from it and i
    /// 0: every ray of a frame is cast at the frame's instant. > 0: the sensor turns once in this
    /// many seconds while the rig drives on: each azimuth step is cast from where the rig is when
    /// the step fires, and reported in the sensor frame of that moment (a spinning lidar's sweep,
    /// its seam at azimuth 0, ahead). The ground truth stays instantaneous.
    double sweep_seconds = 0;

    void validate() const;
};

struct SimulatedFrame {
    std::size_t index = 0;
    double time = 0;             ///< seconds since the start of the drive
    Eigen::Isometry3d pose;      ///< sensor-to-world
    PointCloud scan;             ///< sensor frame
    PointCloud ground_truth;     ///< sensor frame; empty when gt_beams = 0
    Mesh movers;                 ///< the moving objects at `time`, world frame
    std::vector<float> times;    ///< with sweep_seconds > 0: per point of `scan`, seconds after `time`
};

class Simulator {
public:
    Simulator(World world, SimulatorConfig config);
    std::size_t frame_count() const { return static_cast<std::size_t>(config_.frames); }
    /// Fraction of the drive at which frame i is taken.
    double fraction(std::size_t index) const;
    /// The sensor's pose (sensor-to-world) at `seconds` since the start of the drive (held at the
    /// end after it).
    Eigen::Isometry3d pose_at_time(double seconds) const;
    /// Simulates frame `index` (< frame_count()). Thread-safe; parallel inside.
    SimulatedFrame frame(std::size_t index) const;

    const World& world() const { return world_; }
    const SimulatorConfig& config() const { return config_; }
    SensorModel ground_truth_sensor() const;

private:
    World world_;
    SimulatorConfig config_;
    MeshScene static_scene_;
    std::optional<MeshScene> dark_scene_;  // the world's dark surfaces: a ray that hits one first returns nothing
};

}  // namespace lidarsurf::sim
