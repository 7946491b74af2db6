#include "lidarsurf/core/voxel_grid.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <unordered_set>

#include <tbb/parallel_for.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/radix_sort.hpp"
#include "lidarsurf/core/simd.hpp"

namespace lidarsurf {

namespace {
// The lattice point nearest to `world`: the grid's local origin, so that the world lattice is kept.
Eigen::Vector3d lattice_point_near(const Eigen::Vector3d& world, double alpha) { return (world / alpha).array().round().matrix() * alpha; }
}  // namespace

VoxelGrid::VoxelGrid(double alpha, const std::optional<Eigen::Vector3d>& origin) : alpha_(alpha) {
    if (!std::isfinite(alpha) || alpha <= 0) throw InvalidArgument("voxel size must be finite and > 0");
    if (origin) {
        if (!origin->allFinite()) throw InvalidArgument("grid origin must be finite");
        origin_ = lattice_point_near(*origin, alpha_);
        origin_set_ = true;
    }
}

std::string VoxelGrid::out_of_range_message(const Eigen::Vector3d& world, std::optional<std::size_t> index) const {
    return out_of_range_message(world, index, origin_);
}

std::string VoxelGrid::out_of_range_message(const Eigen::Vector3d& world, std::optional<std::size_t> index, const Eigen::Vector3d& origin) const {
    char which[32] = "";
    if (index) std::snprintf(which, sizeof which, "#%zu ", *index);
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "point %s(%.10g, %.10g, %.10g) is more than %d voxels (%.6g m) from the first point (%.10g, %.10g, %.10g); "
                  "split the cloud, drop the outlier, or use a larger voxel size",
                  which, world.x(), world.y(), world.z(), kMaxLatticeIndex, kMaxLatticeIndex * alpha_, origin.x(), origin.y(), origin.z());
    return buf;
}

VoxelKey VoxelGrid::key_of_local(const Eigen::Vector3d& local) const {
    VoxelKey key;
    for (int i = 0; i < 3; ++i) {
        const double f = std::floor(local[i] / alpha_);
        if (!(std::fabs(f) <= kMaxLatticeIndex)) throw InvalidInput(out_of_range_message(to_world(local), std::nullopt));
        key[i] = static_cast<std::int32_t>(f);
    }
    return key;
}

void VoxelGrid::set_origin_from(const Eigen::Vector3d& world) {
    if (origin_set_) return;
    origin_ = lattice_point_near(world, alpha_);  // the first point's
    origin_set_ = true;
}

void VoxelGrid::Slots::insert(int layer, std::uint64_t word, int bit, std::int32_t voxel) {
    voxels.insert(voxels.begin() + static_cast<std::ptrdiff_t>(rank(layer, word, bit)), voxel);
    for (std::size_t l = static_cast<std::size_t>(layer) + 1; l < before.size(); ++l) ++before[l];
}

void VoxelGrid::Slots::erase(int layer, std::uint64_t word, int bit) {
    voxels.erase(voxels.begin() + static_cast<std::ptrdiff_t>(rank(layer, word, bit)));
    for (std::size_t l = static_cast<std::size_t>(layer) + 1; l < before.size(); ++l) --before[l];
}

void VoxelGrid::cache_block(const VoxelKey& block_key) {
    const std::uint32_t b = index_.add(block_key).first;
    if (b >= occupancy_.size()) {
        occupancy_.resize(b + 1, Occupancy{});
        slots_.resize(b + 1);
        touched_flag_.resize(b + 1, 0);
    }
    // Every point goes through here or through the cached block, which was marked when it was
    // cached (clear_touched() drops the cache).
    touch(b);
    last_block_ = &slots_[b];
    last_occupancy_ = &occupancy_[b];
    last_block_key_ = block_key;
}

namespace {
constexpr std::uint32_t kNoChange = 0xffffffffu;
}

void VoxelGrid::track_changes() {
    if (tracking_) return;
    tracking_ = true;
    change_slot_.assign(occupancy_.size(), kNoChange);
}

VoxelGrid::BlockChange& VoxelGrid::change_of(std::uint32_t b) {
    if (b >= change_slot_.size()) change_slot_.resize(std::max<std::size_t>(b + 1, occupancy_.size()), kNoChange);
    std::uint32_t& slot = change_slot_[b];
    if (slot == kNoChange) {
        slot = static_cast<std::uint32_t>(changes_.size());
        changes_.push_back({b, 0, 0, 0, 0});
    }
    return changes_[slot];
}

std::vector<VoxelGrid::BlockChange> VoxelGrid::take_changes() {
    for (const BlockChange& c : changes_) change_slot_[c.block] = kNoChange;
    return std::exchange(changes_, {});
}

void VoxelGrid::touch(std::uint32_t b) {
    if (!touched_flag_[b]) {
        touched_flag_[b] = 1;
        touched_.push_back(b);
    }
}

std::int32_t& VoxelGrid::slot_of(const VoxelKey& key) {
    using Map = BlockMap<std::int32_t>;
    const auto b = static_cast<std::size_t>(index_.index_of(Map::block_of(key)));
    const int offset = Map::offset_of(key);
    return slots_[b].at(offset >> 6, occupancy_[b][static_cast<std::size_t>(offset >> 6)], offset & 63);
}

std::size_t VoxelGrid::remove(std::size_t voxel) {
    using Map = BlockMap<std::int32_t>;
    const VoxelKey key = keys_.at(voxel);
    const auto block = static_cast<std::uint32_t>(index_.index_of(Map::block_of(key)));
    const int offset = Map::offset_of(key);
    std::uint64_t& word = occupancy_[block][static_cast<std::size_t>(offset >> 6)];
    slots_[block].erase(offset >> 6, word, offset & 63);
    word &= ~(std::uint64_t{1} << (offset & 63));
    touch(block);
    if (tracking_) {
        BlockChange& c = change_of(block);
        ++c.removed_voxels;
        c.removed_points += stats_[voxel].count;
    }
    const std::size_t last = keys_.size() - 1;
    if (voxel != last) {
        slot_of(keys_[last]) = static_cast<std::int32_t>(voxel);
        keys_[voxel] = keys_[last];
        stats_[voxel] = stats_[last];
        if (viewpoints_enabled_) viewpoint_means_[voxel] = viewpoint_means_[last];
        if (intensity_enabled_) {
            intensity_[voxel] = intensity_[last];
        }
    }
    keys_.pop_back();
    stats_.pop_back();
    if (viewpoints_enabled_) viewpoint_means_.pop_back();
    if (intensity_enabled_) {
        intensity_.pop_back();
    }
    return last;
}

std::int32_t VoxelGrid::voxel_index_slow(const VoxelKey& key) {
    const VoxelKey block_key = BlockMap<std::int32_t>::block_of(key);
    if (!last_block_ || !same_key(block_key, last_block_key_)) cache_block(block_key);
    const int offset = BlockMap<std::int32_t>::offset_of(key);
    std::uint64_t& word = (*last_occupancy_)[static_cast<std::size_t>(offset >> 6)];
    const std::uint64_t flag = std::uint64_t{1} << (offset & 63);
    if (word & flag) return last_block_->at(offset >> 6, word, offset & 63);
    const auto voxel = static_cast<std::int32_t>(keys_.size());
    last_block_->insert(offset >> 6, word, offset & 63, voxel);
    word |= flag;
    keys_.push_back(key);
    return voxel;
}

void VoxelGrid::insert(const Eigen::Vector3d& world) {
    if (!world.allFinite()) throw InvalidInput("point coordinates must be finite");
    if (viewpoints_enabled_) throw InvalidArgument("this grid has viewpoints: insert points with the position they were seen from");
    set_origin_from(world);  // a first point is never out of range: it sets the origin only when taken
    const Eigen::Vector3d local = world - origin_;
    const VoxelKey key = key_of_local(local);
    const std::size_t before = keys_.size();
    const auto v = static_cast<std::size_t>(voxel_index(key));
    if (v >= stats_.size()) stats_.resize(v + 1);
    if (intensity_enabled_) intensity_.resize(stats_.size());
    stats_[v].add(local);
    ++points_;
    if (tracking_) {
        BlockChange& c = change_of(static_cast<std::uint32_t>(index_.index_of(BlockMap<std::int32_t>::block_of(key))));
        ++c.points;
        c.new_voxels += keys_.size() > before;
    }
}

std::size_t VoxelGrid::insert(std::span<const Eigen::Vector3d> points, const std::optional<Eigen::Vector3d>& viewpoint,
                              std::vector<Hit>* hits, std::span<const float> intensity) {
    if (viewpoints_enabled_ && !viewpoint) throw InvalidArgument("this grid has viewpoints: insert points with the position they were seen from");
    if (viewpoint && !viewpoint->allFinite()) throw InvalidArgument("viewpoint must be finite");
    const std::size_t n = points.size();
    if (!intensity.empty() && intensity.size() != n)
        throw InvalidArgument("intensity: " + std::to_string(intensity.size()) + " values for " + std::to_string(n) + " points");
    std::size_t first = 0;
    while (first < n && !points[first].allFinite()) ++first;
    if (first == n) {
        if (hits) hits->clear();
        return n;
    }
    // 1. The voxel key of every point, in parallel; a point out of range throws before any change
    //    (the lattice origin a first batch would set included: a refused batch leaves no trace).
    const Eigen::Vector3d origin = origin_set_ ? origin_ : lattice_point_near(points[first], alpha_);
    constexpr std::uint32_t kSkip = 0xffffffffu;
    std::vector<VoxelKey> keys(n);
    std::vector<std::uint8_t> finite(n);
    std::atomic<std::size_t> first_out_of_range{n};  // the message names the first such point, whatever the threads' order
    auto key_range = [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i != end; ++i) {
            finite[i] = points[i].allFinite();
            if (!finite[i]) continue;
            try {
                keys[i] = key_of_local(points[i] - origin);
            } catch (const InvalidInput&) {
                std::size_t seen = first_out_of_range.load();
                while (i < seen && !first_out_of_range.compare_exchange_weak(seen, i)) {
                }
                return;
            }
        }
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                      [&](const auto& r) { call_at_simd_level(key_range, r.begin(), r.end()); });
    if (const std::size_t bad = first_out_of_range.load(); bad < n) throw InvalidInput(out_of_range_message(points[bad], bad, origin));
    origin_ = origin;
    origin_set_ = true;
    const std::size_t voxels_before = keys_.size();
    // 2. The voxel of every point, in point order: new voxels are numbered as one-by-one
    //    insertion numbers them (this is the only serial pass: one block lookup per block change).
    std::vector<std::uint32_t> voxel(n, kSkip);
    std::size_t dropped = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!finite[i]) [[unlikely]] {
            ++dropped;
            continue;
        }
        voxel[i] = static_cast<std::uint32_t>(voxel_index(keys[i]));
    }
    stats_.resize(keys_.size());  // the new voxels, empty
    // 3. The points of each voxel, in point order, then Welford's update per voxel in parallel:
    //    each voxel sees its points in the order one-by-one insertion gives it, so the statistics
    //    are identical to the last bit. The grouping is a counting sort over the range of voxel
    //    numbers this batch touches when that range is small (a frame into a new grid), else a
    //    stable radix sort of the point indices (11-bit digits), so that a batch's cost does not
    //    grow with the voxels of earlier batches (a sequence fused frame by frame).
    const std::size_t m = n - dropped;
    std::uint32_t lo = kSkip, hi = 0;
    for (std::uint32_t v : voxel)
        if (v != kSkip) lo = std::min(lo, v), hi = std::max(hi, v);
    std::vector<std::uint32_t> order(m);  // point indices, grouped by voxel
    std::vector<std::size_t> runs;        // run r (one voxel's points) is order[runs[r], runs[r + 1])
    if (m > 0 && hi - lo < 4 * m) {
        std::vector<std::uint32_t> start(hi - lo + 2, 0);
        for (std::uint32_t v : voxel)
            if (v != kSkip) ++start[v - lo + 1];
        runs.reserve(hi - lo + 2);
        for (std::size_t v = 0; v + 1 < start.size(); ++v) {
            if (start[v + 1] > 0) runs.push_back(start[v]);
            start[v + 1] += start[v];
        }
        for (std::size_t i = 0; i < n; ++i)
            if (voxel[i] != kSkip) order[start[voxel[i] - lo]++] = static_cast<std::uint32_t>(i);
    } else if (m > 0) {
        std::size_t at = 0;
        for (std::size_t i = 0; i < n; ++i)
            if (voxel[i] != kSkip) order[at++] = static_cast<std::uint32_t>(i);
        std::vector<std::uint32_t> scratch;
        radix_sort(order, scratch, static_cast<int>(std::bit_width(hi)), [&](std::uint32_t i) { return voxel[i]; });
        for (std::size_t j = 0; j < m; ++j)
            if (j == 0 || voxel[order[j]] != voxel[order[j - 1]]) runs.push_back(j);
    }
    runs.push_back(m);
    auto add_runs = [&](std::size_t from, std::size_t to) {
        for (std::size_t run = from; run != to; ++run) {
            VoxelStats& stats = stats_[voxel[order[runs[run]]]];
            for (std::size_t j = runs[run]; j < runs[run + 1]; ++j) stats.add(points[order[j]] - origin_);
        }
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runs.size() - 1, 512),
                      [&](const auto& r) { call_at_simd_level(add_runs, r.begin(), r.end()); });
    if (viewpoints_enabled_) {
        viewpoint_means_.resize(stats_.size(), Eigen::Vector3f::Zero());
        const Eigen::Vector3d local = *viewpoint - origin_;
        for (std::size_t run = 0; run + 1 < runs.size(); ++run) {
            // The running mean over the voxel's points, the batch's k points at `local` last.
            const std::uint32_t v = voxel[order[runs[run]]];
            const double k = static_cast<double>(runs[run + 1] - runs[run]);
            const Eigen::Vector3d mean = viewpoint_means_[v].cast<double>();
            viewpoint_means_[v] = (mean + (local - mean) * (k / static_cast<double>(stats_[v].count))).cast<float>();
        }
    }
    if (!intensity.empty() && !intensity_enabled_) {
        intensity_enabled_ = true;  // the voxels before hold no point with an intensity
        intensity_.assign(stats_.size(), IntensityMean{});
    }
    if (intensity_enabled_) {
        intensity_.resize(stats_.size());
        if (!intensity.empty()) add_intensity(intensity, voxel, order, runs);
    }
    if (hits) {
        hits->clear();
        hits->reserve(runs.size() - 1);
        for (std::size_t run = 0; run + 1 < runs.size(); ++run)
            hits->push_back({voxel[order[runs[run]]], order[runs[run]]});
    }
    if (tracking_) {
        // Runs come by voxel number: new voxels in first-point order, so mostly block after block.
        std::int64_t block = -1;
        VoxelKey block_key = VoxelKey::Zero();
        for (std::size_t run = 0; run + 1 < runs.size(); ++run) {
            const std::uint32_t v = voxel[order[runs[run]]];
            const VoxelKey key = BlockMap<std::int32_t>::block_of(keys_[v]);
            if (block < 0 || !same_key(key, block_key)) block = index_.index_of(block_key = key);
            BlockChange& c = change_of(static_cast<std::uint32_t>(block));
            c.points += static_cast<std::uint32_t>(runs[run + 1] - runs[run]);
            c.new_voxels += v >= voxels_before;
        }
    }
    points_ += n - dropped;
    return dropped;
}

void VoxelGrid::enable_viewpoints(const Eigen::Vector3d& earlier) {
    if (!earlier.allFinite()) throw InvalidArgument("viewpoint must be finite");
    if (viewpoints_enabled_) return;
    viewpoints_enabled_ = true;
    viewpoint_means_.assign(stats_.size(), (earlier - origin_).cast<float>());
}

std::optional<Eigen::Vector3d> VoxelGrid::mean_viewpoint(const VoxelKey& lo, const VoxelKey& hi) const {
    if (!viewpoints_enabled_) throw InvalidArgument("mean_viewpoint: the grid has no viewpoints");
    double count = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for_each_index_in_box(lo, hi, [&](const VoxelKey&, std::size_t v) {
        count += static_cast<double>(stats_[v].count);
        sum += static_cast<double>(stats_[v].count) * viewpoint_means_[v].cast<double>();
    });
    if (count <= 0) return std::nullopt;
    return sum / count;
}

void VoxelGrid::add_intensity(std::span<const float> intensity, std::span<const std::uint32_t> voxel, std::span<const std::uint32_t> order,
                              std::span<const std::size_t> runs) {
    // Per voxel (disjoint, so in parallel): the running mean over its finite values, point by
    // point in point order, so that a voxel's mean does not depend on how its points were
    // batched (a tile's voxels equal the whole map's to the last bit).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runs.size() - 1, 512), [&](const auto& r) {
        for (std::size_t run = r.begin(); run != r.end(); ++run) {
            const std::uint32_t v = voxel[order[runs[run]]];
            float mean = intensity_[v].mean;
            std::uint32_t count = intensity_[v].count;
            for (std::size_t j = runs[run]; j < runs[run + 1]; ++j) {
                const float value = intensity[order[j]];
                if (!std::isfinite(value)) continue;
                ++count;
                mean = static_cast<float>(mean + (static_cast<double>(value) - mean) / count);
            }
            intensity_[v] = {mean, count};
        }
    });
}

std::optional<double> VoxelGrid::mean_intensity(const VoxelKey& lo, const VoxelKey& hi) const {
    if (!intensity_enabled_) return std::nullopt;
    double count = 0, sum = 0;
    for_each_index_in_box(lo, hi, [&](const VoxelKey&, std::size_t v) {
        const IntensityMean& m = intensity_[v];
        count += m.count;
        sum += static_cast<double>(m.count) * m.mean;
    });
    if (count <= 0) return std::nullopt;
    return sum / count;
}

void VoxelGrid::clear_touched() {
    for (std::uint32_t b : touched_) touched_flag_[b] = 0;
    touched_.clear();
    last_block_ = nullptr;  // so that the next point in the cached block marks it again
}

std::size_t VoxelGrid::slot_bytes() const {
    std::size_t bytes = 0;
    for (const Slots& b : slots_) bytes += b.voxels.capacity() * sizeof(std::int32_t);
    return bytes;
}

std::size_t VoxelGrid::memory_bytes() const {
    return index_.memory_bytes() + slots_.capacity() * sizeof(Slots) + slot_bytes() + occupancy_.capacity() * sizeof(Occupancy) + stats_.capacity() * sizeof(VoxelStats) +
           keys_.capacity() * sizeof(VoxelKey) + touched_flag_.capacity() + touched_.capacity() * sizeof(std::uint32_t) +
           viewpoint_means_.capacity() * sizeof(Eigen::Vector3f) + intensity_.capacity() * sizeof(IntensityMean);
}

std::pair<std::size_t, std::size_t> VoxelGrid::count_new(std::span<const Eigen::Vector3d> points) const {
    std::unordered_set<std::uint64_t> voxels, blocks;
    std::optional<Eigen::Vector3d> base;  // the grid's origin, or the one the insert would set
    if (origin_set_) base = origin_;
    for (const Eigen::Vector3d& p : points) {
        if (!p.allFinite()) continue;
        if (!base) base = lattice_point_near(p, alpha_);
        VoxelKey key;
        try {
            key = key_of_local(p - *base);
        } catch (const InvalidInput&) {
            return {0, 0};  // the insert refuses the batch before any change
        }
        if (find(key)) continue;
        const auto pack = [](const VoxelKey& k) {
            return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.x()) & 0x1fffff) << 42) |
                   (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.y()) & 0x1fffff) << 21) |
                   (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.z()) & 0x1fffff));
        };
        voxels.insert(pack(key));
        const VoxelKey block = BlockMap<std::int32_t>::block_of(key);
        if (index_.index_of(block) < 0) blocks.insert(pack(block));
    }
    return {voxels.size(), blocks.size()};
}

std::size_t VoxelGrid::memory_bytes_after(std::size_t new_voxels, std::size_t new_blocks, std::size_t batch) const {
    // Each array grows to at most twice its capacity or to what it must hold, whichever is more
    // (std::vector's growth); the block index by the blocks' pages and its hash, likewise.
    const auto grown = [](std::size_t capacity, std::size_t needed) { return needed <= capacity ? capacity : std::max(2 * capacity, needed); };
    const std::size_t voxels = keys_.size() + new_voxels, blocks = occupancy_.size() + new_blocks;
    std::size_t bytes = grown(keys_.capacity(), voxels) * sizeof(VoxelKey);
    bytes += grown(stats_.capacity(), voxels) * sizeof(VoxelStats);
    if (viewpoints_enabled_) bytes += grown(viewpoint_means_.capacity(), voxels) * sizeof(Eigen::Vector3f);
    if (intensity_enabled_) bytes += grown(intensity_.capacity(), voxels) * sizeof(IntensityMean);
    bytes += grown(occupancy_.capacity(), blocks) * sizeof(Occupancy) + grown(touched_flag_.capacity(), blocks) +
             grown(touched_.capacity(), blocks) * sizeof(std::uint32_t);
    // The blocks' voxel lists grow by doubling: up to twice the new voxels' indices.
    bytes += grown(slots_.capacity(), blocks) * sizeof(Slots) + slot_bytes() + 2 * new_voxels * sizeof(std::int32_t);
    bytes += 2 * index_.memory_bytes() + new_blocks * 64;
    // The insert's scratch per point: its key, finiteness, voxel, place in the grouping and run.
    bytes += batch * (sizeof(VoxelKey) + 1 + 2 * sizeof(std::uint32_t) + sizeof(std::size_t));
    return bytes;
}

std::int32_t VoxelGrid::voxel_at(const VoxelKey& key) const {
    using Map = BlockMap<std::int32_t>;
    const std::int64_t b = index_.index_of(Map::block_of(key));
    if (b < 0) return -1;
    const int offset = Map::offset_of(key);
    const std::uint64_t word = occupancy_[static_cast<std::size_t>(b)][static_cast<std::size_t>(offset >> 6)];
    return (word >> (offset & 63)) & 1u ? slots_[static_cast<std::size_t>(b)].at(offset >> 6, word, offset & 63) : -1;
}

const VoxelStats* VoxelGrid::find(const VoxelKey& key) const {
    const std::int32_t v = voxel_at(key);
    return v >= 0 ? &stats_[static_cast<std::size_t>(v)] : nullptr;
}

}  // namespace lidarsurf
