#include "lidarsurf/map/free_space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Eigenvalues>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/surface/plane_eigen.hpp"
#include "angles.hpp"

namespace lidarsurf {
namespace {

constexpr double kChi2 = 4.0;           // two sigmas: the ray goes through the points, not beside them
constexpr double kLinePlanarity = 0.05;  // lambda2 < this * lambda1: the points are a line (one ring)
constexpr double kThinness = 0.25;       // lambda3 > this * lambda2: not one plane (a corner, foliage)

constexpr int kColumns = RangeImage::kColumns;
constexpr std::uint32_t kNoPixel = RangeImage::kNoPixel;

using detail::elevation_deg;

}  // namespace

namespace {
const CarvingConfig& checked(const CarvingConfig& c) {
    c.validate();
    return c;
}
}  // namespace

FreeSpaceCarver::FreeSpaceCarver(const CarvingConfig& config, double voxel_size)
    : margin_(checked(config).carve_margin_voxels * voxel_size),
      min_scans_(config.carve_min_scans),
      range_(config.carve_range),
      stale_scans_(config.carve_stale_scans),
      stale_passes_(config.carve_stale_passes),
      empty_range_(config.carve_empty_range),
      plane_reach2_(config.carve_plane_reach * config.carve_plane_reach),
      sigma2_(0),
      clusters_(config.carve_cluster_share, voxel_size) {
    if (!std::isfinite(voxel_size) || voxel_size <= 0) throw InvalidArgument("carving: voxel size must be finite and > 0");
}

void FreeSpaceCarver::fit(const VoxelStats& stats, Evidence& e) const {
    for (int i = 0; i < 3; ++i) e.mean[i] = static_cast<float>(stats.mean[i]);
    e.shape = Shape::Sparse;
    if (stats.count < static_cast<std::uint64_t>(kMinPoints)) return;
    e.shape = Shape::None;
    const Eigen::Matrix3d c = stats.covariance();
    double l1, l2, l3;
    Eigen::Vector3d n;
    if (const auto eig = plane_eigen(c)) {
        l1 = eig->lambda1, l2 = eig->lambda2, l3 = eig->lambda3, n = eig->e3;
    } else {
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
        solver.computeDirect(c);
        l3 = solver.eigenvalues()[0], l2 = solver.eigenvalues()[1], l1 = solver.eigenvalues()[2];
        n = solver.eigenvectors().col(0);
    }
    if (!(l1 > 0)) return;
    if (l2 < kLinePlanarity * l1) {
        e.shape = Shape::Line;
        return;
    }
    if (l3 > kThinness * l2) {
        e.shape = Shape::Thick;
        return;
    }
    e.shape = Shape::Planar;
    for (int i = 0; i < 3; ++i) e.normal[i] = static_cast<float>(n[i]);
    e.lambda1 = static_cast<float>(l1 + sigma2_);
    e.lambda2 = static_cast<float>(l2 + sigma2_);
}

Eigen::Matrix3d FreeSpaceCarver::covariance(const VoxelStats& stats, const Evidence& e) const {
    const double sigma2 = e.shape == Shape::Sparse ? 4 * sigma2_ : sigma2_;  // a few points: a ball of alpha / 2
    return stats.covariance() + sigma2 * Eigen::Matrix3d::Identity();
}

bool FreeSpaceCarver::crosses_plane(const VoxelStats& stats, const Evidence& e, const Eigen::Vector3d& s, const Eigen::Vector3d& p) const {
    const Eigen::Vector3d& mu = stats.mean;
    Eigen::Vector3d n(e.normal[0], e.normal[1], e.normal[2]);
    double ds = n.dot(s - mu);
    if (ds < 0) n = -n, ds = -ds;
    const double dp = n.dot(p - mu);
    if (dp > -margin_) return false;  // the return is not behind the plane by the margin
    const Eigen::Vector3d d = s + (ds / (ds - dp)) * (p - s) - mu;  // where the ray crosses the plane
    const double q0 = d.squaredNorm(), q1 = d.dot(covariance(stats, e) * d);
    const double l1 = e.lambda1, l2 = e.lambda2;
    return ((l1 + l2) * q0 - q1) <= kChi2 * l1 * l2;  // Eq. (3)'s in-plane form (docs/method.md)
}

bool FreeSpaceCarver::passes_near(const VoxelStats& stats, const Evidence& e, const Eigen::Vector3d& s, const Eigen::Vector3d& p) const {
    const Eigen::Vector3d& mu = stats.mean;
    const Eigen::Vector3d u = (p - s).normalized();
    const Eigen::Matrix3d a = covariance(stats, e).inverse();
    const Eigen::Vector3d au = a * u;
    const double t = au.dot(mu - s) / au.dot(u);  // the point of the ray nearest the mean (Mahalanobis)
    if (t <= 0 || (p - s).norm() - t < margin_) return false;
    const Eigen::Vector3d d = s + t * u - mu;
    return d.dot(a * d) <= kChi2;
}

bool FreeSpaceCarver::off_surface(const VoxelGrid& grid, const RangeImage& image, const Eigen::Vector3d& mu, const Eigen::Vector3d& p,
                                  std::uint32_t q) const {
    // The surface the ray returned on: the plane of the return's voxel when it has one and the
    // voxel is within plane_reach of the return, else the normal of the range image at the
    // return, else the horizontal plane (z up) through the return. A voxel on it (the ground
    // beyond a grazing ray's return, seen before by a ring) is not seen through; the rear of a
    // car that drove on, a vertical surface, is.
    Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
    const std::int32_t slot = (mu - p).squaredNorm() <= plane_reach2_ ? grid.voxel_at(grid.key_of_local(p)) : -1;
    if (slot >= 0 && evidence_[static_cast<std::size_t>(slot)].shape == Shape::Planar) {
        const Evidence& e = evidence_[static_cast<std::size_t>(slot)];
        n = Eigen::Vector3d(e.normal[0], e.normal[1], e.normal[2]);
    } else if (const auto normal = image.normal(q)) {
        n = *normal;
    }
    return std::fabs(n.dot(mu - p)) >= margin_;
}

CarvingStats FreeSpaceCarver::carve(VoxelGrid& grid, std::span<const Eigen::Vector3d> points, std::span<const VoxelGrid::Hit> hits,
                                    const Eigen::Vector3d& viewpoint, std::span<const Eigen::Vector3f> no_return) {
    image_.build(grid.origin(), points, viewpoint, no_return, empty_range_);
    return carve(grid, image_, hits);
}

CarvingStats FreeSpaceCarver::carve(VoxelGrid& grid, const RangeImage& image, std::span<const VoxelGrid::Hit> hits) {
    if (!image.empty() && image.origin() != grid.origin()) throw InvalidArgument("carving: the range image is not in the grid's frame");
    CarvingStats out;
    const double alpha = grid.voxel_size();
    sigma2_ = (alpha / 8) * (alpha / 8);
    const std::uint32_t stamp = ++scan_;
    // 1. Hits: counted once per scan; the voxels whose statistics changed get their shape again.
    const std::size_t before = evidence_.size();
    evidence_.resize(grid.size());
    std::vector<std::uint32_t> refit;
    refit.reserve(hits.size() + grid.size() - before);
    for (const VoxelGrid::Hit& h : hits) {
        Evidence& e = evidence_[h.voxel];
        if (e.last_hit == stamp) continue;
        if (e.hits < UINT16_MAX) ++e.hits;
        e.since_hit = 0;
        e.last_hit = stamp;
        refit.push_back(h.voxel);
    }
    for (std::size_t v = before; v < grid.size(); ++v)
        if (evidence_[v].last_hit != stamp) {  // integrated before carving started: one hit
            evidence_[v].hits = 1;
            refit.push_back(static_cast<std::uint32_t>(v));
        }
    const std::vector<VoxelStats>& stats = grid.stats();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, refit.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) fit(stats[refit[i]], evidence_[refit[i]]);
    });
    // 2. The scan as a range image seen from the viewpoint (map/range_image.hpp): per pixel
    //    (azimuth x elevation) the nearest return. Each occupied voxel within the scan's reach,
    //    not hit by it, is tested against the returns of its pixel and of the pixels above and
    //    below it: the ray of one of them went through its surface and returned behind it -> a pass.
    if (image.empty()) return out;
    const Eigen::Vector3d& s = image.sensor();
    const std::size_t pixels = image.pixels();
    out.empty = image.empty_pixels();
    using Map = BlockMap<std::int32_t>;
    constexpr int B = Map::kSize;
    const BlockKeys& index = grid.index();
    const double reach = range_ + B * alpha;  // block centres: the range plus half a block's diagonal
    tbb::enumerable_thread_specific<std::vector<std::uint32_t>> passed;
    tbb::enumerable_thread_specific<std::size_t> crossings(0);
    // One voxel against the scan: within `limit` of the viewpoint, not hit by the scan, one of the
    // returns of its pixel and of the pixels above and below saw through it.
    const auto test = [&](std::uint32_t v, double limit, std::vector<std::uint32_t>& mine, std::size_t& tested) {
        Evidence& e = evidence_[v];
        if (e.last_hit == stamp || e.shape == Shape::None) return;
        const Eigen::Vector3d d = Eigen::Vector3d(e.mean[0], e.mean[1], e.mean[2]) - s;
        const double range = d.norm();
        if (range > limit) return;
        const std::uint32_t px = image.pixel(d, elevation_deg(d));
        if (px == kNoPixel) return;
        // A return that can be behind the voxel's surface by the margin is at least
        // margin - alpha farther than its mean (the crossing lies within alpha of it).
        const double behind = range + margin_ - alpha;
        const float need = behind > 0 ? static_cast<float>(behind * behind) : 0.f;
        for (int dr = -1; dr <= 1; ++dr) {
            const std::int64_t q = static_cast<std::int64_t>(px) + dr * kColumns;
            if (q < 0 || q >= static_cast<std::int64_t>(pixels) || image.nearest(static_cast<std::size_t>(q)) == kNoPixel) continue;
            if (image.depth2(static_cast<std::size_t>(q)) < need) continue;
            ++tested;
            const VoxelStats& st = stats[v];
            const std::uint32_t target = image.nearest(static_cast<std::size_t>(q));
            const bool empty = image.no_surface(target);  // a ray that returned nothing: no surface where it ends
            // A planar voxel by its plane; a thick or sparse one, a young one (a car seen from
            // afar) and a stale one (no hit for stale_scans_ scans) by the returns near it.
            const bool young = e.hits <= kYoungHits, stale = stale_scans_ > 0 && stamp - e.last_hit >= static_cast<std::uint32_t>(stale_scans_);
            if (empty && !young && !stale) continue;  // emptiness alone: only a young or stale voxel
            const Eigen::Vector3d p = image.return_point(target);
            if ((e.shape == Shape::Planar && crosses_plane(st, e, s, p)) ||
                ((e.shape != Shape::Planar || young || stale) && passes_near(st, e, s, p) &&
                 (empty || off_surface(grid, image, st.mean, p, static_cast<std::uint32_t>(q))))) {
                e.last_pass = stamp;
                mine.push_back(v);
                return;
            }
        }
    };
    // 2a. Every voxel within the range, block by block.
    const std::vector<VoxelKey>& block_keys = index.block_keys();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block_keys.size(), 64), [&](const auto& r) {
        std::vector<std::uint32_t>& mine = passed.local();
        std::size_t& tested = crossings.local();
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            const Eigen::Vector3d centre = (block_keys[b].cast<double>() + Eigen::Vector3d::Constant(0.5)) * (B * alpha);
            if ((centre - s).squaredNorm() > reach * reach) continue;
            for (const std::int32_t v : grid.block_voxels(b)) test(static_cast<std::uint32_t>(v), range_, mine, tested);
        }
    });
    // 2b. Beyond the range, the young voxels only (at most kYoungHits scans hit them): a moving
    //     object seen from afar, once or twice, is tested by every later scan that can see
    //     through it, at the cost of a few voxels instead of every static surface in sight.
    //     The list keeps those still young within the scan's reach (its farthest return), then
    //     adds the new ones (a key removed and hit again is new): its length follows the area
    //     around the drive, not the map. One left behind is tested within the range again if
    //     a later pass comes back.
    const double keep = image.farthest() + alpha;
    std::size_t kept = 0;
    young_slots_.clear();
    for (const VoxelKey& key : young_) {
        const Eigen::Vector3d centre = (key.cast<double>() + Eigen::Vector3d::Constant(0.5)) * alpha;
        if ((centre - s).squaredNorm() > keep * keep) continue;
        const std::int32_t slot = grid.voxel_at(key);
        if (slot < 0 || static_cast<std::size_t>(slot) >= before || evidence_[static_cast<std::size_t>(slot)].hits > kYoungHits) continue;
        young_slots_.push_back(static_cast<std::uint32_t>(slot));
        young_[kept++] = key;
    }
    young_.resize(kept);
    for (std::size_t v = before; v < grid.size(); ++v) {
        young_.push_back(grid.keys()[v]);
        young_slots_.push_back(static_cast<std::uint32_t>(v));
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, young_slots_.size(), 1024), [&](const auto& r) {
        std::vector<std::uint32_t>& mine = passed.local();
        std::size_t& tested = crossings.local();
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const std::uint32_t v = young_slots_[i];
            const Evidence& e = evidence_[v];
            const Eigen::Vector3d d = Eigen::Vector3d(e.mean[0], e.mean[1], e.mean[2]) - s;
            if (d.squaredNorm() > range_ * range_) test(v, std::numeric_limits<double>::infinity(), mine, tested);
        }
    });
    out.rays = pixels;
    for (std::size_t c : crossings) out.crossings += c;
    // 3. Passes, counted once per scan; removal in decreasing index order (each removal moves the
    //    last voxel, which is then never one still to remove).
    std::vector<std::uint32_t> pass;
    for (const auto& mine : passed) pass.insert(pass.end(), mine.begin(), mine.end());
    std::sort(pass.begin(), pass.end());
    out.passes = pass.size();
    std::vector<std::uint32_t> carved;  // increasing
    for (std::uint32_t v : pass) {
        Evidence& e = evidence_[v];
        if (e.passes < UINT16_MAX) ++e.passes;
        if (e.since_hit < UINT16_MAX) ++e.since_hit;
        const bool stale = stale_scans_ > 0 && stamp - e.last_hit >= static_cast<std::uint32_t>(stale_scans_);
        if ((e.passes >= min_scans_ && (e.passes > e.hits || e.hits <= 1)) || (stale_passes_ > 0 && stale && e.since_hit >= stale_passes_))
            carved.push_back(v);
    }
    // 4. The rest of the clusters mostly carved (map/carved_clusters.hpp), found after the
    //    removals: the voxels removed are tombstones, the seeds those above the ground.
    const auto last_hit = [&](std::size_t v) { return evidence_[v].last_hit; };
    const auto mean_z = [&](std::size_t v) { return evidence_[v].mean[2]; };
    clusters_.add_ground(grid, before, mean_z);
    std::vector<VoxelKey> seeds;
    const auto remove = [&](const std::vector<std::uint32_t>& gone, std::vector<VoxelKey>* buried) {  // gone: increasing
        for (const std::uint32_t v : gone) {
            const VoxelKey& key = grid.keys()[v];
            if (clusters_.bury(key, mean_z(v), last_hit(v), stamp) && buried) buried->push_back(key);
        }
        for (auto it = gone.rbegin(); it != gone.rend(); ++it) {
            const std::size_t moved = grid.remove(*it);
            evidence_[*it] = evidence_[moved];
            evidence_.pop_back();
        }
    };
    remove(carved, &seeds);
    out.removed = carved.size();
    if (!seeds.empty()) {
        const std::vector<std::uint32_t> rest = clusters_.follow(grid, seeds, stamp, last_hit, mean_z);
        remove(rest, nullptr);
        out.clustered = rest.size();
        out.removed += rest.size();
    }
    return out;
}

}  // namespace lidarsurf
