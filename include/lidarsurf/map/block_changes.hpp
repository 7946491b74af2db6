#pragma once
// Which blocks of a fused map need meshing again (docs/method.md, "Live mesh"). A vertex's TSDF
// depends on the voxels within SurfaceConfig::max_reach() of it; a block of the mesh (an
// 8^3 block of cubes, the grid's block) is re-meshed when
//  - one of its own voxels was removed (free-space carving: what moved must go at once; the
//    blocks around it count the removed points as a change, below), or
//  - the points within `reach` blocks of it changed (inserted, or removed by carving) by `growth`
//    (a fraction) of what they were when it was last meshed, or it was never meshed. Points keep
//    coming where the sensor looks, but each scan adds less to what is there: a block seen by n
//    scans is meshed about log(n) / log(1 + growth) times, not n times.
// Carving removes a few voxels near most surfaces at every scan (grazing rays, mixed returns): were
// a removal to make the 27 blocks around it due at once, those blocks, most of them for a change
// their growth test does not notice, would take the whole budget (docs/benchmarks.md, "Live maps").
// The tracker reads the grid's journal (VoxelGrid::take_changes): its work per scan follows the
// blocks the scan changed, not the map.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/voxel_grid.hpp"

namespace lidarsurf {

class BlockChanges {
public:
    /// `growth` >= 0 (0: any new point dirties), `reach` >= 0 blocks.
    BlockChanges(double growth, int reach);

    /// Takes one batch of the grid's journal: the blocks within `reach` of each changed block get
    /// its points inserted and removed, the block itself its voxels removed; those now due are
    /// listed in their cells (due_near).
    void record(const VoxelGrid& grid, const std::vector<VoxelGrid::BlockChange>& changes);
    /// Every block of the grid as changed (a live mesh started on a grid that already holds points).
    void record_all(const VoxelGrid& grid);

    /// A block due for meshing, seen from a position.
    struct Due {
        VoxelKey key;
        double distance2 = 0;  ///< squared distance (m^2) from the position to the block's centre
        /// Never meshed, or one of its voxels was removed (what moved must leave the live mesh):
        /// to be meshed before the blocks whose points only changed.
        bool urgent = false;
    };
    /// The blocks due for meshing whose centre lies within `radius` (metres) of `local` (the
    /// grid's local frame), each once. Reads only the cells of due blocks near `local` (cubes of
    /// kCellBlocks^3 blocks), so a long drive's blocks left behind cost nothing.
    std::vector<Due> due_near(const Eigen::Vector3d& local, double voxel_size, double radius);
    /// Blocks due, anywhere.
    std::size_t due_count() const { return due_count_; }
    /// Block `key` was meshed from the grid as it is now: its counts start again from there, and
    /// it is no longer due.
    void mark_meshed(const VoxelGrid& grid, const VoxelKey& key);
    static constexpr int kCellBlocks = 8;

    /// Points the grid holds within `reach` blocks of `key` (as recorded).
    std::uint64_t points_near(const VoxelGrid& grid, const VoxelKey& key) const;
    std::size_t memory_bytes() const;

private:
    struct State {
        std::uint64_t points_at_mesh = 0;  // points within reach when last meshed
        std::uint64_t changed_since = 0;   // points inserted or removed within reach since
        std::uint32_t removed_since = 0;   // voxels of this block removed since
        bool meshed = false;
        bool dirty = false;   // due
        bool listed = false;  // in its cell's list (a block meshed since it was listed stays there until the cell is read)
    };
    State& state(const VoxelKey& key);
    bool due(const State& s) const;
    void make_due(const VoxelKey& key, State& s);

    double growth_;
    int reach_;
    BlockIndex index_;            // block key -> states_
    std::vector<State> states_;
    std::vector<std::uint64_t> block_points_;  // per grid block (creation index): points it holds
    // The due blocks by cell (kCellBlocks^3 blocks); a block meshed since it became due stays in
    // its cell's list until due_near() next reads that cell.
    BlockIndex cell_index_;
    std::vector<std::vector<VoxelKey>> cell_due_;
    std::size_t due_count_ = 0;
};

}  // namespace lidarsurf
