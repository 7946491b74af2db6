#include "lidarsurf/core/block_map.hpp"

#include <algorithm>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

std::optional<BlockBox> dense_block_box(const std::vector<VoxelKey>& keys, int margin, std::size_t cells_per_key, std::size_t max_cells) {
    if (keys.empty() || margin < 0) return std::nullopt;
    VoxelKey lo = keys.front(), hi = keys.front();
    for (const VoxelKey& k : keys) {
        lo = lo.cwiseMin(k);
        hi = hi.cwiseMax(k);
    }
    // In 64 bits: the box of far-apart keys overflows int.
    std::int64_t size[3];
    for (int a = 0; a < 3; ++a) size[a] = std::int64_t{hi[a]} - lo[a] + 1 + 2 * std::int64_t{margin};
    const auto limit = static_cast<std::int64_t>(std::min(cells_per_key * keys.size(), max_cells));
    if (size[0] > limit || size[1] > limit || size[2] > limit || size[0] * size[1] > limit || size[0] * size[1] * size[2] > limit)
        return std::nullopt;
    return BlockBox{lo.array() - margin, VoxelKey(static_cast<int>(size[0]), static_cast<int>(size[1]), static_cast<int>(size[2]))};
}

void BlockIndex::use_box(const BlockBox& box) {
    if (size_ != 0 || has_box()) throw InvalidArgument("BlockIndex::use_box: the index must be empty");
    if ((box.size.array() <= 0).any()) throw InvalidArgument("BlockIndex::use_box: the box must not be empty");
    box_lo_ = box.lo;
    box_size_ = box.size;
    box_.assign(static_cast<std::size_t>(box.size.x()) * static_cast<std::size_t>(box.size.y()) * static_cast<std::size_t>(box.size.z()), kAbsent);
}

}  // namespace lidarsurf
