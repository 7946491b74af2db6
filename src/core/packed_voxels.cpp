#include "lidarsurf/core/packed_voxels.hpp"

#include <bit>
#include <string>

#include <tbb/parallel_for.h>

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

void PackedVoxels::left_out(const VoxelKey& key) {
    throw InvalidArgument("voxel block (" + std::to_string(key.x()) + ", " + std::to_string(key.y()) + ", " + std::to_string(key.z()) +
                          ") was left out of the packed snapshot");
}

PackedVoxels::PackedVoxels(const VoxelGrid& grid, const std::vector<std::uint8_t>* only) : grid_(&grid) {
    const std::size_t blocks = grid.index().block_count();
    if (only && only->size() != blocks) throw InvalidArgument("PackedVoxels: one flag per grid block expected");
    auto packed = [&](std::size_t b) { return !only || (*only)[b]; };
    blocks_.resize(blocks);
    // Where each block's records start: a prefix sum of its occupied voxels.
    std::vector<std::size_t> start(blocks + 1, 0);
    for (std::size_t b = 0; b < blocks; ++b) {
        start[b + 1] = start[b] + (packed(b) ? static_cast<std::size_t>(popcount(grid.occupancy(b))) : 0);
    }
    voxels_.resize(start[blocks]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 64), [&](const auto& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            if (!packed(b)) continue;  // occupancy stays nullptr: find() refuses it
            Block& block = blocks_[b];
            block.voxels = voxels_.data() + start[b];
            block.occupancy = &grid.occupancy(b);
            const auto& index = grid.index().block_at(b);
            Voxel* out = voxels_.data() + start[b];
            int rank = 0;
            for (int row = 0; row < 64; ++row) {
                block.row_start[static_cast<std::size_t>(row)] = static_cast<std::uint16_t>(rank);
                const std::uint64_t byte = ((*block.occupancy)[static_cast<std::size_t>(row >> 3)] >> (8 * (row & 7))) & 0xffu;
                for (std::uint64_t bits = byte; bits; bits &= bits - 1, ++rank) {
                    const int offset = std::countr_zero(bits) | (row << 3);
                    const VoxelStats& s = grid.stats()[static_cast<std::size_t>(index[static_cast<std::size_t>(offset)])];
                    const Eigen::Matrix3d& m = s.scatter;
                    out[rank] = {static_cast<double>(s.count), s.mean.x(), s.mean.y(), s.mean.z(),
                                 m(0, 0), m(0, 1), m(0, 2), m(1, 1), m(1, 2), m(2, 2)};
                }
            }
        }
    });
}

}  // namespace lidarsurf
