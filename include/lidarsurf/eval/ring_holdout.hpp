#pragma once
// The ring hold-out check for real scans: mesh a scan from its even rings only and measure how
// far the odd-ring points, never seen by the mesher, lie from the mesh. Unlike a random hold-out,
// which leaves every ring in place, it measures how well the surface fills the space between
// rings (docs/evaluation.md).
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

/// Ring of each point of a scan stored ring after ring, each ring one revolution (KITTI's
/// HDL-64E order): a ring ends where the azimuth atan2(y, x), swept in either direction, passes
/// the azimuth of the scan's last point (the end of the last ring: every ring is cut there), or
/// turns back by more than 20 degrees (a ring that saw only part of the revolution). Rings are
/// numbered 0, 1, ... in file order. Throws InvalidInput for a scan whose consecutive points do
/// not sweep the azimuth (not ring-ordered), with no restart, or with more than kMaxRing + 1 rings.
std::vector<std::uint16_t> rings_from_order(std::span<const Eigen::Vector3d> points);
inline std::vector<std::uint16_t> rings_from_order(const PointCloud& cloud) { return rings_from_order(std::span<const Eigen::Vector3d>(cloud.points)); }

struct RingSplit {
    PointCloud even;  ///< points of even rings: reconstructed
    PointCloud odd;   ///< points of odd rings: held out
    std::size_t rings = 0;  ///< distinct ring numbers seen
};

/// Splits `cloud` by the parity of `rings` (one per point; InvalidInput otherwise, or when either
/// part is empty). Each part keeps the file order.
RingSplit split_rings(const PointCloud& cloud, const std::vector<std::uint16_t>& rings);

struct RingHoldoutConfig {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< sensor position
    double max_range = 30.0;         ///< held-out points farther than this from origin are ignored
    double range_bin = 10.0;         ///< width of the range bins (metres)
    std::vector<double> thresholds = {0.05, 0.1};  ///< reported shares within these (metres)
    int threads = 0;                 ///< 0 = all cores

    /// Throws InvalidArgument naming the first bad field.
    void validate() const;
};

/// Distances of held-out points to the mesh surface, summarised.
struct HoldoutDistances {
    double lo = 0, hi = 0;       ///< range interval (metres)
    std::size_t count = 0;
    std::vector<double> within;  ///< share within each RingHoldoutConfig::thresholds entry
    double mean = 0, median = 0, p90 = 0;
};

struct RingHoldoutResult {
    std::size_t rings = 0;          ///< rings in the scan (0 when measure_ring_holdout was called alone)
    std::size_t reconstructed = 0;  ///< even-ring points given to the mesher
    std::size_t held_out = 0;       ///< odd-ring points (all ranges)
    std::size_t mesh_triangles = 0;
    std::vector<double> thresholds;
    HoldoutDistances all;                  ///< every held-out point within max_range
    std::vector<HoldoutDistances> by_range;  ///< [0, bin), [bin, 2 bin), ... up to max_range
};

/// Exact point-to-surface distances of `held_out` (within max_range of origin) to `mesh`.
/// Throws InvalidInput when the mesh has no triangle or no held-out point lies within range.
RingHoldoutResult measure_ring_holdout(const Mesh& mesh, const std::vector<Eigen::Vector3d>& held_out,
                                       const RingHoldoutConfig& config);

/// The whole check: rings from cloud.rings when present, else from the point order
/// (rings_from_order); `reconstruct` meshes the even rings; the odd rings are measured.
RingHoldoutResult ring_holdout(const PointCloud& cloud, const std::function<Mesh(const PointCloud&)>& reconstruct,
                               const RingHoldoutConfig& config);

}  // namespace lidarsurf
