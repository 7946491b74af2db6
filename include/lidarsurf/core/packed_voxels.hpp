#pragma once
// A read-only snapshot of a VoxelGrid for the fast path's box sums (issue 5). Per 8x8x8 block,
// the statistics of its occupied voxels are stored contiguously in offset order and found by
// their rank among the block's occupancy bits. Summing a box then reads the occupancy word it
// already needs and one compact record per voxel, next to its neighbours' records, instead of
// an index load and a 104-byte VoxelStats scattered in insertion order (the two cache misses
// that dominated the sums).
#include <array>
#include <cstdint>
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
        std::array<std::uint16_t, 64> row_start{};    ///< rank of the first occupied voxel of row y + 8 z
        /// The record of the occupied voxel at `offset` (x + 8 y + 64 z, BlockMap::offset_of): its
        /// rank is the row's start plus the occupied voxels before x in the row (a byte table,
        /// as the portable x86-64 build has no popcount instruction).
        const Voxel& at(int offset) const {
            const int row = offset >> 3;
            const auto byte = static_cast<unsigned>(((*occupancy)[static_cast<std::size_t>(row >> 3)] >> (8 * (row & 7))) & 0xffu);
            return voxels[row_start[static_cast<std::size_t>(row)] + kBitCount[byte & ((1u << (offset & 7)) - 1u)]];
        }
    };

    /// Snapshot of `grid` (which must outlive it and not change while it is used). Built in
    /// parallel per block. With `only`, a flag per grid block (creation order), only the flagged
    /// blocks are copied: an incremental re-mesh needs those near the new points.
    explicit PackedVoxels(const VoxelGrid& grid, const std::vector<std::uint8_t>* only = nullptr);

    const VoxelGrid& grid() const { return *grid_; }
    /// The block with key `key`, or nullptr when it holds no voxel. Throws InvalidArgument for a
    /// block of the grid that was left out of the snapshot (it would read as empty).
    const Block* find(const VoxelKey& key) const {
        const std::int64_t b = grid_->index().index_of(key);
        if (b < 0) return nullptr;
        const Block& block = blocks_[static_cast<std::size_t>(b)];
        if (!block.occupancy) left_out(key);
        return &block;
    }
    /// Bytes held by the snapshot.
    std::size_t memory_bytes() const { return voxels_.capacity() * sizeof(Voxel) + blocks_.capacity() * sizeof(Block); }

private:
    [[noreturn]] static void left_out(const VoxelKey& key);

    const VoxelGrid* grid_;
    std::vector<Voxel> voxels_;
    std::vector<Block> blocks_;  // in the grid's block creation order
};

}  // namespace lidarsurf
