#pragma once
// Sparse voxel grid of size alpha holding VoxelStats (Sec. III-A).
//
// Storage is blocked: 8x8x8 blocks, each with a word of occupancy bits per z layer and the
// indices into a flat array of statistics of its occupied voxels only, in bit order: a voxel's
// index is found by its rank among the block's occupancy bits (about 50 voxels on a block of a
// drive's map: 4 bytes each instead of 2 KiB for every block's 512 cells). Statistics are kept in a
// local frame (world minus `origin`, a multiple of alpha chosen from the first point) so that
// coordinates far from the world origin (UTM maps, 1e6 m) keep full precision.
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/voxel_key.hpp"
#include "lidarsurf/core/voxel_stats.hpp"

namespace lidarsurf {

/// Bits x0..x1 of every row of an 8x8 layer (bit x + 8 y, the layout of VoxelGrid::Occupancy and
/// BlockMask), 0 <= x0 <= x1 < 8.
inline std::uint64_t layer_columns(int x0, int x1) { return ((0xffu >> (7 - (x1 - x0))) << x0) * 0x0101010101010101ull; }
/// All the bits of the rows y0..y1 of an 8x8 layer (bytes y0..y1), 0 <= y0 <= y1 < 8.
inline std::uint64_t layer_rows(int y0, int y1) { return (~std::uint64_t{0} >> (8 * (7 - (y1 - y0)))) << (8 * y0); }
/// Bits x0..x1 of each of the rows y0..y1 of an 8x8 layer.
inline std::uint64_t layer_mask(int x0, int x1, int y0, int y1) { return layer_columns(x0, x1) & layer_rows(y0, y1); }
/// The set bits of `word` below bit `bit` (0 <= bit < 64), without a population-count instruction
/// (the portable x86-64 build has none, and std::popcount then calls a library routine).
inline int bits_below(std::uint64_t word, int bit) {
    std::uint64_t x = word & ((std::uint64_t{1} << bit) - 1);
    x -= (x >> 1) & 0x5555555555555555ull;
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return static_cast<int>((x * 0x0101010101010101ull) >> 56);
}

class VoxelGrid {
public:
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
    /// Inserts the finite points of `points`, in order, skipping (and counting) the others: the
    /// same grid, to the last bit, as inserting them one by one, built in parallel (keys, then the
    /// points of each voxel). Throws InvalidInput before changing the grid if a point falls
    /// outside the index range. Returns the number of non-finite points skipped.
    /// `viewpoint` (world) is where the points were seen from: required once viewpoints are
    /// enabled (InvalidArgument otherwise), ignored before.
    /// `hits`, when given, gets one entry per voxel the batch reached: the voxel's index into
    /// stats() and the index in `points` of its first point in the batch, by voxel index.
    struct Hit {
        std::uint32_t voxel = 0;
        std::uint32_t point = 0;
    };
    /// `intensity`, when not empty, holds one value per point (the return's intensity or
    /// reflectivity, InvalidArgument otherwise): the first such batch turns per-voxel intensity on
    /// for good, and each voxel then keeps the mean of its points' finite values (points without
    /// one, earlier or in batches without intensity, are not counted in it).
    std::size_t insert(std::span<const Eigen::Vector3d> points, const std::optional<Eigen::Vector3d>& viewpoint = std::nullopt,
                       std::vector<Hit>* hits = nullptr, std::span<const float> intensity = {});

    /// Empties voxel `voxel` (an index into stats()): its statistics and viewpoint are dropped, its
    /// block counts as touched, and the last voxel takes its index (keys() and stats() stay dense).
    /// Returns the index the moved voxel had (== `voxel` when it was the last). A later point in
    /// that voxel starts it afresh.
    std::size_t remove(std::size_t voxel);

    /// Viewpoints (sequences seen from several sensor positions): from now on each voxel also
    /// sums the sensor position of each of its points. The points already inserted are taken as
    /// seen from `earlier` (world). Throws InvalidArgument if `earlier` is not finite.
    void enable_viewpoints(const Eigen::Vector3d& earlier);
    bool has_viewpoints() const { return viewpoints_enabled_; }
    /// The point-weighted mean sensor position (local frame) of the occupied voxels with
    /// lo <= key <= hi, or nullopt when the box holds no point. Requires viewpoints.
    std::optional<Eigen::Vector3d> mean_viewpoint(const VoxelKey& lo, const VoxelKey& hi) const;

    /// Whether the voxels keep their points' mean intensity (a batch with intensity was inserted).
    bool has_intensity() const { return intensity_enabled_; }
    /// The mean intensity of the points of the occupied voxels with lo <= key <= hi that have
    /// one, or nullopt when there is none (or the grid keeps no intensity).
    std::optional<double> mean_intensity(const VoxelKey& lo, const VoxelKey& hi) const;
    /// The mean intensity of voxel `voxel` (an index into stats()) and how many points it is
    /// the mean of (0: none had one). Requires has_intensity().
    std::pair<float, std::uint32_t> voxel_intensity(std::size_t voxel) const { return {intensity_[voxel].mean, intensity_[voxel].count}; }

    /// Index of the voxel containing a local-frame point.
    VoxelKey key_of_local(const Eigen::Vector3d& local_point) const;
    /// The message for a point out of the lattice's range: its exact coordinates, and its index in
    /// the batch when known.
    std::string out_of_range_message(const Eigen::Vector3d& world, std::optional<std::size_t> index) const;

    /// Statistics of a voxel (local frame), or nullptr if empty.
    const VoxelStats* find(const VoxelKey& key) const;
    /// Index into stats() of the voxel `key`, or -1 if empty.
    std::int32_t voxel_at(const VoxelKey& key) const;
    /// The indices into stats() of the occupied voxels of block `block` (a creation index of
    /// index()), in the order of its occupancy bits (layer z, then bit x + 8 y).
    std::span<const std::int32_t> block_voxels(std::size_t block) const { return slots_[block].voxels; }

    /// Calls f(key, stats) for each occupied voxel with lo <= key <= hi (inclusive box), by block
    /// (z, y, x order), then by voxel (z, y, x order), skipping empty space through the occupancy bits.
    template <typename F>
    void for_each_in_box(const VoxelKey& lo, const VoxelKey& hi, F&& f) const {
        for_each_index_in_box(lo, hi, [&](const VoxelKey& key, std::size_t v) { f(key, stats_[v]); });
    }

    /// Number of occupied voxels.
    std::size_t size() const { return stats_.size(); }
    const std::vector<VoxelKey>& keys() const { return keys_; }
    const std::vector<VoxelStats>& stats() const { return stats_; }

    /// Total number of points inserted.
    std::uint64_t point_count() const { return points_; }

    /// Converts between world and local coordinates.
    Eigen::Vector3d to_local(const Eigen::Vector3d& world) const { return world - origin_; }
    Eigen::Vector3d to_world(const Eigen::Vector3d& local) const { return local + origin_; }

    /// Bytes held by the grid: index blocks, occupancy words, statistics and keys (capacities).
    std::size_t memory_bytes() const;
    /// How many voxels and blocks inserting `points` would add (a pass that changes nothing).
    std::pair<std::size_t, std::size_t> count_new(std::span<const Eigen::Vector3d> points) const;
    /// An upper bound of memory_bytes() after an insert of `batch` points adding `new_voxels`
    /// voxels in `new_blocks` blocks.
    std::size_t memory_bytes_after(std::size_t new_voxels, std::size_t new_blocks, std::size_t batch) const;

    /// The blocks (8x8x8 voxels, BlockMap's layout) holding a voxel or having held one, numbered
    /// in creation order: the numbers of occupancy() and block_voxels().
    const BlockKeys& index() const { return index_; }

    /// Occupancy bits of a block, one 64-bit word per z layer of the block: bit x + 8 y of
    /// word z is set when voxel (x, y, z) of the block is occupied. Lets box sums skip empty space
    /// 64 voxels at a time. `block` is a creation index of index().
    using Occupancy = std::array<std::uint64_t, 8>;
    const Occupancy& occupancy(std::size_t block) const { return occupancy_[block]; }

    /// Creation indices of the index blocks that received a point since the grid was made or
    /// since the last clear_touched(), each once, in the order they were first touched. What an
    /// incremental re-mesh must redo (Reconstructor::extract_mesh).
    const std::vector<std::uint32_t>& touched_blocks() const { return touched_; }
    void clear_touched();

    /// What happened to one index block since the last take_changes(): the journal a live mesh
    /// reads to decide what to re-mesh (map/block_changes.hpp), kept apart from touched_blocks()
    /// so that the two consumers do not clear each other's record.
    struct BlockChange {
        std::uint32_t block = 0;           ///< creation index of index()
        std::uint32_t points = 0;          ///< points inserted
        std::uint32_t new_voxels = 0;      ///< voxels created
        std::uint32_t removed_voxels = 0;  ///< voxels removed (remove())
        std::uint64_t removed_points = 0;  ///< the points those voxels held
    };
    /// Starts the journal (off by default: a batch fusion pays nothing for it).
    void track_changes();
    /// The blocks changed since the last call (or since track_changes()), each once, in the order
    /// they were first changed; empties the journal.
    std::vector<BlockChange> take_changes();

private:
    void set_origin_from(const Eigen::Vector3d& world);
    std::string out_of_range_message(const Eigen::Vector3d& world, std::optional<std::size_t> index, const Eigen::Vector3d& origin) const;
    // for_each_in_box with the voxel's index into stats_ instead of its statistics.
    template <typename F>
    void for_each_index_in_box(const VoxelKey& lo, const VoxelKey& hi, F&& f) const;
    /// Index of the voxel `key`, created if absent: its key is appended to keys_, and the caller
    /// extends stats_ to keys_.size() (once per batch rather than once per new voxel). Inline,
    /// the common case (a voxel already numbered in the previous point's block: nine in ten
    /// points of a KITTI frame); the others go through voxel_index_slow.
    std::int32_t voxel_index(const VoxelKey& key) {
        if (last_block_ && same_key(BlockMap<std::int32_t>::block_of(key), last_block_key_)) {
            const int offset = BlockMap<std::int32_t>::offset_of(key);
            const std::uint64_t word = (*last_occupancy_)[static_cast<std::size_t>(offset >> 6)];
            if ((word >> (offset & 63)) & 1u) return last_block_->at(offset >> 6, word, offset & 63);
        }
        return voxel_index_slow(key);
    }
    std::int32_t voxel_index_slow(const VoxelKey& key);
    // Makes block `block_key` (created if absent, marked touched) the cached last block.
    void cache_block(const VoxelKey& block_key);
    void touch(std::uint32_t block);
    // The journal's entry of block b (created on first use).
    BlockChange& change_of(std::uint32_t block);

    // The voxels of one block: their indices into stats_ in the order of the block's occupancy
    // bits, and how many lie in the layers below each layer.
    struct Slots {
        std::vector<std::int32_t> voxels;
        std::array<std::uint16_t, 8> before{};
        // The place in `voxels` of bit `bit` of layer `layer`, whose occupancy word is `word`.
        std::size_t rank(int layer, std::uint64_t word, int bit) const {
            return static_cast<std::size_t>(before[static_cast<std::size_t>(layer)]) + static_cast<std::size_t>(bits_below(word, bit));
        }
        // The voxel at bit `bit` of layer `layer` (bit set in `word`).
        std::int32_t at(int layer, std::uint64_t word, int bit) const { return voxels[rank(layer, word, bit)]; }
        std::int32_t& at(int layer, std::uint64_t word, int bit) { return voxels[rank(layer, word, bit)]; }
        // A voxel for the free bit `bit` of layer `layer` (occupancy word `word` before it is set).
        void insert(int layer, std::uint64_t word, int bit, std::int32_t voxel);
        // Drops the voxel at the set bit `bit` of layer `layer` (word before it is cleared).
        void erase(int layer, std::uint64_t word, int bit);
    };
    // The slot of the occupied voxel `key`.
    std::int32_t& slot_of(const VoxelKey& key);
    // Bytes held by the blocks' voxel lists (capacities).
    std::size_t slot_bytes() const;

    double alpha_;
    Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
    bool origin_set_ = false;
    std::uint64_t points_ = 0;
    BlockKeys index_;
    std::vector<Slots> slots_;  // per block, in creation order
    // The block of the previous insert: consecutive lidar returns mostly share a block.
    Slots* last_block_ = nullptr;
    Occupancy* last_occupancy_ = nullptr;
    VoxelKey last_block_key_ = VoxelKey::Zero();
    std::vector<Occupancy> occupancy_;  // per index block, in creation order
    std::vector<std::uint8_t> touched_flag_;  // per index block: in touched_
    std::vector<std::uint32_t> touched_;
    bool tracking_ = false;
    std::vector<std::uint32_t> change_slot_;  // per index block when tracking: its entry in changes_, or kNoChange
    std::vector<BlockChange> changes_;
    std::vector<VoxelKey> keys_;
    std::vector<VoxelStats> stats_;
    bool viewpoints_enabled_ = false;
    // Per voxel when enabled: the mean of its points' sensor positions (local frame; float: 1e-3 m at
    // 10 km, for orienting a plane toward the sensors that saw it).
    std::vector<Eigen::Vector3f> viewpoint_means_;
    bool intensity_enabled_ = false;
    // Per voxel when enabled: the mean intensity of its points that had one, and their count.
    struct IntensityMean {  // one voxel's: its returns' mean intensity and how many they are (side by side: one cache line)
        float mean = 0;
        std::uint32_t count = 0;
    };
    std::vector<IntensityMean> intensity_;
    // Adds the batch's intensities to the voxels of its runs (insert's step 4).
    void add_intensity(std::span<const float> intensity, std::span<const std::uint32_t> voxel, std::span<const std::uint32_t> order,
                       std::span<const std::size_t> runs);
};

template <typename F>
void VoxelGrid::for_each_index_in_box(const VoxelKey& lo, const VoxelKey& hi, F&& f) const {
    using Map = BlockMap<std::int32_t>;
    constexpr int B = Map::kSize, m = B - 1;
    const VoxelKey blo = Map::block_of(lo), bhi = Map::block_of(hi);
    for (int bz = blo.z(); bz <= bhi.z(); ++bz)
        for (int by = blo.y(); by <= bhi.y(); ++by)
            for (int bx = blo.x(); bx <= bhi.x(); ++bx) {
                const std::int64_t b = index_.index_of({bx, by, bz});
                if (b < 0) continue;
                const Slots& block = slots_[static_cast<std::size_t>(b)];
                const Occupancy& occupied = occupancy_[static_cast<std::size_t>(b)];
                const int x0 = std::max(lo.x(), bx * B), x1 = std::min(hi.x(), bx * B + m);
                const int y0 = std::max(lo.y(), by * B), y1 = std::min(hi.y(), by * B + m);
                const int z0 = std::max(lo.z(), bz * B), z1 = std::min(hi.z(), bz * B + m);
                const std::uint64_t mask = layer_mask(x0 & m, x1 & m, y0 & m, y1 & m);
                for (int z = z0; z <= z1; ++z) {
                    const std::uint64_t word = occupied[static_cast<std::size_t>(z & m)];
                    std::uint64_t bits = word & mask;
                    if (!bits) continue;
                    // The layer's voxels from the first one in the box, ranked as they come.
                    const int first = std::countr_zero(bits);
                    std::size_t rank = block.rank(z & m, word, first);
                    for (std::uint64_t all = word >> first << first; bits; all &= all - 1, ++rank) {
                        const int bit = std::countr_zero(all);
                        if (!((bits >> bit) & 1u)) continue;
                        bits &= bits - 1;
                        const VoxelKey key{bx * B + (bit & m), by * B + (bit >> 3), z};
                        f(key, static_cast<std::size_t>(block.voxels[rank]));
                    }
                }
            }
}

}  // namespace lidarsurf
