#include "lidarsurf/surface/neighbourhood_window.hpp"

#include <algorithm>
#include <bit>

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"

namespace lidarsurf {

VoxelStats Moments::to_stats(const Eigen::Vector3d& p) const {
    VoxelStats s;
    if (n <= 0) return s;
    s.count = static_cast<std::uint64_t>(n);
    const Eigen::Vector3d d = s1 / n;
    s.mean = p + d;
    s.scatter = s2 - s1 * d.transpose();  // sum (x-p)(x-p)^T - n d d^T = sum (x-mu)(x-mu)^T
    return s;
}

namespace {
using Map = BlockMap<std::int32_t>;
// The address that marks a window block not looked up yet (never dereferenced).
const PackedVoxels::Block kNotLookedUpBlock{};
const PackedVoxels::Block* const kNotLookedUp = &kNotLookedUpBlock;
}  // namespace

NeighbourhoodWindow::NeighbourhoodWindow(const PackedVoxels& voxels, const VoxelKey& vertex_block, int max_level)
    : voxels_(&voxels), alpha_(voxels.grid().voxel_size()) {
    // H^k(v) = voxels [v-k, v+k-1]: for v in [8b, 8b+7] that is [8b-k, 8b+6+k], within
    // radius ceil(k/8) blocks of b.
    radius_ = (max_level + Map::kSize - 1) / Map::kSize;
    side_ = 2 * radius_ + 1;
    reset(vertex_block);
}

void NeighbourhoodWindow::reset(const VoxelKey& vertex_block) {
    first_voxel_ = (vertex_block.array() - radius_) * Map::kSize;
    blocks_.assign(static_cast<std::size_t>(side_ * side_ * side_), kNotLookedUp);
}

const PackedVoxels::Block* NeighbourhoodWindow::block(int bx, int by, int bz) const {
    const PackedVoxels::Block*& b = blocks_[static_cast<std::size_t>(bx + side_ * (by + side_ * bz))];
    if (b == kNotLookedUp) b = voxels_->find(Map::block_of(first_voxel_) + VoxelKey(bx, by, bz));
    return b;
}

void NeighbourhoodWindow::add_shell(const VoxelKey& lo, const VoxelKey& hi, int inset, const Eigen::Vector3d& p,
                                    Moments& acc, bool caps) const {
    constexpr int B = Map::kSize, m = B - 1;
    const VoxelKey l = lo - first_voxel_, h = hi - first_voxel_;  // window coordinates
    if ((l.array() < 0).any() || (h.array() >= side_ * B).any())
        throw InvalidArgument("neighbourhood box beyond the window's blocks: build the window with the configuration's max_reach()");
    // The hole: [l + inset, h - inset] in x and y, on the layers strictly inside [l.z, h.z]
    // (every layer without caps).
    const VoxelKey il = l.array() + inset, ih = h.array() - inset;
    const double px = p.x(), py = p.y(), pz = p.z();
    double n = acc.n, s1x = acc.s1.x(), s1y = acc.s1.y(), s1z = acc.s1.z();
    double sxx = acc.s2(0, 0), sxy = acc.s2(0, 1), sxz = acc.s2(0, 2), syy = acc.s2(1, 1), syz = acc.s2(1, 2), szz = acc.s2(2, 2);
    for (int bz = l.z() / B; bz <= h.z() / B; ++bz)
        for (int by = l.y() / B; by <= h.y() / B; ++by)
            for (int bx = l.x() / B; bx <= h.x() / B; ++bx) {
                const PackedVoxels::Block* block = this->block(bx, by, bz);
                if (!block) continue;
                // The box's layers within this block that hold a voxel (most blocks of a lidar
                // frame hold a few layers of ground or facade): the others are skipped.
                const int z0 = std::max(l.z(), bz * B), z1 = std::min(h.z(), bz * B + m);
                unsigned layers = block->layers & ((0xffu >> (m - ((z1 - z0) & m))) << (z0 & m));
                if (!layers) continue;
                // The box within this block, in block coordinates, and its 8x8 layer masks.
                const int x0 = std::max(l.x(), bx * B), x1 = std::min(h.x(), bx * B + m);
                const int y0 = std::max(l.y(), by * B), y1 = std::min(h.y(), by * B + m);
                const std::uint64_t full = layer_mask(x0 & m, x1 & m, y0 & m, y1 & m);
                std::uint64_t ring = full;
                const int hx0 = std::max(il.x(), x0), hx1 = std::min(ih.x(), x1);
                const int hy0 = std::max(il.y(), y0), hy1 = std::min(ih.y(), y1);
                if (inset > 0 && hx0 <= hx1 && hy0 <= hy1) ring &= ~layer_mask(hx0 & m, hx1 & m, hy0 & m, hy1 & m);
                for (; layers; layers &= layers - 1) {
                    const int z = bz * B + std::countr_zero(layers);
                    const bool cap = inset == 0 || (caps && (z == l.z() || z == h.z()));
                    std::uint64_t bits = (*block->occupancy)[static_cast<std::size_t>(z & m)] & (cap ? full : ring);
                    while (bits) {
                        const int bit = std::countr_zero(bits);
                        bits &= bits - 1;
                        const PackedVoxels::Voxel& s = block->at(bit | ((z & m) << 6));
                        const double w = s.count;
                        const double dx = s.mx - px, dy = s.my - py, dz = s.mz - pz;
                        const double wx = w * dx, wy = w * dy, wz = w * dz;
                        n += w;
                        s1x += wx, s1y += wy, s1z += wz;
                        sxx += s.xx + wx * dx, sxy += s.xy + wx * dy, sxz += s.xz + wx * dz;
                        syy += s.yy + wy * dy, syz += s.yz + wy * dz, szz += s.zz + wz * dz;
                    }
                }
            }
    // Accumulated in locals (registers) rather than through `acc`; the scatter is symmetric.
    acc.n = n;
    acc.s1 = {s1x, s1y, s1z};
    acc.s2 << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
}

void NeighbourhoodWindow::grow(const VoxelKey& v, int k, Moments& acc) const {
    // H^k \ H^{k-1}: the box [v-k, v+k-1] without its interior [v-k+1, v+k-2] (empty for k = 1).
    add_shell(v.array() - k, v.array() + (k - 1), k > 1 ? 1 : 0, v.cast<double>() * alpha_, acc);
}

Moments NeighbourhoodWindow::box(const VoxelKey& v, int k) const {
    Moments acc;
    add_shell(v.array() - k, v.array() + (k - 1), 0, v.cast<double>() * alpha_, acc);
    return acc;
}

Moments NeighbourhoodWindow::slab(const VoxelKey& v, int k, SlabExtension e) const {
    Moments acc;
    const VoxelBox b = slab_box(v, k, e);
    add_shell(b.lo, b.hi, 0, v.cast<double>() * alpha_, acc);
    return acc;
}

void NeighbourhoodWindow::grow_slab(const VoxelKey& v, int k, Moments& acc, SlabExtension e) const {
    // S^k \ S^{k-1}: the x-y ring of width one around S^{k-1}'s x-y range, on both layers.
    const VoxelBox b = slab_box(v, k, e);
    add_shell(b.lo, b.hi, 1, v.cast<double>() * alpha_, acc, false);
}

}  // namespace lidarsurf
