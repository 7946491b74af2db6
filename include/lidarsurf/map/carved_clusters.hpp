#pragma once
// Mostly carved clusters go whole (docs/method.md, "Free space"). Carving removes what rays went
// through; what no ray reaches (the roof of a car at the sensor's height, its far side, the rear
// of a car that follows) stays. Such a remnant is the rest of an object whose larger part was
// carved: its voxels and the carved ones form one connected cluster above the ground.
//
// The clusters: voxels face-connected above the ground, through the live voxels and the voxels
// carved in the last kMemoryScans scans (tombstones). The ground is what lies within kGroundBand
// of the lowest voxel in the kGroundCell-metre cells around (3 x 3): the road does not join
// everything that stands on it, and a car next to a wall joins the wall (too large to go).
// A cluster goes, its quiet voxels (not hit for kQuietScans scans: what is seen now stays),
// when the tombstones in it that were seen as late as its quiet voxels (kSlackScans) are at least
// `share` of the cluster: a car that stays is not taken with the trail of a walker who passed it
// earlier. A cluster larger than a car's surface, or reaching farther than kReach from where
// the search started, is not an object and stays.
#include <cstdint>
#include <functional>
#include <span>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/voxel_grid.hpp"

namespace lidarsurf {

class CarvedClusters {
public:
    static constexpr int kMemoryScans = 30;
    static constexpr int kQuietScans = 3;
    static constexpr int kSlackScans = 3;
    static constexpr double kGroundCell = 0.8;   // metres
    static constexpr double kGroundBand = 0.3;   // metres
    static constexpr double kMaxArea = 30;       // m^2 of surface: a car
    static constexpr double kReach = 6;          // metres

    /// `share` in (0, 1]: 1 never removes (a cluster is never all tombstones).
    CarvedClusters(double share, double voxel_size);

    bool enabled() const { return share_ < 1; }

    /// The voxels created by this scan, `from` on: the ground's height under them.
    void add_ground(const VoxelGrid& grid, std::size_t from, const std::function<float(std::size_t)>& mean_z);

    /// A voxel carved at scan `stamp`, last hit at `last_hit`, its mean at height `z` (local).
    /// Returns whether it is above the ground (a seed for follow()).
    bool bury(const VoxelKey& key, float z, std::uint32_t last_hit, std::uint32_t stamp);

    /// The live voxels of the clusters through `seeds` (keys buried this scan) that go.
    /// `last_hit(v)` and `mean_z(v)` read a live voxel's evidence.
    std::vector<std::uint32_t> follow(const VoxelGrid& grid, std::span<const VoxelKey> seeds, std::uint32_t stamp,
                                      const std::function<std::uint32_t(std::size_t)>& last_hit,
                                      const std::function<float(std::size_t)>& mean_z);

    std::size_t memory_bytes() const {
        return live_mark_.capacity() * sizeof(std::uint32_t) + tombs_.size() * (sizeof(VoxelKey) + sizeof(Tomb) + 2 * sizeof(void*)) + floor_.size() * (sizeof(std::uint64_t) + sizeof(float) + 2 * sizeof(void*));
    }

private:
    struct Tomb {
        std::uint32_t removed = 0, last_hit = 0;
        bool above = false;
        std::uint32_t mark = 0;  // the follow() call that visited it last
    };
    bool above_ground(const VoxelKey& key, float z) const;
    std::uint64_t cell_of(const VoxelKey& key) const;

    double share_;
    double alpha_;
    int cell_voxels_;
    std::size_t max_live_;
    std::unordered_map<VoxelKey, Tomb, VoxelKeyHash> tombs_;
    std::unordered_map<std::uint64_t, float> floor_;  // per cell (x, y), the lowest voxel mean around it (3 x 3 cells)
    std::uint32_t pruned_ = 0;
    std::uint32_t mark_ = 0;
    std::vector<std::uint32_t> live_mark_;  // per live voxel, the follow() call that visited it last
};

}  // namespace lidarsurf
