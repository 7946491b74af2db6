#pragma once
// Fast neighbourhood statistics for the vertices of one 8^3 vertex block (issue 5). The packed
// voxel blocks (PackedVoxels) that any H^k(v), k <= max_level, of those vertices can reach
// (3x3x3 blocks for max_level <= 8, 5x5x5 up to 16) are looked up at most once each, when a box
// first reaches them, so summing a box needs no hashing, skips empty
// space 64 voxels at a time (VoxelGrid::occupancy) and reads compact records stored in block
// order; and each occupied voxel is added as
// raw moments in the frame of the vertex,
//   n += |V|,  s1 += |V| d,  s2 += V_M2 + |V| d d^T   with d = V_mu - v,
// which is Chan's merge (voxel_stats.cpp) expanded: no division per voxel, and small coordinates
// (|d| <= k alpha) so no loss of precision. The result equals merge_neighbourhood() up to
// rounding (tests/surface/test_neighbourhood_window.cpp).
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"

namespace lidarsurf {

/// Raw moments of a set of points about a reference point p.
struct Moments {
    double n = 0;
    Eigen::Vector3d s1 = Eigen::Vector3d::Zero();  ///< sum (x - p)
    Eigen::Matrix3d s2 = Eigen::Matrix3d::Zero();  ///< sum (x - p)(x - p)^T

    /// Count, mean and scatter about the mean (VoxelStats), given the reference point p.
    VoxelStats to_stats(const Eigen::Vector3d& p) const;
};

class NeighbourhoodWindow {
public:
    /// Window for the vertices of vertex block `vertex_block` (vertices 8 b .. 8 b + 7 per axis)
    /// and levels up to `max_level`. The sums cache their block lookups in the window, so one
    /// window must not be used by two threads at once (`voxels` itself is thread-safe).
    NeighbourhoodWindow(const PackedVoxels& voxels, const VoxelKey& vertex_block, int max_level);
    /// Makes this the window of another vertex block (same voxels and levels; keeps the storage).
    void reset(const VoxelKey& vertex_block);

    /// Adds the voxels of H^k(v) \ H^{k-1}(v) (all of H^1 for k = 1) to `acc`, whose reference
    /// point is v's position. v must be in the window's vertex block and k <= max_level.
    void grow(const VoxelKey& v, int k, Moments& acc) const;
    /// Moments of the whole H^k(v) about v's position.
    Moments box(const VoxelKey& v, int k) const;
    /// Moments of the whole slab S^k(v) extended by e (neighbourhood.hpp's slab_box) about v's
    /// position; k + max(e) must be <= max_level. Every method throws InvalidArgument for a box
    /// beyond the window's blocks.
    Moments slab(const VoxelKey& v, int k, SlabExtension e = {}) const;
    /// Adds S^k(v) \ S^{k-1}(v) (both extended by e) to `acc` (which holds S^{k-1}(v); k >= 2).
    void grow_slab(const VoxelKey& v, int k, Moments& acc, SlabExtension e = {}) const;

    double voxel_size() const { return alpha_; }
    const VoxelGrid& grid() const { return voxels_->grid(); }

private:
    // Adds the voxels of the box lo <= key <= hi (inclusive) to acc, without its interior box
    // [lo + inset, hi - inset] when inset > 0 (a shell; with `caps` false the hole runs through
    // every layer: the x-y ring of a slab). One pass over the window blocks, one 64-bit mask per
    // 8x8 layer.
    void add_shell(const VoxelKey& lo, const VoxelKey& hi, int inset, const Eigen::Vector3d& p, Moments& acc, bool caps = true) const;

    // Block (bx, by, bz) of the window, looked up on first use.
    const PackedVoxels::Block* block(int bx, int by, int bz) const;

    const PackedVoxels* voxels_;
    double alpha_;
    int radius_;   // blocks on each side of the vertex block
    int side_;     // 2 radius + 1
    VoxelKey first_voxel_;  // smallest voxel key covered by the window
    // side^3 blocks, x fastest: nullptr when the block holds no voxel, kNotLookedUp before the
    // first box that reaches it. Most boxes stay within the 3x3x3 blocks around the vertex block
    // (the 5x5x5 of the radial slabs are reached along one axis), and a window is built per
    // vertex block a task meets, so looking all of them up front cost ~9 % of a KITTI frame.
    mutable std::vector<const PackedVoxels::Block*> blocks_;
};

}  // namespace lidarsurf
