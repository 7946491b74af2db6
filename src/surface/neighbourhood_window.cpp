#include "lidarsurf/surface/neighbourhood_window.hpp"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <memory>
#include <new>
#include <string>

#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"
#include "list_kernels.hpp"
#include "raw_sums.hpp"

namespace lidarsurf {

VoxelStats Moments::to_stats(const Eigen::Vector3d& p) const {
    VoxelStats s;
    if (n <= 0) return s;
    s.count = static_cast<std::uint64_t>(n);
    const Eigen::Vector3d d = s1 / n;
    s.mean = p + d;
    s.scatter = SymmetricMatrix3::upper_of(s2 - s1 * d.transpose());  // sum (x-p)(x-p)^T - n d d^T = sum (x-mu)(x-mu)^T
    return s;
}

using namespace window;

namespace {
using Map = BlockMap<std::int32_t>;


// Padding of the voxel list: a coordinate whose level, at least max(v, 201) - min(v, 200) >=
// 201 - 71 for any vertex coordinate v <= K + 7 <= 71 (K <= 64), exceeds every level asked; real
// coordinates are < 2 K + 7 <= 135.
constexpr std::uint8_t kPad = 200;
// Whether the box [l, h] (window coordinates) leaves the window [0, size)^3: one test rather than
// Eigen's any(), which branches per coordinate.
inline bool outside_window(const VoxelKey& l, const VoxelKey& h, int size) {
    return ((l.x() | l.y() | l.z()) < 0) | (std::max({h.x(), h.y(), h.z()}) >= size);
}
// A layer of a window block that holds voxels of the list's region (build_list).
struct LayerBits {
    const PackedVoxels::Block* block;
    int bx, by, z;
    std::uint64_t bits;
};
// What a window block that holds no voxel points to: no layer holds a voxel, so the walks skip it
// with the test of its layers they make anyway (a separate test for an absent block mispredicted
// as often).
const PackedVoxels::Block kNoVoxels{};

}  // namespace

NeighbourhoodWindow::NeighbourhoodWindow(const PackedVoxels& voxels, const VoxelKey& vertex_block, int max_level, int cube_level)
    : voxels_(&voxels), alpha_(voxels.grid().voxel_size()), cube_level_(cube_level < 0 ? max_level : cube_level) {
    if (max_level < 1 || max_level > 64 || cube_level_ < 1 || cube_level_ > max_level)
        throw InvalidArgument("neighbourhood window: need 1 <= cube_level <= max_level <= 64 (got cube_level " + std::to_string(cube_level_) +
                              ", max_level " + std::to_string(max_level) + ")");
    // H^k(v) = voxels [v-k, v+k-1]: for v in [8b, 8b+7] that is [8b-k, 8b+6+k], within
    // radius ceil(k/8) blocks of b.
    radius_ = (max_level + Map::kSize - 1) / Map::kSize;
    side_ = 2 * radius_ + 1;
    reset(vertex_block);
}

void NeighbourhoodWindow::reset(const VoxelKey& vertex_block) {
    vertex_block_ = vertex_block;
    first_voxel_ = (vertex_block.array() - radius_) * Map::kSize;
    // Every block "not looked up yet": a new stamp (a window is reset ~12k times per KITTI frame;
    // writing its 125 entries each time was 12 MB of stores), the entries once when it wraps.
    const auto volume = static_cast<std::size_t>(side_ * side_ * side_);
    if (blocks_.size() != volume || ++stamp_ == 0) {
        blocks_.assign(volume, WindowBlock{});
        stamp_ = 1;
    }
    simd_ = simd_level();
    shared_ = nullptr;
    arena_ = nullptr;
    list_ = nullptr;
    levels_valid_ = false;
}

void NeighbourhoodWindow::share_list(SharedList* list, ListArena* arena) {
    shared_ = list;
    arena_ = arena;
    list_ = nullptr;
    levels_valid_ = false;
}

inline const PackedVoxels::Block* NeighbourhoodWindow::block(int bx, int by, int bz) const {
    WindowBlock& b = blocks_[static_cast<std::size_t>(bx + side_ * (by + side_ * bz))];
    if (b.stamp != stamp_) [[unlikely]]
        b = {look_up(bx, by, bz), stamp_};
    return b.block;
}

const PackedVoxels::Block* NeighbourhoodWindow::look_up(int bx, int by, int bz) const {
    const PackedVoxels::Block* b = voxels_->find(Map::block_of(first_voxel_) + VoxelKey(bx, by, bz));
    return b ? b : &kNoVoxels;
}

template <typename F>
void NeighbourhoodWindow::for_each_block(const VoxelKey& l, const VoxelKey& h, F&& f) const {
    constexpr int B = Map::kSize, m = B - 1;
    for (int bz = l.z() / B; bz <= h.z() / B; ++bz)
        for (int by = l.y() / B; by <= h.y() / B; ++by)
            for (int bx = l.x() / B; bx <= h.x() / B; ++bx) {
                const PackedVoxels::Block* block = this->block(bx, by, bz);
                // The box's layers within this block that hold a voxel (most blocks of a lidar
                // frame hold a few layers of ground or facade): the others are skipped.
                const int z0 = std::max(l.z(), bz * B), z1 = std::min(h.z(), bz * B + m);
                const unsigned layers = block->layers & ((0xffu >> (m - ((z1 - z0) & m))) << (z0 & m));
                if (!layers) continue;
                // The box within this block, as an 8x8 layer mask.
                const int x0 = std::max(l.x(), bx * B), x1 = std::min(h.x(), bx * B + m);
                const int y0 = std::max(l.y(), by * B), y1 = std::min(h.y(), by * B + m);
                f(*block, VoxelKey(bx, by, bz), layers, layer_mask(x0 & m, x1 & m, y0 & m, y1 & m));
            }
}

void NeighbourhoodWindow::add_shell(const VoxelKey& lo, const VoxelKey& hi, int inset, const Eigen::Vector3d& p,
                                    Moments& acc) const {
    constexpr int B = Map::kSize, m = B - 1;
    const VoxelKey l = lo - first_voxel_, h = hi - first_voxel_;  // window coordinates
    if (outside_window(l, h, side_ * B))
        throw InvalidArgument("neighbourhood box beyond the window's blocks: build the window with the configuration's max_reach()");
    // The hole: [l + inset, h - inset] in x and y, on the layers strictly inside [l.z, h.z].
    const VoxelKey il = l.array() + inset, ih = h.array() - inset;
    RawSums sums(acc, p);
    for_each_block(l, h, [&](const PackedVoxels::Block& block, const VoxelKey& b, unsigned layers, std::uint64_t full) {
        std::uint64_t ring = full;
        const int hx0 = std::max(il.x(), b.x() * B), hx1 = std::min(ih.x(), b.x() * B + m);
        const int hy0 = std::max(il.y(), b.y() * B), hy1 = std::min(ih.y(), b.y() * B + m);
        if (inset > 0 && hx0 <= hx1 && hy0 <= hy1) ring &= ~layer_mask(hx0 & m, hx1 & m, hy0 & m, hy1 & m);
        for (; layers; layers &= layers - 1) {
            const int layer = std::countr_zero(layers), z = b.z() * B + layer;
            const bool cap = inset == 0 || z == l.z() || z == h.z();
            for (std::uint64_t bits = (*block.occupancy)[static_cast<std::size_t>(layer)] & (cap ? full : ring); bits; bits &= bits - 1)
                sums.add(block.at(std::countr_zero(bits) | (layer << 6)));
        }
    });
    sums.store(acc);
}

void NeighbourhoodWindow::add_slab(const VoxelKey& lo, const VoxelKey& hi, bool ring, const Eigen::Vector3d& p, Moments& acc) const {
#if defined(LIDARSURF_SSE2)
    if (simd_ >= SimdLevel::Avx2) return add_slab_v3(lo, hi, ring, p, acc);
#endif
    add_slab_walk<false>(lo, hi, ring, p, acc);
}

#if defined(LIDARSURF_SSE2)
// flatten: the walk and RawSums4's methods (which need AVX2) are inlined here, where it is on.
[[gnu::target(LIDARSURF_AVX2_TARGET), gnu::flatten]] void NeighbourhoodWindow::add_slab_v3(const VoxelKey& lo, const VoxelKey& hi, bool ring,
                                                                             const Eigen::Vector3d& p, Moments& acc) const {
    add_slab_walk<true>(lo, hi, ring, p, acc);
}
#endif

template <bool Popcount>
[[gnu::always_inline]] inline void NeighbourhoodWindow::add_slab_walk(const VoxelKey& lo, const VoxelKey& hi, bool ring, const Eigen::Vector3d& p,
                                                                      Moments& acc) const {
    constexpr int B = Map::kSize, m = B - 1;
    const VoxelKey l = lo - first_voxel_, h = hi - first_voxel_;  // window coordinates
    if (outside_window(l, h, side_ * B))
        throw InvalidArgument("neighbourhood box beyond the window's blocks: build the window with the configuration's max_reach()");
    SumsFor<Popcount> sums(acc, p);
    const int bx0 = l.x() / B, bx1 = h.x() / B;
    for (int bz = l.z() / B; bz <= h.z() / B; ++bz) {
        // The slab's layers in this block, as a bit mask of layer indices.
        const int z0 = std::max(l.z(), bz * B) & m, z1 = std::min(h.z(), bz * B + m) & m;
        const unsigned slab_layers = (0xffu >> (m - (z1 - z0))) << z0;
        for (int by = l.y() / B; by <= h.y() / B; ++by) {
            const std::uint64_t rows = layer_rows(std::max(l.y(), by * B) & m, std::min(h.y(), by * B + m) & m);
            const int hy0 = std::max(l.y() + 1, by * B), hy1 = std::min(h.y() - 1, by * B + m);
            const std::uint64_t hole_rows = ring && hy0 <= hy1 ? layer_rows(hy0 & m, hy1 & m) : 0;
            for (int bx = bx0; bx <= bx1; ++bx) {
                const PackedVoxels::Block* block = this->block(bx, by, bz);
                unsigned layers = block->layers & slab_layers;
                if (!layers) continue;
                std::uint64_t mask = layer_columns(std::max(l.x(), bx * B) & m, std::min(h.x(), bx * B + m) & m) & rows;
                const int hx0 = std::max(l.x() + 1, bx * B), hx1 = std::min(h.x() - 1, bx * B + m);
                if (hole_rows && hx0 <= hx1) mask &= ~(layer_columns(hx0 & m, hx1 & m) & hole_rows);
                for (; layers; layers &= layers - 1) {
                    const int layer = std::countr_zero(layers);
                    for (std::uint64_t bits = (*block->occupancy)[static_cast<std::size_t>(layer)] & mask; bits; bits &= bits - 1) {
                        if constexpr (Popcount)
                            sums.add(block->at_layer_bit(layer, std::countr_zero(bits)));
                        else
                            sums.add(block->at(std::countr_zero(bits) | (layer << 6)));
                    }
                }
            }
        }
    }
    sums.store(acc);
}

void* NeighbourhoodWindow::ListArena::allocate(std::size_t bytes) {
    constexpr std::size_t kAlign = alignof(std::max_align_t), kChunk = std::size_t{1} << 18;
    bytes = (bytes + kAlign - 1) / kAlign * kAlign;
    if (bytes > left_) {
        // A new chunk (new[] aligns for any type); a request of over a quarter chunk gets its own,
        // so a chunk's unused tail stays under a quarter of it.
        const std::size_t size = bytes > kChunk / 4 ? bytes : kChunk;
        chunks_.push_back(std::make_unique_for_overwrite<std::byte[]>(size));
        if (size != kChunk) return chunks_.back().get();  // the current chunk stays current
        next_ = chunks_.back().get();
        left_ = size;
    }
    void* at = next_;
    next_ += bytes;
    left_ -= bytes;
    return at;
}

NeighbourhoodWindow::VoxelList NeighbourhoodWindow::VoxelList::padding(std::size_t size, std::uint8_t pad, ListArena* arena) {
    VoxelList l;
    l.size = size;
    const std::size_t bytes = size * (sizeof(const PackedVoxels::Voxel*) + 4);
    std::byte* storage;
    if (arena) {
        storage = static_cast<std::byte*>(arena->allocate(bytes));
        l.in_arena_ = true;
    } else {
        l.storage_ = std::make_unique_for_overwrite<std::byte[]>(bytes);
        storage = l.storage_.get();
    }
    l.records = reinterpret_cast<const PackedVoxels::Voxel**>(storage);  // at the allocation's start: aligned
    std::fill_n(l.records, size, nullptr);
    l.x = reinterpret_cast<std::uint8_t*>(l.records + size);
    l.y = l.x + size;
    l.z = l.y + size;
    l.weight = l.z + size;
    std::fill_n(l.x, 3 * size, pad);
    std::fill_n(l.weight, size, std::uint8_t{0});
    return l;
}

NeighbourhoodWindow::VoxelList NeighbourhoodWindow::build_list(ListArena* arena) const {
    constexpr int B = Map::kSize, m = B - 1;
    // The region [8b - K, 8b + 6 + K]^3, in window coordinates.
    const VoxelKey first = vertex_block_ * B - first_voxel_;  // the vertex block's first vertex
    const VoxelKey l = first.array() - cube_level_, h = first.array() + (6 + cube_level_);
    // The region's layers (one pass over the blocks), then their voxels (one allocation for all the
    // arrays, in `arena` when given).
    // A scratch array per thread, reused from list to list: a vector per list, grown by doubling,
    // was about five allocations per list, half of a KITTI frame's allocations.
    thread_local std::vector<LayerBits> layers;
    layers.clear();
    std::size_t count = 0;
    for_each_block(l, h, [&](const PackedVoxels::Block& block, const VoxelKey& b, unsigned in_box, std::uint64_t full) {
        for (; in_box; in_box &= in_box - 1) {
            const int layer = std::countr_zero(in_box);
            if (const std::uint64_t bits = (*block.occupancy)[static_cast<std::size_t>(layer)] & full) {
                layers.push_back({&block, b.x(), b.y(), b.z() * B + layer, bits});
                count += static_cast<std::size_t>(std::popcount(bits));
            }
        }
    });
    VoxelList list = VoxelList::padding((count + kLanes - 1) / kLanes * kLanes, kPad, arena);
    std::size_t at = 0;
    for (const LayerBits& layer : layers) {
        const auto z = static_cast<std::uint8_t>(layer.z - l.z());
        const int x0 = layer.bx * B - l.x(), y0 = layer.by * B - l.y(), offset = (layer.z & m) << 6;
        for (std::uint64_t bits = layer.bits; bits; bits &= bits - 1, ++at) {
            const int bit = std::countr_zero(bits);
            list.x[at] = static_cast<std::uint8_t>(x0 + (bit & m));
            list.y[at] = static_cast<std::uint8_t>(y0 + (bit >> 3));
            list.z[at] = z;
            list.records[at] = &layer.block->at(bit | offset);
            list.weight[at] = static_cast<std::uint8_t>(std::min(list.records[at]->count, 255.0));
        }
    }
    return list;
}

inline const NeighbourhoodWindow::VoxelList& NeighbourhoodWindow::list() const {
    if (list_) [[likely]]
        return *list_;
    return first_list();
}

const NeighbourhoodWindow::VoxelList& NeighbourhoodWindow::first_list() const {
    if (!shared_) {
        own_ = build_list();
        list_ = &own_;
        return own_;
    }
    const VoxelList* published = shared_->list_.load(std::memory_order_acquire);
    if (!published) {
        // In the arena (the list's header too) when there is one, else on the heap.
        const VoxelList* mine = arena_ ? new (arena_->allocate(sizeof(VoxelList))) VoxelList(build_list(arena_)) : new VoxelList(build_list());
        if (shared_->list_.compare_exchange_strong(published, mine, std::memory_order_acq_rel, std::memory_order_acquire))
            published = mine;
        else if (!mine->in_arena())  // `published` is another thread's identical list; a copy in the arena stays there unused
            delete mine;
    }
    list_ = published;
    return *list_;
}

bool NeighbourhoodWindow::listed(const VoxelKey& v, int k) const {
    return k >= 1 && k <= cube_level_ && same_key(Map::block_of(v), vertex_block_);
}

const std::uint8_t* NeighbourhoodWindow::levels(const VoxelKey& v) const {
    const VoxelList& list = this->list();
    if (levels_valid_ && same_key(level_vertex_, v)) return levels_.data();
    const VoxelKey r = (v - vertex_block_ * Map::kSize).array() + cube_level_;  // region coordinates, in [K, K + 7]
    const ListArrays arrays = arrays_of(list);
    if (levels_.size() < arrays.count) levels_.resize(arrays.count);
    // With the levels, the points of H^1(v) and H^2(v) (first_counted_level).
#if defined(LIDARSURF_SSE2)
    const LevelCounts n = simd_ == SimdLevel::Avx512 ? levels_avx512(arrays, r, levels_.data())
                          : simd_ == SimdLevel::Avx2 ? levels_avx2(arrays, r, levels_.data())
                                                     : levels_sse2(arrays, r, levels_.data());
#else
    const LevelCounts n = levels_portable(arrays, r, levels_.data());
#endif
    count1_ = n.in1;
    count2_ = n.in2;
    level_vertex_ = v;
    levels_valid_ = true;
    return levels_.data();
}

int NeighbourhoodWindow::first_counted_level(const VoxelKey& v, int n_min) const {
    if (n_min > 255) return 1;  // the weights saturate at 255
    levels(v);
    if (count1_ >= n_min) return 1;
    if (count2_ >= n_min || cube_level_ < 2) return 2;
    return 3;
}

void NeighbourhoodWindow::add_listed(const VoxelKey& v, int k, bool whole, Moments& acc) const {
    const std::uint8_t* levels = this->levels(v);
    const ListArrays arrays = arrays_of(list());
    const Eigen::Vector3d p = v.cast<double>() * alpha_;
    const int lo = whole ? 1 : k;
#if defined(LIDARSURF_SSE2)
    if (simd_ == SimdLevel::Avx512)
        add_listed_avx512(arrays, levels, lo, k, p, acc);
    else if (simd_ == SimdLevel::Avx2)
        add_listed_avx2(arrays, levels, lo, k, p, acc);
    else
        add_listed_sse2(arrays, levels, lo, k, p, acc);
#else
    add_listed_portable(arrays, levels, lo, k, p, acc);
#endif
}

void NeighbourhoodWindow::grow(const VoxelKey& v, int k, Moments& acc) const {
    // H^k \ H^{k-1} = {L = k} (every listed voxel has L >= 1, so k = 1 gives H^1).
    if (listed(v, k)) return add_listed(v, k, false, acc);
    // Otherwise: the box [v-k, v+k-1] without its interior [v-k+1, v+k-2] (empty for k = 1).
    add_shell(v.array() - k, v.array() + (k - 1), k > 1 ? 1 : 0, v.cast<double>() * alpha_, acc);
}

Moments NeighbourhoodWindow::box(const VoxelKey& v, int k) const {
    Moments acc;
    if (listed(v, k))
        add_listed(v, k, true, acc);
    else
        add_shell(v.array() - k, v.array() + (k - 1), 0, v.cast<double>() * alpha_, acc);
    return acc;
}

Moments NeighbourhoodWindow::slab(const VoxelKey& v, int k, SlabExtension e) const {
    Moments acc;
    const VoxelBox b = slab_box(v, k, e);
    add_slab(b.lo, b.hi, false, v.cast<double>() * alpha_, acc);
    return acc;
}

Moments NeighbourhoodWindow::sum_box(const VoxelBox& b, const VoxelKey& v) const {
    Moments acc;
    add_slab(b.lo, b.hi, false, v.cast<double>() * alpha_, acc);
    return acc;
}

void NeighbourhoodWindow::grow_slab(const VoxelKey& v, int k, Moments& acc, SlabExtension e) const {
    // S^k \ S^{k-1}: the x-y ring of width one around S^{k-1}'s x-y range, on both layers.
    const VoxelBox b = slab_box(v, k, e);
    add_slab(b.lo, b.hi, true, v.cast<double>() * alpha_, acc);
}

}  // namespace lidarsurf
