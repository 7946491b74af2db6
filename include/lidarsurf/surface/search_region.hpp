#pragma once
// The part of the lattice a surface search is kept to (SearchRegion): what the live mesh
// re-meshes of a large map, and what a tile of a map meshes (compute_seeded_tsdf's `region`).
#include <cstdint>
#include <span>
#include <vector>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/voxel_key.hpp"

namespace lidarsurf {

/// A part of the lattice the surface search is kept to: per 8^3 block of cubes, the mask of
/// the cubes in it (cube i = the cube with minimum corner i, BlockMask layout). What a live mesh
/// re-meshes of a large map: some blocks, and a margin of cubes around them so that the surface
/// reaching them from their neighbours is found.
class SearchRegion {
public:
    /// The blocks `core` (block keys) whole, and the cubes within `halo` cubes (Chebyshev
    /// distance, >= 0) of them.
    static SearchRegion around(std::span<const VoxelKey> core, int halo);
    /// Adds the cubes of `mask` in block `block`.
    void add(const VoxelKey& block, const BlockMask& mask);
    bool contains(const VoxelKey& cube) const {
        const std::uint32_t i = index_.find(BlockMap<std::int32_t>::block_of(cube));
        if (i == BlockIndex::kAbsent) return false;
        const int offset = BlockMap<std::int32_t>::offset_of(cube);
        return (masks_[i][static_cast<std::size_t>(offset >> 6)] >> (offset & 63)) & 1u;
    }
    const std::vector<VoxelKey>& blocks() const { return blocks_; }
    const BlockMask& mask(std::size_t i) const { return masks_[i]; }

private:
    BlockIndex index_;
    std::vector<VoxelKey> blocks_;
    std::vector<BlockMask> masks_;
};

}  // namespace lidarsurf
