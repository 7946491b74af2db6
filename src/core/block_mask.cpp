#include "lidarsurf/core/block_mask.hpp"

#include <algorithm>

#include <tbb/parallel_for.h>

namespace lidarsurf {

namespace {
using Map = BlockMap<std::int32_t>;
constexpr int B = Map::kSize;

// Floor division of a lattice coordinate by the block size (arithmetic shift).
int block_coord(int x) { return x >> Map::kBits; }
}  // namespace

BlockMask dilated_occupancy(const VoxelGrid& grid, const VoxelKey& block, int lo, int hi) {
    BlockMask mask{};
    // Voxel i reaches this block when [i + lo, i + hi] meets [8 b, 8 b + 7] on every axis.
    const VoxelKey first = block * B;
    const VoxelKey vlo = first.array() - hi, vhi = first.array() + (B - 1) - lo;
    for (int bz = block_coord(vlo.z()); bz <= block_coord(vhi.z()); ++bz)
        for (int by = block_coord(vlo.y()); by <= block_coord(vhi.y()); ++by)
            for (int bx = block_coord(vlo.x()); bx <= block_coord(vhi.x()); ++bx) {
                const std::int64_t b = grid.index().index_of({bx, by, bz});
                if (b < 0) continue;
                const VoxelGrid::Occupancy& occ = grid.occupancy(static_cast<std::size_t>(b));
                const VoxelKey origin(bx * B, by * B, bz * B);
                for (int z = 0; z < B; ++z) {
                    const int iz = origin.z() + z;
                    if (iz < vlo.z() || iz > vhi.z()) continue;
                    const int z0 = std::max(iz + lo, first.z()) - first.z(), z1 = std::min(iz + hi, first.z() + B - 1) - first.z();
                    for (std::uint64_t bits = occ[static_cast<std::size_t>(z)]; bits; bits &= bits - 1) {
                        const int bit = std::countr_zero(bits);
                        const int ix = origin.x() + (bit & 7), iy = origin.y() + (bit >> 3);
                        if (ix < vlo.x() || ix > vhi.x() || iy < vlo.y() || iy > vhi.y()) continue;
                        const int x0 = std::max(ix + lo, first.x()) - first.x(), x1 = std::min(ix + hi, first.x() + B - 1) - first.x();
                        const int y0 = std::max(iy + lo, first.y()) - first.y(), y1 = std::min(iy + hi, first.y() + B - 1) - first.y();
                        const std::uint64_t rect = layer_mask(x0, x1, y0, y1);
                        for (int pz = z0; pz <= z1; ++pz) mask[static_cast<std::size_t>(pz)] |= rect;
                    }
                }
            }
    return mask;
}

std::vector<VoxelKey> blocks_near_occupancy(const VoxelGrid& grid, int lo, int hi) {
    // Voxel block c holds voxels [8c, 8c + 7]; dilated by [lo, hi] they reach the blocks
    // block_coord(8c + lo) .. block_coord(8c + 7 + hi).
    const int rlo = block_coord(lo), rhi = block_coord(B - 1 + hi);
    std::vector<VoxelKey> out;
    BlockIndex seen;
    seen.reserve(grid.index().block_count() * 4);
    for (const VoxelKey& c : grid.index().block_keys())
        for (int z = rlo; z <= rhi; ++z)
            for (int y = rlo; y <= rhi; ++y)
                for (int x = rlo; x <= rhi; ++x) {
                    const VoxelKey b = c + VoxelKey(x, y, z);
                    if (seen.try_emplace(b, 0).second) out.push_back(b);
                }
    return out;
}

std::vector<MaskedBlock> dilated_occupancy(const VoxelGrid& grid, int lo, int hi) {
    const std::vector<VoxelKey> blocks = blocks_near_occupancy(grid, lo, hi);
    std::vector<MaskedBlock> all(blocks.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 16), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) all[i] = {blocks[i], dilated_occupancy(grid, blocks[i], lo, hi)};
    });
    std::erase_if(all, [](const MaskedBlock& b) { return popcount(b.mask) == 0; });
    return all;
}

}  // namespace lidarsurf
