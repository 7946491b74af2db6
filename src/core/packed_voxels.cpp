#include "lidarsurf/core/packed_voxels.hpp"

#include <bit>
#include <optional>
#include <thread>

#include <tbb/parallel_for.h>

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

PackedVoxels::PackedVoxels(const VoxelGrid& grid, const std::vector<std::uint8_t>* eager) : grid_(&grid) {
    const std::size_t blocks = grid.index().block_count();
    if (eager && eager->size() != blocks) throw InvalidArgument("PackedVoxels: one flag per grid block expected");
    allocate(blocks);
    index_keys(grid.index().block_keys());
    pack_up_front(eager);
}

PackedVoxels::PackedVoxels(const VoxelGrid& grid, std::span<const std::uint32_t> blocks)
    : grid_(&grid), subset_(true), grid_blocks_(blocks.begin(), blocks.end()) {
    allocate(grid_blocks_.size());
    std::vector<VoxelKey> keys(grid_blocks_.size());
    for (std::size_t b = 0; b < keys.size(); ++b) keys[b] = grid.index().block_keys()[grid_blocks_[b]];
    index_keys(keys);
    pack_up_front(nullptr);
}

void PackedVoxels::allocate(std::size_t blocks) {
    blocks_.resize(blocks);
    state_ = std::make_unique<std::atomic<std::uint8_t>[]>(blocks);  // value-initialised: kUnpacked
    // Where each block's records start: a prefix sum of its occupied voxels.
    start_.assign(blocks + 1, 0);
    for (std::size_t b = 0; b < blocks; ++b) start_[b + 1] = start_[b] + static_cast<std::size_t>(popcount(grid_->occupancy(in_grid(b))));
    voxel_count_ = start_[blocks];
    voxels_.reset(new Voxel[voxel_count_]);  // default-initialised: no page is touched before its block is packed
}

void PackedVoxels::index_keys(const std::vector<VoxelKey>& keys) {
    // The windows of a frame look blocks up ~150k times (KITTI 000000), mostly blocks near the
    // data. A lidar frame's blocks fill 3-5 % of their bounding box (a disc ten blocks thick:
    // 2,283 blocks in a 98 x 64 x 10 box on KITTI 000000, 1,221 in 146 x 47 x 4 on the simulated
    // town), so a table of the box costs ~110 bytes per block (250 KB there) and answers with one
    // load instead of a hash probe (which runs on to an empty slot for the many absent blocks).
    // A box sparser than kDenseCellsPerBlock (a fused map along a long trajectory) keeps a hash:
    // the grid's own for a snapshot of every block, one of the subset's keys for a subset.
    const std::optional<BlockBox> box = dense_block_box(keys, 0, kDenseCellsPerBlock);
    if (box) dense_.use_box(*box);
    else if (subset_) dense_.reserve(keys.size());
    else return;
    for (std::size_t b = 0; b < keys.size(); ++b) dense_.try_emplace(keys[b], static_cast<std::uint32_t>(b));
}

void PackedVoxels::pack_up_front(const std::vector<std::uint8_t>* eager) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks_.size(), 64), [&](const auto& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            if (eager && !(*eager)[b]) continue;
            pack(b);
            state_[b].store(kPacked, std::memory_order_release);
        }
    });
}

void PackedVoxels::pack(std::size_t b) const {
    const VoxelGrid& grid = *grid_;
    Block& block = blocks_[b];
    block.voxels = voxels_.get() + start_[b];
    block.occupancy = &grid.occupancy(in_grid(b));
    block.layers = 0;
    for (int z = 0; z < 8; ++z) block.layers |= static_cast<std::uint8_t>(((*block.occupancy)[static_cast<std::size_t>(z)] != 0) << z);
    const std::span<const std::int32_t> index = grid.block_voxels(in_grid(b));
    Voxel* out = voxels_.get() + start_[b];
    int rank = 0;
    for (int row = 0; row < 64; ++row) {
        block.row_start[static_cast<std::size_t>(row)] = static_cast<std::uint16_t>(rank);
        const std::uint64_t byte = ((*block.occupancy)[static_cast<std::size_t>(row >> 3)] >> (8 * (row & 7))) & 0xffu;
        for (std::uint64_t bits = byte; bits; bits &= bits - 1, ++rank) {
            const VoxelStats& s = grid.stats()[static_cast<std::size_t>(index[static_cast<std::size_t>(rank)])];
            const SymmetricMatrix3& m = s.scatter;
            out[rank] = {static_cast<double>(s.count), s.mean.x(), s.mean.y(), s.mean.z(), m.xx, m.xy, m.xz, m.yy, m.yz, m.zz};
        }
    }
}

void PackedVoxels::pack_now(std::size_t b) const {
    std::uint8_t state = kUnpacked;
    if (state_[b].compare_exchange_strong(state, kBusy, std::memory_order_acq_rel)) {
        pack(b);
        state_[b].store(kPacked, std::memory_order_release);
        return;
    }
    while (state_[b].load(std::memory_order_acquire) != kPacked) std::this_thread::yield();
}

std::size_t PackedVoxels::packed_blocks() const {
    std::size_t n = 0;
    for (std::size_t b = 0; b < blocks_.size(); ++b) n += state_[b].load(std::memory_order_acquire) == kPacked;
    return n;
}

}  // namespace lidarsurf
