#include "lidarsurf/core/packed_voxels.hpp"

#include <bit>

#include <tbb/parallel_for.h>

#include "lidarsurf/core/block_mask.hpp"

namespace lidarsurf {

PackedVoxels::PackedVoxels(const VoxelGrid& grid) : grid_(&grid) {
    const std::size_t blocks = grid.index().block_count();
    blocks_.resize(blocks);
    // Where each block's records start: a prefix sum of its occupied voxels.
    std::vector<std::size_t> start(blocks + 1, 0);
    for (std::size_t b = 0; b < blocks; ++b) {
        start[b + 1] = start[b] + static_cast<std::size_t>(popcount(grid.occupancy(b)));
    }
    voxels_.resize(start[blocks]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 64), [&](const auto& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
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
