#pragma once
// A point cloud as read from a file: positions, the intensity of each point when the file has
// one, and the ring of each point when asked for (other fields are ignored by the readers).
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

struct PointCloud {
    std::vector<Eigen::Vector3d> points;
    std::vector<std::uint16_t> rings = {};  ///< empty, or the laser ring of each point
    /// empty, or the intensity of each point (reflectance, reflectivity: the sensor's unit)
    std::vector<float> intensities = {};
};

/// Ring numbers are whole numbers in [0, kMaxRing].
inline constexpr std::uint16_t kMaxRing = 4095;

/// `value` as a ring number; nullopt when it is not a whole number in [0, kMaxRing].
inline std::optional<std::uint16_t> ring_number(double value) {
    if (!(value >= 0 && value <= kMaxRing && value == std::floor(value))) return std::nullopt;
    return static_cast<std::uint16_t>(value);
}

/// Removes points with a NaN or infinite coordinate (and their rings and intensities); returns how many were removed.
std::size_t drop_non_finite(PointCloud& cloud);

}  // namespace lidarsurf
