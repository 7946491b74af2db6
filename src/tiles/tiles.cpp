#include "lidarsurf/tiles/tiles.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <set>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"
#include "lidarsurf/map/carved_clusters.hpp"
#include "lidarsurf/map/range_image.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"

namespace lidarsurf {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
using Map = BlockMap<std::int32_t>;

// The x-y distance from `p` to the box (0 inside).
double distance_xy(const Eigen::Vector3d& p, const Eigen::AlignedBox3d& box) {
    const double dx = std::max({box.min().x() - p.x(), 0.0, p.x() - box.max().x()});
    const double dy = std::max({box.min().y() - p.y(), 0.0, p.y() - box.max().y()});
    return std::hypot(dx, dy);
}

Eigen::AlignedBox3d grown_xy(const Eigen::AlignedBox3d& box, double margin) {
    return {Eigen::Vector3d(box.min().x() - margin, box.min().y() - margin, -kInf),
            Eigen::Vector3d(box.max().x() + margin, box.max().y() + margin, kInf)};
}
}  // namespace

void TileConfig::validate() const {
    if (!std::isfinite(tile_size) || tile_size < 1.0) throw InvalidArgument("tile_size must be finite and >= 1 m, got " + format_value(tile_size));
    if (halo_cubes < 8 || halo_cubes > 1024) throw InvalidArgument("halo_cubes must be in [8, 1024], got " + std::to_string(halo_cubes));
    if (group < 1 || group > 64) throw InvalidArgument("group must be in [1, 64], got " + std::to_string(group));
}

ScanReach scan_reach(std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint, bool empty_rays) {
    if (!viewpoint.allFinite()) throw InvalidArgument("viewpoint must be finite");
    ScanReach r;
    r.viewpoint = viewpoint;
    r.empty_rays = empty_rays;
    double r2 = 0;
    for (const Eigen::Vector3d& p : points) {
        if (!p.allFinite()) continue;
        if (!r.first_point) r.first_point = p;
        r.box.extend(p);
        r2 = std::max(r2, (p - viewpoint).squaredNorm());
    }
    r.radius = std::sqrt(r2);
    return r;
}

void TilePlan::check(const ReconstructionConfig& config) {
    config.validate();
    if (!config.seeded_surface) throw InvalidArgument("tiles mesh with the seeded surface (not the paper as written)");
    if (config.min_component_triangles > 0) throw InvalidArgument("min_component_triangles filters the whole map's components: not with tiles");
}

TilePlan::TilePlan(std::vector<ScanReach> scans, const ReconstructionConfig& config, const TileConfig& tiles)
    : scans_(std::move(scans)), config_(config), tile_config_(tiles) {
    check(config_);
    tile_config_.validate();
    const auto first = std::find_if(scans_.begin(), scans_.end(), [](const ScanReach& s) { return s.first_point.has_value(); });
    if (first == scans_.end()) throw InvalidInput("the sequence has no finite point");
    origin_ = *first->first_point;
    const double alpha = config_.voxel_size;
    for (const ScanReach& s : scans_) {
        if (!s.viewpoint.allFinite()) throw InvalidArgument("viewpoint must be finite");
        ray_reach_ = std::max(ray_reach_, s.radius);
        if (!s.box.isEmpty()) bounds_.extend(s.box);
    }
    // A cube in the square depends on the vertices within the search halo, each on the voxels
    // within max_reach; one block more for the blocks that straddle the square's edge.
    dependency_margin_ = alpha * (tile_config_.halo_cubes + config_.max_reach() + 2 * Map::kSize);
    // Carving a voxel of the dependency box reads, besides the scans' range images (whole), the
    // plane of the voxel a ray returned in within carve_plane_reach of it, and removes it with
    // the rest of a cluster: one searched from a voxel carved within the clusters' reach of it
    // (which read the planes within carve_plane_reach of itself), and that goes only when it
    // reaches no farther than that from where the search started. Two voxels more.
    const double reach = CarvedClusters::kReach;
    crop_margin_ = config_.carve ? reach + std::max(reach, config_.carve_plane_reach) + 2 * alpha : 0.0;
    // The tiles within reach of a point: a vertex is defined within max_reach of a voxel.
    std::set<TileKey> keys;
    const double near = alpha * (config_.max_reach() + 2);
    for (const ScanReach& s : scans_) {
        if (s.box.isEmpty()) continue;
        const TileKey lo = tile_of(s.box.min() - Eigen::Vector3d::Constant(near));
        const TileKey hi = tile_of(s.box.max() + Eigen::Vector3d::Constant(near));
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) keys.insert({x, y});
    }
    tiles_.assign(keys.begin(), keys.end());
    std::sort(tiles_.begin(), tiles_.end(), [](const TileKey& a, const TileKey& b) { return std::tie(a.y, a.x) < std::tie(b.y, b.x); });
}

std::vector<std::vector<TileKey>> TilePlan::groups() const {
    const int g = tile_config_.group;
    const auto floor_div = [g](int v) { return v >= 0 ? v / g : -((-v + g - 1) / g); };
    std::map<std::pair<int, int>, std::vector<TileKey>> by_square;  // (y, x) of the group's square
    for (const TileKey& t : tiles_) by_square[{floor_div(t.y), floor_div(t.x)}].push_back(t);  // tiles_ is in (y, x) order
    std::vector<std::vector<TileKey>> out;
    out.reserve(by_square.size());
    for (auto& [square, group] : by_square) out.push_back(std::move(group));
    return out;
}

TileKey TilePlan::tile_of(const Eigen::Vector3d& world) const {
    const double s = tile_config_.tile_size;
    return {static_cast<int>(std::floor(world.x() / s)), static_cast<int>(std::floor(world.y() / s))};
}

Eigen::AlignedBox3d TilePlan::square(const TileKey& t) const {
    const double s = tile_config_.tile_size;
    return {Eigen::Vector3d(t.x * s, t.y * s, -kInf), Eigen::Vector3d((t.x + 1) * s, (t.y + 1) * s, kInf)};
}

Eigen::AlignedBox3d TilePlan::dependency(const TileKey& t) const { return grown_xy(square(t), dependency_margin_); }

Eigen::AlignedBox3d TilePlan::crop(const TileKey& t) const { return grown_xy(dependency(t), crop_margin_); }

bool TilePlan::reaches(const TileKey& t, std::size_t scan) const {
    const ScanReach& s = scans_.at(scan);
    if (s.box.isEmpty()) return false;
    // No return beyond the radius (nor a ray that returned nothing, beyond carve_empty_range): no
    // voxel farther than it (and a voxel) is passed or hit, and the young voxels it would keep are
    // within it. A metre for rounding (the carver's floats).
    const double radius = s.empty_rays && config_.carve ? std::max(s.radius, config_.carve_empty_range) : s.radius;
    return distance_xy(s.viewpoint, crop(t)) <= radius + 2 * config_.voxel_size + 1.0;
}

std::size_t TilePlan::scans_of(const TileKey& t) const {
    std::size_t n = 0;
    for (std::size_t i = 0; i < scans_.size(); ++i) n += reaches(t, i);
    return n;
}

Mesh fuse_tile(const TilePlan& plan, const TileKey& tile, const std::function<std::vector<Eigen::Vector3d>(std::size_t)>& scan,
               ReconstructionSummary* summary) {
    return fuse_tile(plan, tile, [&](std::size_t i, std::vector<Eigen::Vector3f>&) { return PointCloud{scan(i)}; }, summary);
}

Mesh fuse_tile(const TilePlan& plan, const TileKey& tile, const TileScans& scan, ReconstructionSummary* summary) {
    Mesh out;
    fuse_tiles(plan, std::span<const TileKey>(&tile, 1), scan, [&](const TileKey&, Mesh&& mesh, const ReconstructionSummary& s) {
        out = std::move(mesh);
        if (summary) *summary = s;
    });
    return out;
}

TilePassStats fuse_tiles(const TilePlan& plan, std::span<const TileKey> tiles, const TileScans& scan, const TileDone& done) {
    using Clock = std::chrono::steady_clock;
    const auto seconds_since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
    const ReconstructionConfig& config = plan.config();
    struct Tile {
        TileKey key;
        std::size_t first = 0, last = 0;  // the first and last scans that reach it
        Eigen::AlignedBox3d crop;
        std::unique_ptr<Reconstructor> rec;
    };
    std::vector<Tile> open;  // every tile some scan reaches, until it is meshed
    std::vector<std::size_t> needed;  // the scans some tile of the group takes, in order
    {
        std::vector<bool> wanted(plan.scan_count(), false);
        for (const TileKey& key : tiles) {
            Tile t{key, plan.scan_count(), 0, plan.crop(key), nullptr};
            for (std::size_t i = 0; i < plan.scan_count(); ++i)
                if (plan.reaches(key, i)) t.first = std::min(t.first, i), t.last = i, wanted[i] = true;
            if (t.first == plan.scan_count()) done(key, Mesh{}, ReconstructionSummary{});
            else open.push_back(std::move(t));
        }
        for (std::size_t i = 0; i < wanted.size(); ++i)
            if (wanted[i]) needed.push_back(i);
    }
    TilePassStats stats;
    RangeImage image;
    Eigen::Vector3d origin = plan.grid_origin();
    const double budget = config.max_memory_mb * 1048576.0;
    // Each needed scan read once, the next one on a thread of its own while this one is fused.
    struct Read {
        PointCloud cloud;
        std::vector<Eigen::Vector3f> no_return;
        double seconds = 0;
    };
    const auto read = [&scan, &seconds_since](std::size_t i) {
        Read r;
        const auto t0 = Clock::now();
        r.cloud = scan(i, r.no_return);
        r.seconds = seconds_since(t0);
        return r;
    };
    std::size_t next_read = 0;
    std::future<Read> reading;
    if (!needed.empty()) reading = std::async(std::launch::async, read, needed[next_read++]);
    for (std::size_t i = 0; i < plan.scan_count() && !open.empty(); ++i) {
        std::size_t opened = 0;
        for (Tile& t : open) {
            if (t.first > i) continue;
            if (!t.rec) {  // opened at its first scan: the ones before it are counted
                t.rec = std::make_unique<Reconstructor>(config, plan.sensor(), plan.grid_origin());
                for (std::size_t k = 0; k < i; ++k) t.rec->skip_scan();
                origin = t.rec->grid().origin();  // the lattice point every tile's grid takes
            }
            ++opened;
        }
        stats.most_open = std::max(stats.most_open, opened);
        if (next_read == 0 || needed[next_read - 1] != i) {  // no tile of the group takes scan i
            for (Tile& t : open)
                if (t.rec) t.rec->skip_scan();
            continue;
        }
        const Read current = reading.get();
        if (next_read < needed.size()) reading = std::async(std::launch::async, read, needed[next_read++]);
        const PointCloud& cloud = current.cloud;
        const std::vector<Eigen::Vector3f>& no_return = current.no_return;
        stats.seconds_read += current.seconds;
        ++stats.scans_read;
        const Eigen::Vector3d& viewpoint = plan.viewpoint(i);
        if (config.carve) {
            const auto t1 = Clock::now();
            image.build(origin, cloud.points, viewpoint, no_return, config.carve_empty_range);
            stats.seconds_image += seconds_since(t1);
        }
        std::size_t held = 0;
        for (Tile& t : open) {
            if (!t.rec) continue;
            if (!plan.reaches(t.key, i)) t.rec->skip_scan();
            else if (config.carve) t.rec->integrate(cloud.points, viewpoint, t.crop, image, cloud.intensities);
            else t.rec->integrate(cloud.points, viewpoint, t.crop, no_return, cloud.intensities);
            held += t.rec->map_bytes();
        }
        // The scan, the one read ahead (about as large) and the image beside the open tiles' maps.
        const std::size_t scan_bytes = 2 * (cloud.points.capacity() * sizeof(Eigen::Vector3d) + cloud.intensities.capacity() * sizeof(float) +
                                            no_return.capacity() * sizeof(Eigen::Vector3f));
        const std::size_t fusing = kProcessBaselineBytes + held + image.memory_bytes() + scan_bytes;
        stats.memory_estimate = std::max(stats.memory_estimate, fusing);
        if (static_cast<double>(fusing) > budget) {
            char buf[200];
            std::snprintf(buf, sizeof buf, "the tiles fused at once would need about %.0f MiB, above the memory budget of %.0f MiB",
                          static_cast<double>(fusing) / 1048576.0, config.max_memory_mb);
            throw ResourceLimit(std::string(buf) + "; use smaller tiles or groups (tile_size, group; CLI --tile-size, --tile-group) or raise the budget (max_memory_mb, CLI --max-memory)");
        }
        for (auto it = open.begin(); it != open.end();) {
            if (it->last != i) {
                ++it;
                continue;
            }
            Mesh mesh = mesh_tile(*it->rec, plan, it->key);
            const ReconstructionSummary summary = it->rec->summary();
            // Its extraction (the summary's estimate: the baseline, its map and the extraction)
            // beside the other open tiles' maps and the scans in hand.
            std::size_t others = image.memory_bytes() + scan_bytes;
            for (const Tile& t : open)
                if (t.rec && &t != &*it) others += t.rec->map_bytes();
            stats.memory_estimate = std::max(stats.memory_estimate, summary.memory_estimate + others);
            const TileKey key = it->key;
            it = open.erase(it);  // the tile's grid is freed before the next one is handed over
            done(key, std::move(mesh), summary);
        }
    }
    return stats;
}

Mesh mesh_tile(Reconstructor& rec, const TilePlan& plan, const TileKey& tile) {
    const VoxelGrid& grid = rec.grid();
    if (grid.point_count() == 0) return {};
    // The search: the blocks of cubes in the square that are within reach of a voxel, and the halo.
    const ReconstructionConfig& config = plan.config();
    const double alpha = config.voxel_size, block = alpha * Map::kSize;
    const Eigen::AlignedBox3d sq = plan.square(tile);
    const Eigen::Vector3d& o = grid.origin();
    const int r = (config.max_reach() + 1 + Map::kSize - 1) / Map::kSize;
    const auto block_lo = [&](double world, double org) { return static_cast<int>(std::floor((world - org) / block)); };
    const int bx0 = block_lo(sq.min().x(), o.x()), bx1 = block_lo(sq.max().x(), o.x());
    const int by0 = block_lo(sq.min().y(), o.y()), by1 = block_lo(sq.max().y(), o.y());
    BlockIndex seen;
    std::vector<VoxelKey> core;
    for (const VoxelKey& b : grid.index().block_keys()) {
        if (b.x() + r < bx0 || b.x() - r > bx1 || b.y() + r < by0 || b.y() - r > by1) continue;
        for (int z = -r; z <= r; ++z)
            for (int y = std::max(b.y() - r, by0); y <= std::min(b.y() + r, by1); ++y)
                for (int x = std::max(b.x() - r, bx0); x <= std::min(b.x() + r, bx1); ++x) {
                    const VoxelKey k(x, y, b.z() + z);
                    if (seen.try_emplace(k, 0).second) core.push_back(k);
                }
    }
    if (core.empty()) return {};
    const SearchRegion region = SearchRegion::around(core, plan.tile_config().halo_cubes);
    const auto owns = [&](const VoxelKey& cube) {
        return plan.tile_of(o + alpha * (cube.cast<double>() + Eigen::Vector3d::Constant(0.5))) == tile;
    };
    return rec.extract_mesh(region, owns);
}

std::size_t SeamWelder::KeyHash::operator()(const Key& k) const noexcept {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (std::uint64_t v : k.position) h = (h ^ v) * 0xff51afd7ed558ccdull, h ^= h >> 33;
    for (std::uint32_t v : k.attributes) h = (h ^ v) * 0xc4ceb9fe1a85ec53ull, h ^= h >> 29;
    return static_cast<std::size_t>(h);
}

std::vector<std::int64_t> SeamWelder::weld(const TileKey& tile, const Mesh& part, std::uint64_t written) {
    // Only a vertex within a cube of the square's border can be shared with another tile.
    const Eigen::AlignedBox3d sq = plan_->square(tile);
    const double near = 1.5 * plan_->config().voxel_size;
    std::vector<std::int64_t> out(part.vertices.size(), -1);
    for (std::size_t i = 0; i < part.vertices.size(); ++i) {
        const Eigen::Vector3d& v = part.vertices[i];
        const bool border = v.x() - sq.min().x() < near || sq.max().x() - v.x() < near || v.y() - sq.min().y() < near ||
                            sq.max().y() - v.y() < near;
        if (!border) {
            ++written;
            continue;
        }
        Key key{};
        for (int a = 0; a < 3; ++a) key.position[static_cast<std::size_t>(a)] = std::bit_cast<std::uint64_t>(v[a]);
        if (!part.normals.empty())
            for (int a = 0; a < 3; ++a) key.attributes[static_cast<std::size_t>(a)] = std::bit_cast<std::uint32_t>(part.normals[i][a]);
        if (!part.confidence.empty()) key.attributes[3] = std::bit_cast<std::uint32_t>(part.confidence[i]);
        if (!part.levels.empty()) key.attributes[4] = part.levels[i];
        if (!part.intensity.empty()) key.attributes[5] = std::bit_cast<std::uint32_t>(part.intensity[i]);
        const auto [it, added] = seam_.try_emplace(key, written);
        if (added) ++written;
        else out[i] = static_cast<std::int64_t>(it->second);
    }
    return out;
}

}  // namespace lidarsurf
