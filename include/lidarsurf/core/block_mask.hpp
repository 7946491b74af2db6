#pragma once
// Bit masks over one 8x8x8 block of the lattice (the layout of VoxelGrid::occupancy): one 64-bit
// word per z layer, bit x + 8 y. Used to find, per block and in parallel, the lattice points near
// occupied voxels (the seeds of the surface search) without visiting them one by one.
#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "lidarsurf/core/voxel_grid.hpp"

namespace lidarsurf {

using BlockMask = std::array<std::uint64_t, 8>;

/// Calls f(offset) for every set bit of `mask`, in increasing offset (x fastest, then y, then z,
/// as BlockMap::offset_of).
template <typename F>
void for_each_bit(const BlockMask& mask, F&& f) {
    for (int z = 0; z < 8; ++z)
        for (std::uint64_t bits = mask[static_cast<std::size_t>(z)]; bits; bits &= bits - 1)
            f(std::countr_zero(bits) | (z << 6));
}

inline int popcount(const BlockMask& mask) {
    int n = 0;
    for (std::uint64_t w : mask) n += std::popcount(w);
    return n;
}

/// The lattice points p of block `block` with p in [i + lo, i + hi] (per axis, lo <= hi) for some
/// occupied voxel i of `grid`: the occupancy dilated by the box [lo, hi]^3.
BlockMask dilated_occupancy(const VoxelGrid& grid, const VoxelKey& block, int lo, int hi);

/// The blocks that dilated_occupancy(grid, block, lo, hi) can make non-empty, each once, in a
/// deterministic order (that of the grid's blocks).
std::vector<VoxelKey> blocks_near_occupancy(const VoxelGrid& grid, int lo, int hi);

struct MaskedBlock {
    VoxelKey block;
    BlockMask mask;
};
/// The whole dilated occupancy: every non-empty dilated_occupancy mask, in the order of
/// blocks_near_occupancy, computed in parallel.
std::vector<MaskedBlock> dilated_occupancy(const VoxelGrid& grid, int lo, int hi);

}  // namespace lidarsurf
