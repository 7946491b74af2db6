#pragma once
// A read-only snapshot of a VoxelGrid for the fast path's box sums. Per 8x8x8 block,
// the statistics of its occupied voxels are stored contiguously in offset order and found by
// their rank among the block's occupancy bits. Summing a box then reads the occupancy word it
// already needs and one compact record per voxel, next to its neighbours' records, instead of
// an index load and an 80-byte VoxelStats scattered in insertion order (the two cache misses
// that dominated the sums).
#include <array>
#include <bit>
#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "lidarsurf/core/voxel_grid.hpp"

namespace lidarsurf {

class PackedVoxels {
public:
    /// Number of set bits of each byte value.
    static constexpr std::array<std::uint8_t, 256> kBitCount = [] {
        std::array<std::uint8_t, 256> t{};
        for (int i = 1; i < 256; ++i) t[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>((i & 1) + t[static_cast<std::size_t>(i >> 1)]);
        return t;
    }();

    /// A voxel's VoxelStats in 10 doubles: count, mean, and the upper triangle of the scatter.
    struct Voxel {
        double count;
        double mx, my, mz;
        double xx, xy, xz, yy, yz, zz;
    };
    struct Block {
        const Voxel* voxels = nullptr;                ///< the block's occupied voxels, in offset order
        const VoxelGrid::Occupancy* occupancy = nullptr;
        std::uint8_t layers = 0;                      ///< bit z set when layer z holds a voxel
        std::array<std::uint16_t, 64> row_start{};    ///< rank of the first occupied voxel of row y + 8 z
        /// The record of the occupied voxel at `offset` (x + 8 y + 64 z, BlockMap::offset_of): its
        /// rank is the row's start plus the occupied voxels before x in the row (a byte table,
        /// as the portable x86-64 build has no popcount instruction).
        const Voxel& at(int offset) const {
            const int row = offset >> 3;
            const auto byte = static_cast<unsigned>(((*occupancy)[static_cast<std::size_t>(row >> 3)] >> (8 * (row & 7))) & 0xffu);
            return voxels[row_start[static_cast<std::size_t>(row)] + kBitCount[byte & ((1u << (offset & 7)) - 1u)]];
        }
        /// The same record as at(bit | layer << 6), ranked from the layer's first record and the
        /// occupied voxels before `bit` in the layer's word: for code built with a population-count
        /// instruction (core/simd.hpp's Avx2 level), where that is 3 instructions instead of ~20.
        [[gnu::always_inline]] const Voxel& at_layer_bit(int layer, int bit) const {
            const std::uint64_t before = (*occupancy)[static_cast<std::size_t>(layer)] & ((std::uint64_t{1} << bit) - 1);
            return voxels[row_start[static_cast<std::size_t>(layer << 3)] + std::popcount(before)];
        }
    };

    /// Snapshot of `grid` (which must outlive it and not change while it is used). Without
    /// `eager`, every block is copied here, in parallel. With `eager` (a flag per grid block, in
    /// creation order) only the flagged blocks are; the others are copied when find() first
    /// meets them, by the thread that does (others needing it meanwhile wait). An incremental
    /// re-mesh packs the blocks near the new points up front and the few others it reads lazily.
    explicit PackedVoxels(const VoxelGrid& grid, const std::vector<std::uint8_t>* eager = nullptr);
    /// Snapshot of the grid blocks `blocks` only (creation indices, each once), packed up front
    /// in parallel: find() answers nullptr for every other block, as for an empty one. What a
    /// region of a large map needs (SearchRegion), in time and memory that follow the region,
    /// not the map.
    PackedVoxels(const VoxelGrid& grid, std::span<const std::uint32_t> blocks);

    const VoxelGrid& grid() const { return *grid_; }
    /// The block with key `key`, or nullptr when it holds no voxel. Thread-safe.
    const Block* find(const VoxelKey& key) const {
        std::size_t i;
        if (subset_ || dense_.has_box()) {
            const std::uint32_t b = dense_.find(key);
            if (b == BlockIndex::kAbsent) return nullptr;
            i = b;
        } else {
            const std::int64_t b = grid_->index().index_of(key);
            if (b < 0) return nullptr;
            i = static_cast<std::size_t>(b);
        }
        if (state_[i].load(std::memory_order_acquire) != kPacked) pack_now(i);
        return &blocks_[i];
    }
    /// Blocks copied so far.
    std::size_t packed_blocks() const;
    /// Bytes held by the snapshot (records reserved for every block; pages of unpacked ones are
    /// not touched).
    std::size_t memory_bytes() const { return voxel_count_ * sizeof(Voxel) + blocks_.capacity() * (sizeof(Block) + 1) + dense_.memory_bytes(); }

    /// Whether find() reads a dense table of the blocks' bounding box instead of probing the
    /// grid's hash index (built when the box holds at most kDenseCellsPerBlock cells per block).
    bool dense() const { return dense_.has_box(); }
    static constexpr std::size_t kDenseCellsPerBlock = 64;

private:
    static constexpr std::uint8_t kUnpacked = 0, kBusy = 1, kPacked = 2;

    void pack(std::size_t b) const;      // copies block b's records and builds its ranks
    void pack_now(std::size_t b) const;  // packs block b, or waits for the thread packing it
    void allocate(std::size_t blocks);   // the blocks' headers and the room for their records
    void index_keys(const std::vector<VoxelKey>& keys);         // dense_: keys[b] -> b
    void pack_up_front(const std::vector<std::uint8_t>* eager);  // the flagged blocks (all without flags), in parallel
    // The creation index in the grid of this snapshot's block b.
    std::size_t in_grid(std::size_t b) const { return subset_ ? grid_blocks_[b] : b; }

    const VoxelGrid* grid_;
    std::size_t voxel_count_ = 0;
    std::unique_ptr<Voxel[]> voxels_;  // uninitialised: a block's records are written when it is packed
    std::vector<std::size_t> start_;   // first record of each block
    mutable std::vector<Block> blocks_;  // in the grid's block creation order
    std::unique_ptr<std::atomic<std::uint8_t>[]> state_;
    // The blocks' positions here by key, in a dense table of their box; without a box when the box
    // is too sparse (find() then probes the grid's index, or for a subset this hash).
    BlockIndex dense_;
    // Built from a subset of the blocks: dense_ (a box or a hash) maps their keys to their
    // positions in the subset, and grid_blocks_ to their creation indices in the grid.
    bool subset_ = false;
    std::vector<std::uint32_t> grid_blocks_;
};

}  // namespace lidarsurf
