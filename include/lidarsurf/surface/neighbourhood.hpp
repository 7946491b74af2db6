#pragma once
// Neighbourhoods of a grid vertex (Sec. III-B1). Vertex v (integer lattice point, world position
// origin + alpha*v) is the shared corner of voxels v-1 and v along each axis, so
// H^k(v) = the (2k)^3 voxels with indices in [v-k, v+k-1]^3; H^1 are its 8 adjacent voxels.
#include <array>

#include "lidarsurf/core/voxel_grid.hpp"

namespace lidarsurf {

/// A box of voxels, lo <= key <= hi (inclusive).
struct VoxelBox {
    VoxelKey lo, hi;
};

/// The shell H^k(v) \ H^{k-1}(v) (k >= 2) as 6 disjoint boxes: the two z-slabs, the two y-slabs of
/// the inner z range, the two x-slabs of the inner y and z range.
std::array<VoxelBox, 6> shell_boxes(const VoxelKey& vertex, int k);

/// How far a slab reaches beyond [v-k, v+k-1] on each side, per horizontal axis (x, y).
struct SlabExtension {
    int x = 0, y = 0;
};

/// The radial slab extension of a vertex at `position` seen from `sensor` (same frame): `voxels`
/// along the horizontal axis on which the vertex is further from the sensor (x on a tie), 0 along
/// the other (docs/method.md, "Radial slabs").
SlabExtension radial_extension(const Eigen::Vector3d& position, const Eigen::Vector3d& sensor, int voxels);

/// The slab S^k(v) = [v-k-e_x, v+k-1+e_x] x [v-k-e_y, v+k-1+e_y] x [v_z - 1, v_z]: H^k(v) cut to
/// the two voxel layers beside v along z and extended by e (the slab fallback, docs/method.md).
VoxelBox slab_box(const VoxelKey& vertex, int k, SlabExtension e = {});

/// The bridge boxes of vertex v at `position` seen from `sensor` (docs/method.md, "Bridges"):
/// along the horizontal axis on which v is further from the sensor (x on a tie; the radial
/// slabs' axis), [v - k - reach, v - 1] and [v, v + k - 1 + reach]; across it [v - k, v + k - 1];
/// along z [v_z - 2, v_z + 1]. The first is the one on the sensor's side.
std::array<VoxelBox, 2> bridge_boxes(const VoxelKey& vertex, int k, int reach, const Eigen::Vector3d& position, const Eigen::Vector3d& sensor);

/// Merged statistics of the voxels of `box`.
VoxelStats merge_box(const VoxelGrid& grid, const VoxelBox& box);

/// Merged statistics |H|, H_mu, H_sigma of H^k(v) (k >= 1).
VoxelStats merge_neighbourhood(const VoxelGrid& grid, const VoxelKey& vertex, int k);

/// Grows `acc` from the statistics of H^{k-1}(v) to those of H^k(v) by merging only the shell
/// H^k \ H^{k-1} (for k = 1, acc must be empty). Same set as merge_neighbourhood, less work.
void grow_neighbourhood(const VoxelGrid& grid, const VoxelKey& vertex, int k, VoxelStats& acc);

}  // namespace lidarsurf
