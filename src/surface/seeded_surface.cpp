#include "lidarsurf/surface/seeded_surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/parallel_for.h>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"

namespace lidarsurf {

namespace {

VoxelKey corner(const VoxelKey& base, int c) { return base + VoxelKey(c & 1, (c >> 1) & 1, (c >> 2) & 1); }

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

// The search over cubes, independent of how vertex values are obtained. `lookup(v)` returns the
// sample of a vertex (nullptr if undefined); `prepare(cubes)` is called before a wave of cubes
// is examined, so that a lazy implementation can evaluate their corners first.
template <typename Lookup, typename Prepare>
std::vector<VoxelKey> search(const VoxelGrid& grid, int dilation, Lookup&& lookup, Prepare&& prepare) {
    BlockMap<std::uint8_t> visited(0);
    visited.reserve_blocks(grid.index().block_count() * 2);
    BlockMap<std::uint8_t>::WriteAccessor seen_of(visited);
    std::vector<VoxelKey> wave, next, active;
    auto visit = [&](const VoxelKey& cube, std::vector<VoxelKey>& out) {
        std::uint8_t& seen = seen_of[cube];
        if (!seen) {
            seen = 1;
            out.push_back(cube);
        }
    };
    for (const VoxelKey& k : grid.keys())
        for (int z = -dilation; z <= dilation; ++z)
            for (int y = -dilation; y <= dilation; ++y)
                for (int x = -dilation; x <= dilation; ++x) visit(k + VoxelKey(x, y, z), wave);
    // A surface through a seed's corner (|value| <= eps, e.g. data lying on a lattice plane) may
    // cross only the neighbouring cubes (zero counts as positive): they become seeds too.
    const double eps = 1e-6 * grid.voxel_size();
    bool seeding = true;
    while (!wave.empty()) {
        prepare(wave);
        next.clear();
        for (const VoxelKey& cube : wave) {
            std::array<const VertexSample*, 8> s{};
            bool all = true;
            int negatives = 0;
            for (int c = 0; c < 8 && all; ++c) {
                s[c] = lookup(corner(cube, c));
                all = s[c] != nullptr;
                if (all) negatives += s[c]->tsdf < 0;
            }
            if (!all) continue;
            if (negatives == 0 || negatives == 8) {
                if (!seeding) continue;
                for (int c = 0; c < 8; ++c) {
                    if (!(std::fabs(s[c]->tsdf) <= eps)) continue;
                    const VoxelKey v = corner(cube, c);
                    for (int n = 0; n < 8; ++n) visit(v - VoxelKey(n & 1, (n >> 1) & 1, (n >> 2) & 1), next);  // the 8 cubes around v
                }
                continue;
            }
            active.push_back(cube);
            for (const Face& f : faces()) {
                int neg = 0;
                for (int c : f.corners) neg += s[c]->tsdf < 0;
                if (neg == 0 || neg == 4) continue;
                visit(cube + f.step, next);
            }
        }
        std::swap(wave, next);
        seeding = false;
    }
    // Which cubes are reached does not depend on the order of the waves; the sort makes the
    // output (and so the mesh's vertex and triangle order) deterministic.
    std::sort(active.begin(), active.end(), zyx_less);
    return active;
}

}  // namespace

std::vector<VoxelKey> seeded_cubes(const TsdfField& field, const VoxelGrid& grid, int dilation) {
    TsdfField::Accessor values(field);
    return search(grid, dilation, [&](const VoxelKey& v) { return values.find(v); }, [](const std::vector<VoxelKey>&) {});
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
    Slots::WriteAccessor slot_of(slots);
    auto prepare = [&](const std::vector<VoxelKey>& cubes) {
        for (const VoxelKey& cube : cubes)
            for (int c = 0; c < 8; ++c) {
                const VoxelKey v = corner(cube, c);
                std::int32_t& slot = slot_of[v];
                if (slot != kUnevaluated) continue;
                slot = kQueued;
                const std::uint32_t bi = slot_of.block_index();
                if (bi >= pending.size()) pending.resize(slots.block_count());
                if (pending[bi].empty()) pending_blocks.push_back(bi);
                pending[bi].push_back(static_cast<std::uint16_t>(Slots::offset_of(v)));
            }
        pending_base.resize(pending_blocks.size());
        std::size_t total = samples.size();
        for (std::size_t i = 0; i < pending_blocks.size(); ++i) {
            pending_base[i] = total;
            total += pending[pending_blocks[i]].size();
        }
        keys.resize(total);
        samples.resize(total);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pending_blocks.size(), 1), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const std::uint32_t bi = pending_blocks[i];
                const VoxelKey block_key = slots.block_keys()[bi];
                const NeighbourhoodWindow window(grid, block_key, config.max_level());
                Slots::Block& block = slots.block_at(bi);
                std::size_t at = pending_base[i];
                for (std::uint16_t offset : pending[bi]) {
                    const VoxelKey v = Slots::key_at(block_key, offset);
                    VertexSample s = evaluate_vertex(window, v, config, sensor_local, solver);
                    if (s.defined && !(std::fabs(s.tsdf) <= truncation)) s.defined = false;  // as assemble_field
                    keys[at] = v;
                    samples[at] = s;
                    block[offset] = s.defined ? static_cast<std::int32_t>(at) : kUndefined;
                    ++at;
                }
            }
        });
        for (std::uint32_t bi : pending_blocks) pending[bi].clear();
        pending_blocks.clear();
    };
    Slots::Accessor values(slots);
    auto lookup = [&](const VoxelKey& v) -> const VertexSample* {
        const std::int32_t* slot = values.find(v);
        return slot && *slot >= 0 ? &samples[static_cast<std::size_t>(*slot)] : nullptr;
    };
    SeededTsdf out;
    out.cubes = search(grid, config.seed_dilation, lookup, prepare);
    out.evaluated = samples.size();
    // The field: the defined evaluated vertices, in evaluation order (deterministic: the waves
    // and the grouping by block do not depend on the thread count).
    std::size_t defined = 0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
        if (!samples[i].defined) continue;
        slot_of[keys[i]] = static_cast<std::int32_t>(defined);
        keys[defined] = keys[i];
        samples[defined] = samples[i];
        ++defined;
    }
    keys.resize(defined);
    samples.resize(defined);
    out.field = TsdfField(std::move(slots), std::move(keys), std::move(samples), grid.voxel_size(), grid.origin());
    return out;
}

}  // namespace lidarsurf
