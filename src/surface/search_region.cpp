#include "lidarsurf/surface/search_region.hpp"

#include <array>
#include <cstdint>
#include <utility>

namespace lidarsurf {

namespace {

// Byte b spread over the rows of an 8x8 layer: bit p of b becomes bit 8 p (a column, x = 0).
constexpr std::array<std::uint64_t, 256> kColumnOfByte = [] {
    std::array<std::uint64_t, 256> t{};
    for (std::size_t b = 0; b < 256; ++b)
        for (int p = 0; p < 8; ++p)
            if ((b >> p) & 1u) t[b] |= std::uint64_t{1} << (8 * p);
    return t;
}();

// `in` with every cube grown by `halo` cubes both ways along `axis` (0: x, 1: y, 2: z), in
// `in`'s blocks and the blocks beyond: each line of a block along the axis (8 cubes, a byte)
// becomes the union of its runs grown by the halo. Blocks of `in` first, in its order.
void dilate_along(const std::vector<VoxelKey>& blocks, const std::vector<BlockMask>& masks, int axis, int halo, SearchRegion& out) {
    constexpr int B = BlockMap<std::int32_t>::kSize;
    const int rings = (halo + B - 1) / B;
    for (std::size_t i = 0; i < blocks.size(); ++i) out.add(blocks[i], masks[i]);
    std::vector<BlockMask> grown(static_cast<std::size_t>(2 * rings + 1));
    // Line (i, j) of a mask along the axis: its 8 cubes as a byte; and bits added to it.
    const auto line = [axis](const BlockMask& m, int i, int j) -> unsigned {
        if (axis == 0) return static_cast<unsigned>((m[static_cast<std::size_t>(j)] >> (8 * i)) & 0xffu);  // (y, z)
        unsigned b = 0;
        for (int p = 0; p < B; ++p)
            b |= static_cast<unsigned>(axis == 1 ? (m[static_cast<std::size_t>(j)] >> (i + 8 * p)) & 1u      // (x, z)
                                                 : (m[static_cast<std::size_t>(p)] >> (i + 8 * j)) & 1u) << p;  // (x, y)
        return b;
    };
    const auto set_line = [axis](BlockMask& m, int i, int j, unsigned bits) {
        if (axis == 0) {
            m[static_cast<std::size_t>(j)] |= std::uint64_t{bits} << (8 * i);
        } else if (axis == 1) {
            m[static_cast<std::size_t>(j)] |= kColumnOfByte[bits] << i;
        } else {
            for (; bits; bits &= bits - 1) m[static_cast<std::size_t>(std::countr_zero(bits))] |= std::uint64_t{1} << (i + 8 * j);
        }
    };
    // Fills `grown` with mask m's lines grown by the halo, block offset d - rings in grown[d].
    const auto grow = [&](const BlockMask& m) {
        for (BlockMask& g : grown) g.fill(0);
        for (int j = 0; j < B; ++j)
            for (int i = 0; i < B; ++i) {
                unsigned b = line(m, i, j);
                int lo = 0, hi = -1;  // the interval being merged, cubes relative to the block
                const auto flush = [&] {
                    for (int d = 0; d <= 2 * rings; ++d) {
                        const int from = std::max(lo - B * (d - rings), 0), to = std::min(hi - B * (d - rings), B - 1);
                        if (from <= to) set_line(grown[static_cast<std::size_t>(d)], i, j, (0xffu >> (B - 1 - (to - from))) << from);
                    }
                };
                while (b) {
                    const int a = std::countr_zero(b);
                    const int e = a + std::countr_one(b >> a) - 1;  // the run [a, e]
                    b &= ~((0xffu >> (B - 1 - (e - a))) << a);
                    if (hi >= lo && a - halo <= hi + 1) {
                        hi = e + halo;
                    } else {
                        if (hi >= lo) flush();
                        lo = a - halo, hi = e + halo;
                    }
                }
                if (hi >= lo) flush();
            }
    };
    // A full block grows the same way wherever it is (most of a region's core): grown once.
    const auto is_full = [](const BlockMask& m) { return std::all_of(m.begin(), m.end(), [](std::uint64_t w) { return w == ~std::uint64_t{0}; }); };
    BlockMask all;
    all.fill(~std::uint64_t{0});
    grow(all);
    const std::vector<BlockMask> grown_full = grown;
    for (std::size_t k = 0; k < blocks.size(); ++k) {
        if (is_full(masks[k]))
            grown = grown_full;
        else
            grow(masks[k]);
        for (int d = 0; d <= 2 * rings; ++d) {
            const BlockMask& g = grown[static_cast<std::size_t>(d)];
            if (d == rings || std::all_of(g.begin(), g.end(), [](std::uint64_t w) { return w == 0; })) continue;
            VoxelKey to = blocks[k];
            to[axis] += d - rings;
            out.add(to, g);
        }
    }
}

}  // namespace

SearchRegion SearchRegion::around(std::span<const VoxelKey> core, int halo) {
    // The cubes within Chebyshev distance `halo` of the core: the core grown along x, then y, then
    // z (a box is the Minkowski sum of its three edges), line by line rather than block by block.
    SearchRegion region;
    BlockMask full;
    full.fill(~std::uint64_t{0});
    for (const VoxelKey& block : core) region.add(block, full);
    if (halo <= 0) return region;
    for (int axis = 0; axis < 3; ++axis) {
        SearchRegion next;
        dilate_along(region.blocks_, region.masks_, axis, halo, next);
        region = std::move(next);
    }
    return region;
}

void SearchRegion::add(const VoxelKey& block, const BlockMask& mask) {
    const auto [i, added] = index_.try_emplace(block, static_cast<std::uint32_t>(blocks_.size()));
    if (added) {
        blocks_.push_back(block);
        masks_.push_back(mask);
        return;
    }
    for (std::size_t z = 0; z < mask.size(); ++z) masks_[i][z] |= mask[z];
}


}  // namespace lidarsurf
