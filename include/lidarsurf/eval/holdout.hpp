#pragma once
// The hold-out check for real scans without ground truth (Sec. IV-D): split a scan at random
// (seeded), reconstruct from one part, measure against the other.
#include <cstdint>

#include "lidarsurf/io/point_cloud.hpp"

namespace lidarsurf {

struct HoldoutSplit {
    PointCloud kept;      ///< used for the reconstruction
    PointCloud held_out;  ///< used as ground truth
};

/// Moves round(fraction * N) points of `cloud`, chosen uniformly at random with `seed`, to
/// held_out; the rest, in their original order, to kept. Disjoint, covering, reproducible for a
/// seed on every platform (std::mt19937_64 with its own bounded draw). fraction must be in (0, 1).
HoldoutSplit split_holdout(const PointCloud& cloud, double fraction, std::uint64_t seed);

}  // namespace lidarsurf
