#include "lidarsurf/surface/seeded_surface.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <deque>
#include <memory>
#include <optional>
#include <thread>
#include <tuple>
#include <utility>

#if defined(__SSE2__) && !defined(LIDARSURF_SCALAR)
#include <emmintrin.h>
#endif
#include <tbb/concurrent_unordered_map.h>
#include <tbb/concurrent_vector.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "lidarsurf/core/stopwatch.hpp"
#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/core/cube.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"
#include "corner_evaluator.hpp"
#include "cube_search.hpp"

namespace lidarsurf {

using namespace seeded;

namespace {

// The Morton (z-order) code of a block key: the bits of its coordinates (offset to be
// non-negative, 21 bits each) interleaved, so that keys close in space are mostly close in order.
std::uint64_t morton_code(const VoxelKey& key) {
    auto spread = [](std::int32_t c) {
        std::uint64_t v = static_cast<std::uint64_t>(static_cast<std::uint32_t>(c) + (1u << 20)) & 0x1fffffu;
        v = (v | v << 32) & 0x1f00000000ffffull;
        v = (v | v << 16) & 0x1f0000ff0000ffull;
        v = (v | v << 8) & 0x100f00f00f00f00full;
        v = (v | v << 4) & 0x10c30c30c30c30c3ull;
        v = (v | v << 2) & 0x1249249249249249ull;
        return v;
    };
    return spread(key.x()) | spread(key.y()) << 1 | spread(key.z()) << 2;
}


}  // namespace

std::vector<VoxelKey> seeded_cubes(const TsdfField& field, const VoxelGrid& grid, int dilation) {
    CubeSearch search(grid);
    search.seed(grid, dilation);
    // Every vertex is already evaluated.
    struct FieldView {
        TsdfField::Accessor values;
        bool corners(const VoxelKey& cube, CornerValues& s) {
            std::array<const VertexSample*, 8> samples;
            if (!values.corners(cube, samples)) return false;
            for (std::size_t c = 0; c < 8; ++c) s[c] = samples[c]->tsdf;
            return true;
        }
    };
    std::vector<VoxelKey> cubes = search.run(true, 1024, [&] { return FieldView{TsdfField::Accessor(field)}; }, [](const std::vector<VoxelKey>&) {});
    sort_zyx(cubes);
    return cubes;
}

SeededTsdf reference_seeded_tsdf(const VoxelGrid& grid, const SurfaceConfig& config, const Eigen::Vector3d& sensor_world) {
    config.validate();
    const Eigen::Vector3d sensor_local = grid.to_local(sensor_world);
    const Truncation truncation = truncation_of(config, grid);
    tbb::concurrent_unordered_map<VoxelKey, VertexSample, VoxelKeyHash> evaluated;
    CubeSearch search(grid);
    search.seed(grid, config.seed_dilation);
    // Each corner evaluated when a visited cube first needs it (the reference evaluation).
    struct LazyView {
        const VoxelGrid* grid;
        const SurfaceConfig* config;
        const Eigen::Vector3d* sensor;
        const Truncation* truncation;
        tbb::concurrent_unordered_map<VoxelKey, VertexSample, VoxelKeyHash>* evaluated;
        bool corners(const VoxelKey& cube, CornerValues& s) {
            for (std::size_t c = 0; c < 8; ++c) {
                const VoxelKey v = cube + corner_offset(static_cast<int>(c));
                auto it = evaluated->find(v);
                if (it == evaluated->end()) it = evaluated->insert({v, evaluate_vertex(*grid, v, *config, *sensor)}).first;
                if (!truncation->keeps(it->second)) return false;
                s[c] = it->second.tsdf;
            }
            return true;
        }
    };
    SeededTsdf out;
    out.cubes = search.run(true, 256, [&] { return LazyView{&grid, &config, &sensor_local, &truncation, &evaluated}; },
                           [](const std::vector<VoxelKey>&) {});
    sort_zyx(out.cubes);
    std::vector<VoxelKey> keys;
    keys.reserve(evaluated.size());
    for (const auto& [key, sample] : evaluated) keys.push_back(key);
    sort_zyx(keys);
    std::vector<VertexSample> samples;
    samples.reserve(keys.size());
    for (const VoxelKey& key : keys) samples.push_back(evaluated.find(key)->second);
    out.evaluated = keys.size();
    out.field = assemble_field(grid, keys, samples, truncation);
    return out;
}

namespace {

// The blocks an incremental re-mesh must redo (compute_seeded_tsdf's `previous`): the vertex
// blocks within `reach` blocks of a touched voxel block (their windows can see a new point),
// and, as flags per grid block, the voxel blocks within 2 `reach` (what those windows read, packed
// up front; a clean vertex block that `previous` had not evaluated packs what its window needs
// when it is built).
struct DirtyRegion {
    BlockIndex vertex_blocks;
    std::vector<std::uint8_t> eager_blocks;
};
DirtyRegion dirty_region(const VoxelGrid& grid, int reach) {
    DirtyRegion d;
    const BlockKeys& index = grid.index();
    d.eager_blocks.assign(index.block_count(), 0);
    for (std::uint32_t b : grid.touched_blocks()) {
        const VoxelKey key = index.block_keys()[b];
        for (int z = -2 * reach; z <= 2 * reach; ++z)
            for (int y = -2 * reach; y <= 2 * reach; ++y)
                for (int x = -2 * reach; x <= 2 * reach; ++x) {
                    const VoxelKey near = key + VoxelKey(x, y, z);
                    if (std::max({std::abs(x), std::abs(y), std::abs(z)}) <= reach) d.vertex_blocks.try_emplace(near, 0);
                    const std::int64_t i = index.index_of(near);
                    if (i >= 0) d.eager_blocks[static_cast<std::size_t>(i)] = 1;
                }
    }
    return d;
}

// Bit i set when slots[i] >= 0 (a defined vertex), for 64 slots: the slots' sign bits, 4 per
// SSE2 instruction (x86-64's baseline), else one by one.
std::uint64_t defined_bits(const std::int32_t* slots) {
#if defined(__SSE2__) && !defined(LIDARSURF_SCALAR)
    std::uint64_t negative = 0;
    for (int i = 0; i < 64; i += 4)
        negative |= static_cast<std::uint64_t>(_mm_movemask_ps(_mm_castsi128_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(slots + i))))) << i;
    return ~negative;
#else
    std::uint64_t bits = 0;
    for (int i = 0; i < 64; ++i) bits |= static_cast<std::uint64_t>(slots[i] >= 0) << i;
    return bits;
#endif
}

}  // namespace

namespace {
// The grid blocks a region's windows read (creation indices, each once): those within `reach`
// blocks of a vertex block of the region's cubes (a region block or the next one along some axes),
// that is the region's blocks dilated by [-reach, reach + 1], one axis after the other (6 + 2 reach
// keys per block and axis instead of (2 reach + 2)^3 per block).
std::vector<std::uint32_t> blocks_read_by(const VoxelGrid& grid, const SearchRegion& region, int reach) {
    std::vector<VoxelKey> keys = region.blocks();
    for (int axis = 0; axis < 3; ++axis) {
        BlockIndex seen;
        seen.reserve(keys.size() * 2);
        std::vector<VoxelKey> dilated;
        for (const VoxelKey& key : keys)
            for (int d = -reach; d <= reach + 1; ++d) {
                VoxelKey k = key;
                k[axis] += d;
                if (seen.try_emplace(k, 0).second) dilated.push_back(k);
            }
        keys = std::move(dilated);
    }
    std::vector<std::uint32_t> out;
    for (const VoxelKey& key : keys)
        if (const std::int64_t b = grid.index().index_of(key); b >= 0) out.push_back(static_cast<std::uint32_t>(b));
    return out;
}
}  // namespace

SeededTsdf compute_seeded_tsdf(const VoxelGrid& grid, const SurfaceConfig& config, const Eigen::Vector3d& sensor_world,
                               EigenSolver solver, const TsdfField* previous, const SearchRegion* region) {
    config.validate();
    if (previous && region) throw InvalidArgument("compute_seeded_tsdf: a region search does not reuse a previous field");
    SeededTiming timing;
    auto t0 = Clock::now();
    // A window of vertex block b reads the voxel blocks within ceil(max_reach / 8) of b.
    const int reach = (config.max_reach() + BlockMap<std::int32_t>::kSize - 1) / BlockMap<std::int32_t>::kSize;
    const DirtyRegion dirty = previous ? dirty_region(grid, reach) : DirtyRegion{};
    // What the search can visit: the grid's blocks, or the region's.
    const std::size_t search_blocks = region ? region->blocks().size() : grid.index().block_count();
    using Slots = CornerEvaluator::Slots;
    Slots slots(CornerEvaluator::kUnevaluated);
    slots.reserve_blocks(search_blocks * 2);
    // The search's vertex and cube blocks lie within `reach` blocks of the voxel blocks (one more
    // for a cube's far corners): through a dense table of that box, when it is small (a frame's
    // is ~100k cells, 0.4 MB; the hash, which the blocks outside it use, probed ~300k times per
    // KITTI frame). A region's lie within one block of its blocks.
    const std::optional<BlockBox> search_box =
        region ? dense_block_box(region->blocks(), 1, PackedVoxels::kDenseCellsPerBlock, std::size_t{1} << 21)
               : dense_block_box(grid.index().block_keys(), reach + 1, PackedVoxels::kDenseCellsPerBlock, std::size_t{1} << 21);
    if (search_box) slots.use_box(*search_box);
    std::size_t region_voxels = 0;
    if (region)
        for (const VoxelKey& b : region->blocks())
            if (const std::int64_t i = grid.index().index_of(b); i >= 0) region_voxels += static_cast<std::size_t>(popcount(grid.occupancy(static_cast<std::size_t>(i))));
    EvaluatedStore defined_vertices;
    // ~3 per occupied voxel on lidar frames (more grows it). One block reserved up front costs
    // page faults only where written, and avoids the growth's smaller blocks (measured: 10k more
    // page faults per 16 frames without it); capped so a huge grid does not reserve gigabytes.
    defined_vertices.reserve(std::min<std::size_t>(4 * (region ? region_voxels : grid.size()), std::size_t{1} << 22));
    std::atomic<std::size_t> evaluated{0}, reused{0};
    tbb::enumerable_thread_specific<StoreRun> runs;
    tbb::enumerable_thread_specific<NeighbourhoodWindow::ListArena> arenas;  // before `lists`: destroyed after it
    BlockLists lists;
    const PackedVoxels packed = region ? PackedVoxels(grid, blocks_read_by(grid, *region, reach))
                                       : PackedVoxels(grid, previous ? &dirty.eager_blocks : nullptr);
    const CornerEvaluator::Shared shared{slots, packed, config, grid.to_local(sensor_world), solver, truncation_of(config, grid),
                                         defined_vertices, evaluated, previous, dirty.vertex_blocks, reused, runs,
                                         lists, arenas};
    CubeSearch search(grid, search_blocks * 2, region);
    if (search_box) search.visited().use_box(*search_box);
    // One evaluator per thread, for every task and wave: its windows (and their voxel lists and
    // level buffers) stay built from one task to the next.
    tbb::enumerable_thread_specific<std::unique_ptr<CornerEvaluator>> evaluators;
    auto evaluator = [&]() -> CornerEvaluator& {
        std::unique_ptr<CornerEvaluator>& e = evaluators.local();
        if (!e) e = std::make_unique<CornerEvaluator>(shared);
        return *e;
    };

    // Wave 0, the seeds (three quarters of the vertices on a lidar frame), in parallel per block:
    // the seed cubes are the occupied voxels dilated by [-d, d] (block masks, no per-cube
    // hashing). Each seed cube's corners are evaluated lazily, then the cube is classified; the
    // cubes it leads to are visited serially, in block order.
    const int d = config.seed_dilation;
    {
        std::vector<MaskedBlock> seeds;
        if (region) {
            for (std::size_t i = 0; i < region->blocks().size(); ++i) {
                BlockMask mask = dilated_occupancy(grid, region->blocks()[i], -d, d);
                bool any = false;
                for (std::size_t z = 0; z < mask.size(); ++z) any |= (mask[z] &= region->mask(i)[z]) != 0;
                if (any) seeds.push_back({region->blocks()[i], mask});
            }
        } else {
            seeds = dilated_occupancy(grid, -d, d);
        }
        // In Morton order of the block keys, so that the blocks a task takes (and the two
        // threads' ranges) are compact in space and share the voxel records their windows read.
        {
            std::vector<std::pair<std::uint64_t, std::size_t>> order(seeds.size());
            for (std::size_t i = 0; i < seeds.size(); ++i) order[i] = {morton_code(seeds[i].block), i};
            std::sort(order.begin(), order.end());
            std::vector<MaskedBlock> sorted(seeds.size());
            for (std::size_t i = 0; i < seeds.size(); ++i) sorted[i] = seeds[order[i].second];
            seeds = std::move(sorted);
        }
        // Every seed is marked visited before the wave, so that the wave's claims drop the seeds
        // the cubes lead to (three fifths of the cubes they lead to on a KITTI frame). The
        // blocks of the marks and of the seeds' corners are created serially, then filled with
        // their empty values and marked in parallel (filling 5 MB of new slot blocks was most of
        // the setup on a KITTI frame). The seeds' blocks are distinct: one task per seed.
        BlockMap<std::uint8_t>& visited = search.visited();
        std::vector<std::uint32_t> seen_block(seeds.size()), new_slot_blocks;
        const std::size_t first_seen = visited.block_count();
        for (std::size_t i = 0; i < seeds.size(); ++i) {
            seen_block[i] = visited.block_index_unfilled(seeds[i].block).first;
            for_each_corner_block(seeds[i].block, seeds[i].mask, [&](const VoxelKey& b) {
                if (const auto [index, added] = slots.block_index_unfilled(b); added) new_slot_blocks.push_back(index);
            });
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, new_slot_blocks.size(), 32), [&](const auto& r) {
            for (std::size_t j = r.begin(); j != r.end(); ++j) slots.fill_block(new_slot_blocks[j]);
        });
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size(), 64), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                if (seen_block[i] >= first_seen) visited.fill_block(seen_block[i]);  // created above
                BlockMap<std::uint8_t>::Block& seen = visited.block_at(seen_block[i]);
                for_each_bit(seeds[i].mask, [&](int offset) { seen[static_cast<std::size_t>(offset)] = 1; });
            }
        });
        lists.reserve(slots.block_count());
        std::vector<CubeSearch::Part> parts(seeds.size());
        timing.setup = seconds_since(t0);
        t0 = Clock::now();
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size(), 4), [&](const auto& r) {
            CornerEvaluator& corners = evaluator();
            BlockMap<std::uint8_t>::CornerAccessor seen = search.visited_reader();
            // One part per range of seed blocks, kept at the range's first index (the ranges are
            // disjoint and absorb() takes the parts in index order, so the cubes come in seed
            // order as with a part per seed): a part per seed was 2 allocations per seed block,
            // and freeing them, serially after the wave, took ~0.3 ms of a KITTI frame.
            CubeSearch::Part& part = parts[r.begin()];
            std::size_t n = 0;
            for (std::size_t i = r.begin(); i != r.end(); ++i) n += static_cast<std::size_t>(popcount(seeds[i].mask));
            part.active.reserve(n);  // as in the later waves
            part.next.reserve(n);
            for (std::size_t i = r.begin(); i != r.end(); ++i)
                for_each_bit(seeds[i].mask, [&](int offset) { search.examine(corners, Slots::key_at(seeds[i].block, offset), true, part, seen); });
        });
        timing.seed_wave = seconds_since(t0);
        t0 = Clock::now();
        search.absorb(parts, search.wave());
        timing.serial = seconds_since(t0);
    }
    // The later waves (about two fifths of a KITTI frame's vertices, ~20 small waves; the
    // seed wave and these are timed apart, SeededTiming): the corners' blocks are
    // created serially (one lookup per cube unless it is a block's last on some axis, or the
    // block changes), then each cube's corners are evaluated lazily and the cube classified, in
    // parallel chunks of a few cubes.
    Slots::WriteAccessor slot_blocks(slots);  // remembers the blocks met recently, from wave to wave
    // Most cubes' corner blocks exist already (nine in ten on a KITTI frame): they are looked for
    // in parallel (reads only), and the cubes with a missing one are then visited serially, in
    // wave order, to create them. Flags per chunk of the wave, then per cube of the chunks with a
    // miss.
    std::vector<std::uint8_t> missing;
    auto before_wave = [&](const std::vector<VoxelKey>& cubes) {
        missing.assign(cubes.size(), 0);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cubes.size(), 2048), [&](const auto& r) {
            std::optional<VoxelKey> last;  // a block found to exist
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const VoxelKey block = Slots::block_of(cubes[i]);
                if (Slots::last_axes(cubes[i]) == 0 && last && same_key(*last, block)) continue;  // all its corners in `block`
                bool all = true;
                for_each_corner_block(cubes[i], [&](const VoxelKey& b) { all = all && slots.find_block(b); });
                missing[i] = !all;
                if (all) last = block;
            }
        });
        for (std::size_t i = 0; i < cubes.size(); ++i)
            if (missing[i]) for_each_corner_block(cubes[i], [&](const VoxelKey& b) { slot_blocks.block_index(b); });
        lists.reserve(slots.block_count());
    };
    SeededTsdf out;
    out.cubes = search.run(false, 64, evaluator, before_wave);
    evaluators.clear();  // adds their counts
    out.evaluated = evaluated.load();
    out.reused = reused.load();
    timing.later_waves = search.seconds_parallel();
    timing.serial += search.seconds_serial();
    t0 = Clock::now();

    // The field: the defined evaluated vertices, ordered by slot (blocks in z, y, x order of their
    // keys, then offset), which does not depend on the thread count or on the threads' timing
    // (the blocks' creation order does: it follows the waves' order, run()). Assembled while
    // another task sorts the active cubes: the sort is serial (~1 ms on a KITTI frame), and run
    // after the waves it left one of the two cores idle.
    std::vector<VoxelKey> field_keys;
    std::vector<VertexSample> field_samples;
    auto assemble = [&] {
        // The first pass counts each block's defined slots and keeps them as a bit mask (one word per
        // 64 slots, branch-free), so that the second visits only those (a twelfth of the slots on a
        // KITTI frame) instead of testing every slot again.
        const std::size_t nblocks = slots.block_count();
        constexpr std::size_t kWords = Slots::kVolume / 64;
        std::vector<std::size_t> block_start(nblocks, 0);
        std::vector<std::array<std::uint64_t, kWords>> defined_mask(nblocks);
        std::vector<std::uint32_t> order(nblocks);  // the blocks by key
        for (std::size_t b = 0; b < nblocks; ++b) order[b] = static_cast<std::uint32_t>(b);
        const std::vector<VoxelKey>& block_keys = slots.block_keys();
        std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
            const VoxelKey &ka = block_keys[a], &kb = block_keys[b];
            return std::tie(ka.z(), ka.y(), ka.x()) < std::tie(kb.z(), kb.y(), kb.x());
        });
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks, 16), [&](const auto& r) {
            for (std::size_t b = r.begin(); b != r.end(); ++b) {
                const Slots::Block& block = slots.block_at(b);
                std::size_t count = 0;
                for (std::size_t w = 0; w < kWords; ++w) {
                    const std::uint64_t bits = defined_bits(block.data() + 64 * w);
                    defined_mask[b][w] = bits;
                    count += static_cast<std::size_t>(std::popcount(bits));
                }
                block_start[b] = count;
            }
        });
        std::size_t defined = 0;  // the blocks' counts to their starts, in key order
        for (const std::uint32_t b : order) defined += std::exchange(block_start[b], defined);
        field_keys.resize(defined);
        field_samples.resize(defined);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nblocks, 16), [&](const auto& r) {
            for (std::size_t b = r.begin(); b != r.end(); ++b) {
                Slots::Block& block = slots.block_at(b);
                std::size_t at = block_start[b];
                for (std::size_t w = 0; w < kWords; ++w)
                    for (std::uint64_t bits = defined_mask[b][w]; bits; bits &= bits - 1, ++at) {
                        std::int32_t& slot = block[64 * w + static_cast<std::size_t>(std::countr_zero(bits))];
                        const Evaluated& e = defined_vertices[static_cast<std::size_t>(slot)];
                        slot = static_cast<std::int32_t>(at);
                        field_keys[at] = e.key;
                        field_samples[at] = e.sample;
                    }
            }
        });
    };
    tbb::parallel_invoke([&] { sort_zyx(out.cubes); }, assemble);
    out.field = TsdfField(std::move(slots), std::move(field_keys), std::move(field_samples), grid.voxel_size(), grid.origin());
    timing.field = seconds_since(t0);
    out.timing = timing;
    return out;
}

}  // namespace lidarsurf
