#include "lidarsurf/map/carved_clusters.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

CarvedClusters::CarvedClusters(double share, double voxel_size)
    : share_(share),
      alpha_(voxel_size),
      cell_voxels_(std::max(1, static_cast<int>(std::lround(kGroundCell / voxel_size)))),
      max_live_(static_cast<std::size_t>(kMaxArea / (voxel_size * voxel_size))) {
    if (!(share > 0 && share <= 1)) throw InvalidArgument("carving: the cluster share must be in (0, 1]");
}

std::uint64_t CarvedClusters::cell_of(const VoxelKey& key) const {
    const VoxelKey c(floor_div(key.x(), cell_voxels_), floor_div(key.y(), cell_voxels_), 0);
    return pack_key(c);
}

void CarvedClusters::add_ground(const VoxelGrid& grid, std::size_t from, const std::function<float(std::size_t)>& mean_z) {
    if (!enabled()) return;
    // floor_ holds, per cell, the lowest over the 3 x 3 cells around it: a new voxel lowers the
    // nine cells whose neighbourhood holds its own.
    for (std::size_t v = from; v < grid.size(); ++v) {
        const VoxelKey& key = grid.keys()[v];
        const std::int32_t cx = floor_div(key.x(), cell_voxels_), cy = floor_div(key.y(), cell_voxels_);
        const float z = mean_z(v);
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const auto [it, added] = floor_.try_emplace(pack_key(VoxelKey(cx + dx, cy + dy, 0)), z);
                if (!added) it->second = std::min(it->second, z);
            }
    }
}

bool CarvedClusters::above_ground(const VoxelKey& key, float z) const {
    const auto it = floor_.find(cell_of(key));
    return it == floor_.end() || z > it->second + static_cast<float>(kGroundBand);
}

bool CarvedClusters::bury(const VoxelKey& key, float z, std::uint32_t last_hit, std::uint32_t stamp) {
    if (!enabled()) return false;
    const bool above = above_ground(key, z);
    tombs_[key] = Tomb{stamp, last_hit, above};
    return above;
}

std::vector<std::uint32_t> CarvedClusters::follow(const VoxelGrid& grid, std::span<const VoxelKey> seeds, std::uint32_t stamp,
                                                  const std::function<std::uint32_t(std::size_t)>& last_hit,
                                                  const std::function<float(std::size_t)>& mean_z) {
    std::vector<std::uint32_t> out;
    if (!enabled()) return out;
    if (stamp - pruned_ >= 8) {  // forget the tombstones older than the memory
        pruned_ = stamp;
        std::erase_if(tombs_, [&](const auto& kv) { return stamp - kv.second.removed > static_cast<std::uint32_t>(kMemoryScans); });
    }
    const auto reach = static_cast<std::int32_t>(std::ceil(kReach / alpha_));
    // Visited: a live voxel's mark in live_mark_ (by index), a tombstone's in its own; this
    // call's mark is new.
    ++mark_;
    live_mark_.resize(grid.size(), 0);
    std::vector<VoxelKey> queue;
    std::vector<std::uint32_t> live, tomb_hits;
    for (const VoxelKey& seed : seeds) {
        Tomb& first = tombs_.at(seed);
        if (first.mark == mark_) continue;
        first.mark = mark_;
        queue.assign(1, seed);
        live.clear();
        tomb_hits.assign(1, first.last_hit);
        bool object = true;
        for (std::size_t head = 0; head < queue.size() && object; ++head) {
            const VoxelKey k = queue[head];
            for (int face = 0; face < 6; ++face) {
                VoxelKey nk = k;
                nk[face / 2] += face % 2 ? 1 : -1;
                if (const std::int32_t v = grid.voxel_at(nk); v >= 0) {
                    std::uint32_t& m = live_mark_[static_cast<std::size_t>(v)];
                    if (m == mark_ || !above_ground(nk, mean_z(static_cast<std::size_t>(v)))) continue;
                    m = mark_;
                    live.push_back(static_cast<std::uint32_t>(v));
                } else if (const auto t = tombs_.find(nk); t != tombs_.end() && t->second.mark != mark_ && t->second.above &&
                                                           stamp - t->second.removed <= static_cast<std::uint32_t>(kMemoryScans)) {
                    t->second.mark = mark_;
                    tomb_hits.push_back(t->second.last_hit);
                } else {
                    continue;
                }
                queue.push_back(nk);
                if (live.size() > max_live_ || (nk - seed).cwiseAbs().maxCoeff() > reach) {
                    object = false;  // a wall, a row of trees: not an object that left
                    break;
                }
            }
        }
        if (!object) continue;
        // The quiet voxels (not seen for kQuietScans scans) and the latest of their hits.
        std::uint32_t latest = 0;
        std::size_t quiet = 0;
        for (const std::uint32_t v : live)
            if (const std::uint32_t h = last_hit(v); stamp - h >= static_cast<std::uint32_t>(kQuietScans)) ++quiet, latest = std::max(latest, h);
        if (quiet == 0) continue;
        const auto carved = static_cast<std::size_t>(
            std::count_if(tomb_hits.begin(), tomb_hits.end(), [&](std::uint32_t h) { return h + static_cast<std::uint32_t>(kSlackScans) >= latest; }));
        if (static_cast<double>(carved) < share_ * static_cast<double>(carved + live.size())) continue;
        for (const std::uint32_t v : live)
            if (stamp - last_hit(v) >= static_cast<std::uint32_t>(kQuietScans)) out.push_back(v);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
}

}  // namespace lidarsurf
