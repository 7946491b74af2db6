#pragma once
// Sparse voxel grid of size alpha holding VoxelStats (Sec. III-A).
//
// Storage is blocked: a hash map of 8x8x8 dense blocks of indices into a flat array of
// statistics, so that box queries over H^k(v) read contiguous memory. Statistics are kept in a
// local frame (world minus `origin`, a multiple of alpha chosen from the first point) so that
// coordinates far from the world origin (UTM maps, 1e6 m) keep full precision.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/voxel_key.hpp"
#include "lidarsurf/core/voxel_stats.hpp"

namespace lidarsurf {

class VoxelGrid {
public:
    static constexpr int kBlockBits = 3;
    static constexpr int kBlockSize = 1 << kBlockBits;  // 8 voxels per block side
    static constexpr int kBlockVolume = kBlockSize * kBlockSize * kBlockSize;

    /// Creates an empty grid of voxel size `alpha` (metres, must be finite and > 0). The local
    /// origin is `origin` rounded to the lattice if given, else the lattice point nearest the first
    /// inserted point.
    explicit VoxelGrid(double alpha, const std::optional<Eigen::Vector3d>& origin = std::nullopt);

    double voxel_size() const { return alpha_; }

    /// World position of local coordinate 0 (a multiple of alpha); set by the first insert.
    const Eigen::Vector3d& origin() const { return origin_; }
    bool has_origin() const { return origin_set_; }

    /// Inserts one world point. Throws InvalidInput if it is not finite or falls outside the
    /// grid's index range (+-2^20 voxels around the first point).
    void insert(const Eigen::Vector3d& world_point);

    /// Index of the voxel containing a local-frame point.
    VoxelKey key_of_local(const Eigen::Vector3d& local_point) const;

    /// Statistics of a voxel (local frame), or nullptr if empty.
    const VoxelStats* find(const VoxelKey& key) const;

    /// Calls f(key, stats) for each occupied voxel with lo <= key <= hi (inclusive box).
    template <typename F>
    void for_each_in_box(const VoxelKey& lo, const VoxelKey& hi, F&& f) const;

    /// Number of occupied voxels.
    std::size_t size() const { return stats_.size(); }
    const std::vector<VoxelKey>& keys() const { return keys_; }
    const std::vector<VoxelStats>& stats() const { return stats_; }

    /// Total number of points inserted.
    std::uint64_t point_count() const { return points_; }

    /// Converts between world and local coordinates.
    Eigen::Vector3d to_local(const Eigen::Vector3d& world) const { return world - origin_; }
    Eigen::Vector3d to_world(const Eigen::Vector3d& local) const { return local + origin_; }

private:
    using Block = std::array<std::int32_t, kBlockVolume>;  // -1 = empty voxel

    static int local_index(const VoxelKey& key) {
        const int m = kBlockSize - 1;
        return (key.x() & m) | ((key.y() & m) << kBlockBits) | ((key.z() & m) << (2 * kBlockBits));
    }
    static VoxelKey block_of(const VoxelKey& key) {
        return {key.x() >> kBlockBits, key.y() >> kBlockBits, key.z() >> kBlockBits};
    }
    const Block* find_block(const VoxelKey& block_key) const;

    double alpha_;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    bool origin_set_ = false;
    std::uint64_t points_ = 0;
    std::unordered_map<VoxelKey, std::unique_ptr<Block>, VoxelKeyHash> blocks_;
    std::vector<VoxelKey> keys_;
    std::vector<VoxelStats> stats_;
};

template <typename F>
void VoxelGrid::for_each_in_box(const VoxelKey& lo, const VoxelKey& hi, F&& f) const {
    const VoxelKey blo = block_of(lo), bhi = block_of(hi);
    for (int bz = blo.z(); bz <= bhi.z(); ++bz)
        for (int by = blo.y(); by <= bhi.y(); ++by)
            for (int bx = blo.x(); bx <= bhi.x(); ++bx) {
                const Block* block = find_block({bx, by, bz});
                if (!block) continue;
                const int x0 = std::max(lo.x(), bx * kBlockSize), x1 = std::min(hi.x(), bx * kBlockSize + kBlockSize - 1);
                const int y0 = std::max(lo.y(), by * kBlockSize), y1 = std::min(hi.y(), by * kBlockSize + kBlockSize - 1);
                const int z0 = std::max(lo.z(), bz * kBlockSize), z1 = std::min(hi.z(), bz * kBlockSize + kBlockSize - 1);
                for (int z = z0; z <= z1; ++z)
                    for (int y = y0; y <= y1; ++y)
                        for (int x = x0; x <= x1; ++x) {
                            const VoxelKey key{x, y, z};
                            const std::int32_t idx = (*block)[local_index(key)];
                            if (idx >= 0) f(key, stats_[static_cast<std::size_t>(idx)]);
                        }
            }
}

}  // namespace lidarsurf
