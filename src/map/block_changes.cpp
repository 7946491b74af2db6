#include "lidarsurf/map/block_changes.hpp"

#include <algorithm>
#include <cmath>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

BlockChanges::BlockChanges(double growth, int reach) : growth_(growth), reach_(reach) {
    if (!(growth >= 0) || reach < 0) throw InvalidArgument("BlockChanges: growth must be >= 0 and reach >= 0");
}

BlockChanges::State& BlockChanges::state(const VoxelKey& key) {
    const auto [i, added] = index_.try_emplace(key, static_cast<std::uint32_t>(states_.size()));
    if (added) states_.emplace_back();
    return states_[i];
}

bool BlockChanges::due(const State& s) const {
    if (s.removed_since > 0) return true;
    if (s.changed_since == 0) return false;
    return !s.meshed || static_cast<double>(s.changed_since) > growth_ * static_cast<double>(s.points_at_mesh);
}

void BlockChanges::record(const VoxelGrid& grid, const std::vector<VoxelGrid::BlockChange>& changes) {
    const std::vector<VoxelKey>& keys = grid.index().block_keys();
    if (block_points_.size() < keys.size()) block_points_.resize(keys.size(), 0);
    for (const VoxelGrid::BlockChange& c : changes) {
        block_points_[c.block] = block_points_[c.block] + c.points - c.removed_points;
        const VoxelKey& block = keys[c.block];
        state(block).removed_since += c.removed_voxels;  // its own: due at once (the loop lists it)
        for (int z = -reach_; z <= reach_; ++z)
            for (int y = -reach_; y <= reach_; ++y)
                for (int x = -reach_; x <= reach_; ++x) {
                    const VoxelKey key = block + VoxelKey(x, y, z);
                    State& s = state(key);
                    s.changed_since += c.points + c.removed_points;
                    if (!s.dirty && due(s)) make_due(key, s);
                }
    }
}

void BlockChanges::record_all(const VoxelGrid& grid) {
    std::vector<std::uint64_t> counts(grid.index().block_count(), 0);
    const BlockKeys& index = grid.index();
    for (std::size_t v = 0; v < grid.size(); ++v)
        counts[static_cast<std::size_t>(index.index_of(BlockMap<std::int32_t>::block_of(grid.keys()[v])))] += grid.stats()[v].count;
    std::vector<VoxelGrid::BlockChange> all;
    all.reserve(counts.size());
    for (std::size_t b = 0; b < counts.size(); ++b)
        if (counts[b] > 0) all.push_back({static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(std::min<std::uint64_t>(counts[b], 0xffffffffu)), 0, 0, 0});
    record(grid, all);
}

void BlockChanges::mark_meshed(const VoxelGrid& grid, const VoxelKey& key) {
    const std::uint64_t points = points_near(grid, key);
    State& s = state(key);
    s.points_at_mesh = points;
    s.changed_since = 0;
    s.removed_since = 0;
    s.meshed = true;
    if (s.dirty) --due_count_;
    s.dirty = false;
}

namespace {
int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
VoxelKey cell_of(const VoxelKey& block) {
    return {floor_div(block.x(), BlockChanges::kCellBlocks), floor_div(block.y(), BlockChanges::kCellBlocks),
            floor_div(block.z(), BlockChanges::kCellBlocks)};
}
}  // namespace

void BlockChanges::make_due(const VoxelKey& key, State& s) {
    s.dirty = true;
    ++due_count_;
    if (s.listed) return;
    s.listed = true;
    const VoxelKey cell = cell_of(key);
    const auto [i, added] = cell_index_.try_emplace(cell, static_cast<std::uint32_t>(cell_due_.size()));
    if (added) cell_due_.emplace_back();
    cell_due_[i].push_back(key);
}

std::vector<BlockChanges::Due> BlockChanges::due_near(const Eigen::Vector3d& local, double voxel_size, double radius) {
    constexpr int B = BlockMap<std::int32_t>::kSize;
    const double block = B * voxel_size, cell = kCellBlocks * block;
    std::vector<Due> out;
    VoxelKey lo, hi;
    for (int a = 0; a < 3; ++a) {
        lo[a] = static_cast<int>(std::floor((local[a] - radius) / cell));
        hi[a] = static_cast<int>(std::floor((local[a] + radius) / cell));
    }
    const double r2 = radius * radius;
    for (int z = lo.z(); z <= hi.z(); ++z)
        for (int y = lo.y(); y <= hi.y(); ++y)
            for (int x = lo.x(); x <= hi.x(); ++x) {
                const std::uint32_t c = cell_index_.find({x, y, z});
                if (c == BlockIndex::kAbsent) continue;
                std::vector<VoxelKey>& keys = cell_due_[c];
                std::erase_if(keys, [&](const VoxelKey& key) {  // meshed since
                    State& st = states_[index_.find(key)];
                    st.listed = st.dirty;
                    return !st.dirty;
                });
                for (const VoxelKey& key : keys) {
                    const double d2 = ((key.cast<double>().array() + 0.5) * block - local.array()).matrix().squaredNorm();
                    if (d2 > r2) continue;
                    const State& st = states_[index_.find(key)];
                    out.push_back({key, d2, !st.meshed || st.removed_since > 0});
                }
            }
    return out;
}

std::uint64_t BlockChanges::points_near(const VoxelGrid& grid, const VoxelKey& key) const {
    std::uint64_t sum = 0;
    for (int z = -reach_; z <= reach_; ++z)
        for (int y = -reach_; y <= reach_; ++y)
            for (int x = -reach_; x <= reach_; ++x) {
                const std::int64_t b = grid.index().index_of(key + VoxelKey(x, y, z));
                if (b >= 0 && static_cast<std::size_t>(b) < block_points_.size()) sum += block_points_[static_cast<std::size_t>(b)];
            }
    return sum;
}

std::size_t BlockChanges::memory_bytes() const {
    std::size_t due_bytes = cell_due_.capacity() * sizeof(std::vector<VoxelKey>);
    for (const auto& keys : cell_due_) due_bytes += keys.capacity() * sizeof(VoxelKey);
    return index_.memory_bytes() + states_.capacity() * sizeof(State) + block_points_.capacity() * sizeof(std::uint64_t) +
           cell_index_.memory_bytes() + due_bytes;
}

}  // namespace lidarsurf
