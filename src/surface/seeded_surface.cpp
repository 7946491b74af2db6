#include "lidarsurf/surface/seeded_surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include <tbb/parallel_for.h>

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
    std::unordered_set<VoxelKey, VoxelKeyHash> visited;
    for (const VoxelKey& k : grid.keys())
        for (int z = -dilation; z <= dilation; ++z)
            for (int y = -dilation; y <= dilation; ++y)
                for (int x = -dilation; x <= dilation; ++x) visited.insert(k + VoxelKey(x, y, z));
    std::vector<VoxelKey> wave(visited.begin(), visited.end()), next, active;
    std::sort(wave.begin(), wave.end(), zyx_less);
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
                    for (int n = 0; n < 8; ++n) {  // the 8 cubes around vertex v
                        const VoxelKey nb = v - VoxelKey(n & 1, (n >> 1) & 1, (n >> 2) & 1);
                        if (visited.insert(nb).second) next.push_back(nb);
                    }
                }
                continue;
            }
            active.push_back(cube);
            for (const Face& f : faces()) {
                int neg = 0;
                for (int c : f.corners) neg += s[c]->tsdf < 0;
                if (neg == 0 || neg == 4) continue;
                const VoxelKey nb = cube + f.step;
                if (visited.insert(nb).second) next.push_back(nb);
            }
        }
        std::swap(wave, next);
        std::sort(wave.begin(), wave.end(), zyx_less);
        seeding = false;
    }
    std::sort(active.begin(), active.end(), zyx_less);
    return active;
}

}  // namespace

std::vector<VoxelKey> seeded_cubes(const TsdfField& field, const VoxelGrid& grid, int dilation) {
    return search(grid, dilation, [&](const VoxelKey& v) { return field.find(v); }, [](const std::vector<VoxelKey>&) {});
}

SeededTsdf compute_seeded_tsdf(const VoxelGrid& grid, const ReconstructionConfig& config, const Eigen::Vector3d& sensor_world) {
    config.validate();
    const Eigen::Vector3d sensor_local = grid.to_local(sensor_world);
    const double truncation = config.truncation_distance();
    // Every evaluated vertex, defined or not (an undefined one is stored with defined = false).
    std::unordered_map<VoxelKey, VertexSample, VoxelKeyHash> cache;
    cache.reserve(grid.size() * 8);
    std::vector<VoxelKey> todo;
    std::vector<VertexSample> values;
    auto prepare = [&](const std::vector<VoxelKey>& cubes) {
        todo.clear();
        for (const VoxelKey& cube : cubes)
            for (int c = 0; c < 8; ++c) {
                const VoxelKey v = corner(cube, c);
                if (cache.try_emplace(v).second) todo.push_back(v);
            }
        values.resize(todo.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, todo.size(), 256), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                VertexSample s = evaluate_vertex(grid, todo[i], config, sensor_local);
                if (s.defined && !(std::fabs(s.tsdf) <= truncation)) s.defined = false;  // as assemble_field
                values[i] = s;
            }
        });
        for (std::size_t i = 0; i < todo.size(); ++i) cache[todo[i]] = values[i];
    };
    auto lookup = [&](const VoxelKey& v) -> const VertexSample* {
        auto it = cache.find(v);
        return it != cache.end() && it->second.defined ? &it->second : nullptr;
    };
    SeededTsdf out;
    out.cubes = search(grid, config.seed_dilation, lookup, prepare);
    out.evaluated = cache.size();
    out.field.voxel_size = grid.voxel_size();
    out.field.origin = grid.origin();
    // The field holds the corners of the active cubes, in cube order: deterministic.
    for (const VoxelKey& cube : out.cubes)
        for (int c = 0; c < 8; ++c) {
            const VoxelKey v = corner(cube, c);
            if (!out.field.find(v)) out.field.insert(v, cache.at(v));
        }
    return out;
}

}  // namespace lidarsurf
