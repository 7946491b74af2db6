#include "lidarsurf/surface/tsdf_field.hpp"

#include <algorithm>
#include <bitset>
#include <cmath>

#include <tbb/parallel_for.h>

namespace lidarsurf {

void TsdfField::insert(const VoxelKey& v, const VertexSample& s) {
    std::int32_t& slot = index_[v];
    if (slot < 0) {
        slot = static_cast<std::int32_t>(samples_.size());
        keys_.push_back(v);
        samples_.push_back(s);
    } else {
        samples_[static_cast<std::size_t>(slot)] = s;
    }
}

std::vector<VoxelKey> candidate_vertices(const VoxelGrid& grid, int level) {
    // Voxel i lies in H^L(v) iff v - L <= i <= v + L - 1, i.e. v in [i - L + 1, i + L]^3.
    constexpr int B = 8;
    using Bits = std::bitset<B * B * B>;
    std::unordered_map<VoxelKey, Bits, VoxelKeyHash> marks;
    for (const VoxelKey& i : grid.keys()) {
        const VoxelKey lo = i.array() - (level - 1), hi = i.array() + level;
        for (int z = lo.z(); z <= hi.z(); ++z)
            for (int y = lo.y(); y <= hi.y(); ++y) {
                Bits* bits = nullptr;
                int current_bx = 0;
                for (int x = lo.x(); x <= hi.x(); ++x) {
                    const int bx = x >> 3;
                    if (!bits || bx != current_bx) {
                        bits = &marks[VoxelKey(bx, y >> 3, z >> 3)];
                        current_bx = bx;
                    }
                    bits->set(static_cast<std::size_t>((x & 7) | ((y & 7) << 3) | ((z & 7) << 6)));
                }
            }
    }
    std::vector<VoxelKey> out;
    for (const auto& [block, bits] : marks)
        for (int idx = 0; idx < B * B * B; ++idx)
            if (bits.test(static_cast<std::size_t>(idx)))
                out.emplace_back(block.x() * B + (idx & 7), block.y() * B + ((idx >> 3) & 7), block.z() * B + (idx >> 6));
    sort_zyx(out);
    return out;
}

TsdfField compute_tsdf(const VoxelGrid& grid, const SurfaceConfig& config, const Eigen::Vector3d& sensor_world,
                       TsdfStats* stats) {
    config.validate();
    const std::vector<VoxelKey> candidates = candidate_vertices(grid, config.max_level());
    std::vector<VertexSample> samples(candidates.size());
    const Eigen::Vector3d sensor_local = grid.to_local(sensor_world);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 256), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            samples[i] = evaluate_vertex(grid, candidates[i], config, sensor_local);
    });
    // Truncation: a vertex farther than the truncation distance from its plane cannot be a corner
    // of a cube the surface crosses; it stays undefined so no cube is meshed from it.
    return assemble_field(grid, candidates, samples, truncation_of(config, grid), stats);
}

TsdfField assemble_field(const VoxelGrid& grid, const std::vector<VoxelKey>& candidates,
                         const std::vector<VertexSample>& samples, const Truncation& truncation, TsdfStats* stats) {
    TsdfField field;
    field.voxel_size = grid.voxel_size();
    field.origin = grid.origin();
    std::size_t defined = 0;
    for (std::size_t i = 0; i < candidates.size(); ++i)
        if (truncation.keeps(samples[i])) {
            field.insert(candidates[i], samples[i]);
            ++defined;
        }
    if (stats) *stats = {candidates.size(), defined};
    return field;
}

}  // namespace lidarsurf
