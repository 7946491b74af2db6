#include "lidarsurf/surface/seeded_surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/block_mask.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"

namespace lidarsurf {

namespace {

VoxelKey corner(const VoxelKey& base, int c) { return base + VoxelKey(c & 1, (c >> 1) & 1, (c >> 2) & 1); }
// The corners of a cube whose coordinates are all even / all odd: the base rounded up to even /
// to odd per axis. Every cube has exactly one of each; they are the lazy evaluation's probes.
VoxelKey even_corner(const VoxelKey& base) { return {base.x() + (base.x() & 1), base.y() + (base.y() & 1), base.z() + (base.z() & 1)}; }
VoxelKey odd_corner(const VoxelKey& base) { return {base.x() + 1 - (base.x() & 1), base.y() + 1 - (base.y() & 1), base.z() + 1 - (base.z() & 1)}; }

// The 6 faces: corner indices and the direction to the neighbouring cube.
struct Face {
    std::array<int, 4> corners;
    VoxelKey step;
};
const std::array<Face, 6>& faces() {
    static const std::array<Face, 6> f{{
        {{0, 2, 4, 6}, VoxelKey(-1, 0, 0)},
        {{1, 3, 5, 7}, VoxelKey(1, 0, 0)},
        {{0, 1, 4, 5}, VoxelKey(0, -1, 0)},
        {{2, 3, 6, 7}, VoxelKey(0, 1, 0)},
        {{0, 1, 2, 3}, VoxelKey(0, 0, -1)},
        {{4, 5, 6, 7}, VoxelKey(0, 0, 1)},
    }};
    return f;
}

bool zyx_less(const VoxelKey& a, const VoxelKey& b) {
    if (a.z() != b.z()) return a.z() < b.z();
    if (a.y() != b.y()) return a.y() < b.y();
    return a.x() < b.x();
}

// What one cube of a wave tells the search, given `lookup(v)`, the sample of vertex v (nullptr if
// undefined): active(cube) when the surface crosses it, and next(c) for each cube it leads to,
// through each face the surface crosses. A surface through a seed's corner (|value| <= eps, e.g.
// data lying on a lattice plane) may cross only the neighbouring cubes (zero counts as
// positive): when `seeding`, the 8 cubes around such a corner are next as well.
template <typename Lookup, typename Active, typename Next>
void classify_cube(const VoxelKey& cube, bool seeding, double eps, Lookup&& lookup, Active&& active, Next&& next) {
    std::array<const VertexSample*, 8> s{};
    int negatives = 0;
    for (int c = 0; c < 8; ++c) {
        s[c] = lookup(corner(cube, c));
        if (!s[c]) return;
        negatives += s[c]->tsdf < 0;
    }
    if (negatives == 0 || negatives == 8) {
        if (!seeding) return;
        for (int c = 0; c < 8; ++c) {
            if (!(std::fabs(s[c]->tsdf) <= eps)) continue;
            const VoxelKey v = corner(cube, c);
            for (int n = 0; n < 8; ++n) next(v - VoxelKey(n & 1, (n >> 1) & 1, (n >> 2) & 1));  // the 8 cubes around v
        }
        return;
    }
    active(cube);
    for (const Face& f : faces()) {
        int neg = 0;
        for (int c : f.corners) neg += s[c]->tsdf < 0;
        if (neg != 0 && neg != 4) next(cube + f.step);
    }
}

// The breadth-first search over cubes, independent of how vertex values are obtained.
class CubeSearch {
public:
    explicit CubeSearch(const VoxelGrid& grid) : eps_(1e-6 * grid.voxel_size()), seen_of_(visited_) {
        visited_.reserve_blocks(grid.index().block_count() * 2);
    }
    double eps() const { return eps_; }
    BlockMap<std::uint8_t>& visited() { return visited_; }
    std::vector<VoxelKey>& wave() { return wave_; }
    std::vector<VoxelKey>& active() { return active_; }

    /// Adds `cube` to `out` unless it was visited before.
    void visit(const VoxelKey& cube, std::vector<VoxelKey>& out) {
        std::uint8_t& seen = seen_of_[cube];
        if (!seen) {
            seen = 1;
            out.push_back(cube);
        }
    }
    /// The seeds, one by one: the cubes within `dilation` of an occupied voxel.
    void seed(const VoxelGrid& grid, int dilation) {
        for (const VoxelKey& k : grid.keys())
            for (int z = -dilation; z <= dilation; ++z)
                for (int y = -dilation; y <= dilation; ++y)
                    for (int x = -dilation; x <= dilation; ++x) visit(k + VoxelKey(x, y, z), wave_);
    }
    /// Runs the waves from wave(); `prepare(cubes)` is called before a wave of cubes is examined,
    /// so that a lazy implementation can evaluate their corners first. `make_lookup()` gives a
    /// lookup for one thread: a large wave is examined in parallel chunks, and the cubes they lead
    /// to are visited in chunk order (the serial order). Returns the active cubes.
    template <typename MakeLookup, typename Prepare>
    std::vector<VoxelKey> run(bool seeding, MakeLookup&& make_lookup, Prepare&& prepare) {
        constexpr std::size_t kChunk = 1024;
        std::vector<VoxelKey> next;
        std::vector<std::vector<VoxelKey>> actives, nexts;
        while (!wave_.empty()) {
            prepare(wave_);
            const std::size_t chunks = (wave_.size() + kChunk - 1) / kChunk;
            actives.assign(chunks, {});
            nexts.assign(chunks, {});
            tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
                auto lookup = make_lookup();
                for (std::size_t i = c * kChunk; i < std::min(wave_.size(), (c + 1) * kChunk); ++i)
                    classify_cube(
                        wave_[i], seeding, eps_, lookup, [&](const VoxelKey& a) { actives[c].push_back(a); },
                        [&](const VoxelKey& n) { nexts[c].push_back(n); });
            });
            next.clear();
            for (std::size_t c = 0; c < chunks; ++c) {
                active_.insert(active_.end(), actives[c].begin(), actives[c].end());
                for (const VoxelKey& n : nexts[c]) visit(n, next);
            }
            std::swap(wave_, next);
            seeding = false;
        }
        // Which cubes are reached does not depend on the order of the waves; the sort makes the
        // output (and so the mesh's vertex and triangle order) deterministic.
        tbb::parallel_sort(active_.begin(), active_.end(), zyx_less);
        return std::move(active_);
    }

private:
    double eps_;
    BlockMap<std::uint8_t> visited_{0};
    BlockMap<std::uint8_t>::WriteAccessor seen_of_;
    std::vector<VoxelKey> wave_, active_;
};

}  // namespace

std::vector<VoxelKey> seeded_cubes(const TsdfField& field, const VoxelGrid& grid, int dilation) {
    CubeSearch search(grid);
    search.seed(grid, dilation);
    auto make_lookup = [&] { return [values = TsdfField::Accessor(field)](const VoxelKey& v) mutable { return values.find(v); }; };
    return search.run(true, make_lookup, [](const std::vector<VoxelKey>&) {});
}

SeededTsdf compute_seeded_tsdf(const VoxelGrid& grid, const ReconstructionConfig& config, const Eigen::Vector3d& sensor_world,
                               EigenSolver solver) {
    config.validate();
    const Eigen::Vector3d sensor_local = grid.to_local(sensor_world);
    const double truncation = config.truncation_distance();
    // Every vertex the search asks for, in evaluation order, and a block map from vertex to its
    // position there (or one of the states below).
    constexpr std::int32_t kUnevaluated = -1, kQueued = -2, kUndefined = -3;
    using Slots = BlockMap<std::int32_t>;
    Slots slots(kUnevaluated);
    slots.reserve_blocks(grid.index().block_count() * 2);
    std::vector<VoxelKey> keys;
    std::vector<VertexSample> samples;
    // Vertices to evaluate in this wave, grouped by vertex block so that each group shares one
    // NeighbourhoodWindow (no hashing in the neighbourhood sums).
    std::vector<std::vector<std::uint16_t>> pending;
    std::vector<std::uint32_t> pending_blocks;
    std::vector<std::size_t> pending_base;
    std::vector<std::pair<std::size_t, std::size_t>> tasks;  // (pending block, first vertex)
    const PackedVoxels packed(grid);
    // About 3.5 evaluated vertices per voxel on lidar frames: reserving avoids regrowing (and
    // copying) the arrays wave after wave.
    keys.reserve(4 * grid.size());
    samples.reserve(4 * grid.size());
    // Evaluates the pending vertices, in parallel (tasks of a few dozen vertices of one block).
    auto evaluate_pending = [&] {
        pending_base.resize(pending_blocks.size());
        std::size_t total = samples.size();
        for (std::size_t i = 0; i < pending_blocks.size(); ++i) {
            pending_base[i] = total;
            total += pending[pending_blocks[i]].size();
        }
        keys.resize(total);
        samples.resize(total);
        // Tasks of at most kTask vertices of one block, so that a wave of a few blocks (the long
        // tail of the search) still keeps every thread busy.
        constexpr std::size_t kTask = 48;
        tasks.clear();
        for (std::size_t i = 0; i < pending_blocks.size(); ++i)
            for (std::size_t b = 0; b < pending[pending_blocks[i]].size(); b += kTask) tasks.push_back({i, b});
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1), [&](const auto& r) {
            for (std::size_t t = r.begin(); t != r.end(); ++t) {
                const auto [i, first] = tasks[t];
                const std::uint32_t bi = pending_blocks[i];
                const VoxelKey block_key = slots.block_keys()[bi];
                const NeighbourhoodWindow window(packed, block_key, config.max_level());
                Slots::Block& block = slots.block_at(bi);
                const std::vector<std::uint16_t>& offsets = pending[bi];
                const std::size_t last = std::min(offsets.size(), first + kTask);
                for (std::size_t j = first; j < last; ++j) {
                    const std::uint16_t offset = offsets[j];
                    const std::size_t at = pending_base[i] + j;
                    const VoxelKey v = Slots::key_at(block_key, offset);
                    VertexSample s = evaluate_vertex(window, v, config, sensor_local, solver);
                    if (s.defined && !(std::fabs(s.tsdf) <= truncation)) s.defined = false;  // as assemble_field
                    keys[at] = v;
                    samples[at] = s;
                    block[offset] = s.defined ? static_cast<std::int32_t>(at) : kUndefined;
                }
            }
        });
        for (std::uint32_t bi : pending_blocks) pending[bi].clear();
        pending_blocks.clear();
    };
    auto lookup_in = [&](Slots::Accessor& values, const VoxelKey& v) -> const VertexSample* {
        const std::int32_t* slot = values.find(v);
        return slot && *slot >= 0 ? &samples[static_cast<std::size_t>(*slot)] : nullptr;
    };
    CubeSearch search(grid);

    // Wave 0, the seeds, in parallel per block (three quarters of the vertices on a lidar frame):
    // the seed cubes are the occupied voxels dilated by [-d, d], so their corners are the occupied
    // voxels dilated by [-d, d + 1] (block masks, no per-cube hashing). A cube with an undefined
    // corner cannot be active, so the corners are evaluated in three passes: each cube's all-even
    // corner, then the all-odd corner of the cubes whose all-even one is defined, then the other
    // six corners of the cubes whose two probes are defined. A corner skipped this way is
    // evaluated later if a wave needs it. Skipped vertices are mostly undefined ones, the dearest
    // (every level fails up to k_max).
    const int d = config.seed_dilation;
    {
        const std::vector<MaskedBlock> corners = dilated_occupancy(grid, -d, d + 1);
        std::vector<std::uint32_t> block_of_corners(corners.size());
        for (std::size_t j = 0; j < corners.size(); ++j) block_of_corners[j] = slots.block_index(corners[j].block);
        pending.resize(slots.block_count());
        auto queue = [&](auto&& wanted) {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, corners.size(), 16), [&](const auto& r) {
                Slots::Accessor values(slots);
                for (std::size_t j = r.begin(); j != r.end(); ++j) {
                    std::vector<std::uint16_t>& list = pending[block_of_corners[j]];
                    for_each_bit(corners[j].mask, [&](int offset) {
                        if (wanted(values, Slots::key_at(corners[j].block, offset))) list.push_back(static_cast<std::uint16_t>(offset));
                    });
                }
            });
            for (std::uint32_t bi : block_of_corners)
                if (!pending[bi].empty()) pending_blocks.push_back(bi);
            evaluate_pending();
        };
        // Parity class of a vertex: bit a set when coordinate a is odd (0: all even, 7: all odd).
        auto parity = [](const VoxelKey& v) { return (v.x() & 1) | ((v.y() & 1) << 1) | ((v.z() & 1) << 2); };
        // Whether some cube c = v - n (n in {0,1}^3) around v has its all-even probe defined and,
        // when `both`, its all-odd one too. On an axis where v is even, c's even corner has v's
        // coordinate whatever n, and its odd corner v - 1 or v + 1 (n = 1 or 0); on an odd axis,
        // the other way round. So the even corner depends only on n's bits on v's odd axes, the
        // odd corner only on its bits on v's even axes, and the 8 cubes have a live one iff one
        // of the 2^(odd axes) even corners is defined and one of the 2^(even axes) odd corners is:
        // at most 6 distinct lookups instead of 16.
        auto any_defined = [&](Slots::Accessor& values, const VoxelKey& v, int axes) {
            // The vertices v + s, s_a in {-1, +1} on the axes in `axes`, 0 elsewhere.
            for (int m = 0; m < 8; ++m) {
                if (m & ~axes) continue;
                VoxelKey w = v;
                for (int a = 0; a < 3; ++a)
                    if (axes >> a & 1) w[a] += (m >> a & 1) ? 1 : -1;
                if (lookup_in(values, w)) return true;
            }
            return false;
        };
        auto near_live_cube = [&](Slots::Accessor& values, const VoxelKey& v, bool both) {
            const int odd = parity(v);
            return any_defined(values, v, odd) && (!both || any_defined(values, v, 7 & ~odd));
        };
        queue([&](Slots::Accessor&, const VoxelKey& v) { return parity(v) == 0; });
        queue([&](Slots::Accessor& values, const VoxelKey& v) { return parity(v) == 7 && near_live_cube(values, v, false); });
        queue([&](Slots::Accessor& values, const VoxelKey& v) {
            const int p = parity(v);
            return p != 0 && p != 7 && near_live_cube(values, v, true);
        });
    }
    {
        const std::vector<MaskedBlock> seeds = dilated_occupancy(grid, -d, d);
        std::vector<std::uint32_t> visited_block(seeds.size());
        for (std::size_t i = 0; i < seeds.size(); ++i) visited_block[i] = search.visited().block_index(seeds[i].block);
        // Per seed block, in parallel: mark its seeds visited (its own visited block) and classify
        // them; the cubes they lead to are then visited serially, in block order.
        std::vector<std::vector<VoxelKey>> active(seeds.size()), next(seeds.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size(), 8), [&](const auto& r) {
            Slots::Accessor values(slots);
            auto lookup = [&](const VoxelKey& v) { return lookup_in(values, v); };
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                BlockMap<std::uint8_t>::Block& seen = search.visited().block_at(visited_block[i]);
                for_each_bit(seeds[i].mask, [&](int offset) {
                    seen[static_cast<std::size_t>(offset)] = 1;
                    classify_cube(
                        Slots::key_at(seeds[i].block, offset), true, search.eps(), lookup,
                        [&](const VoxelKey& c) { active[i].push_back(c); }, [&](const VoxelKey& c) { next[i].push_back(c); });
                });
            }
        });
        for (std::size_t i = 0; i < seeds.size(); ++i) {
            search.active().insert(search.active().end(), active[i].begin(), active[i].end());
            for (const VoxelKey& c : next[i]) search.visit(c, search.wave());
        }
    }
    // The later waves (a quarter of the vertices): queue the cubes' unevaluated corners, then
    // evaluate them in parallel.
    Slots::WriteAccessor slot_of(slots);
    auto queue_vertex = [&](const VoxelKey& v) {
        std::int32_t& slot = slot_of[v];
        if (slot != kUnevaluated) return;
        slot = kQueued;
        const std::uint32_t bi = slot_of.block_index();
        if (bi >= pending.size()) pending.resize(slots.block_count());
        if (pending[bi].empty()) pending_blocks.push_back(bi);
        pending[bi].push_back(static_cast<std::uint16_t>(Slots::offset_of(v)));
    };
    // As in the seed wave: the all-even corners, the all-odd corners of the cubes whose all-even
    // one is defined, then the other corners of the cubes whose two probes are defined.
    auto prepare = [&](const std::vector<VoxelKey>& cubes) {
        for (const VoxelKey& cube : cubes) queue_vertex(even_corner(cube));
        evaluate_pending();
        for (const VoxelKey& cube : cubes)
            if (slot_of[even_corner(cube)] >= 0) queue_vertex(odd_corner(cube));
        evaluate_pending();
        for (const VoxelKey& cube : cubes) {
            if (slot_of[even_corner(cube)] < 0 || slot_of[odd_corner(cube)] < 0) continue;
            for (int c = 0; c < 8; ++c) queue_vertex(corner(cube, c));
        }
        evaluate_pending();
    };
    auto make_lookup = [&] { return [&, values = Slots::Accessor(slots)](const VoxelKey& v) mutable { return lookup_in(values, v); }; };
    SeededTsdf out;
    out.cubes = search.run(false, make_lookup, prepare);
    out.evaluated = samples.size();

    // The field: the defined evaluated vertices, in evaluation order (deterministic: the waves
    // and the grouping by block do not depend on the thread count).
    std::vector<std::int32_t> position(samples.size(), kUndefined);
    std::size_t defined = 0;
    for (std::size_t i = 0; i < samples.size(); ++i)
        if (samples[i].defined) position[i] = static_cast<std::int32_t>(defined++);
    std::vector<VoxelKey> field_keys(defined);
    std::vector<VertexSample> field_samples(defined);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots.block_count(), 16), [&](const auto& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b)
            for (std::int32_t& slot : slots.block_at(b))
                if (slot >= 0) {
                    const auto i = static_cast<std::size_t>(slot);
                    slot = position[i];
                    field_keys[static_cast<std::size_t>(slot)] = keys[i];
                    field_samples[static_cast<std::size_t>(slot)] = samples[i];
                }
    });
    out.field = TsdfField(std::move(slots), std::move(field_keys), std::move(field_samples), grid.voxel_size(), grid.origin());
    return out;
}

}  // namespace lidarsurf
