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

// The range image: columns of kAzimuthStep degrees, rows of kElevationStep degrees (about the
// angular resolution of a 64-beam sensor; a voxel is tested against its row and the rows beside it).
constexpr float kAzimuthStep = 0.2f, kElevationStep = 0.4f;
constexpr int kColumns = 1800;
constexpr std::uint32_t kNoPixel = 0xffffffffu;

using detail::atan2_deg;
using detail::azimuth_deg;
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

std::optional<Eigen::Vector3d> FreeSpaceCarver::image_normal(std::span<const Eigen::Vector3d> points, std::uint32_t q) const {
    // Tangents from the returns of the neighbouring pixels (the nearest within two columns and
    // within two rows) on the same surface: a range within 5 % (0.3 m at least) of the return's.
    // The ground far away has its rings metres apart: no vertical tangent there.
    const int row = static_cast<int>(q / kColumns), col = static_cast<int>(q % kColumns);
    const float r = std::sqrt(depth_[q]), tolerance = std::max(0.3f, 0.05f * r);
    const Eigen::Vector3d& p = points[nearest_[q]];
    const auto neighbour = [&](int dr, int dc) -> const Eigen::Vector3d* {
        for (int k = 1; k <= 2; ++k) {
            const int rr = row + k * dr, cc = (col + k * dc + kColumns) % kColumns;
            if (rr < 0 || rr >= rows_) return nullptr;
            const std::size_t i = static_cast<std::size_t>(rr) * kColumns + static_cast<std::size_t>(cc);
            if (nearest_[i] == kNoPixel || nearest_[i] >= real_) continue;  // no return, or an empty pixel's
            return std::fabs(std::sqrt(depth_[i]) - r) <= tolerance ? &points[nearest_[i]] : nullptr;
        }
        return nullptr;
    };
    const auto tangent = [&](const Eigen::Vector3d* a, const Eigen::Vector3d* b) -> std::optional<Eigen::Vector3d> {
        if (a && b) return *a - *b;
        if (a) return *a - p;
        if (b) return p - *b;
        return std::nullopt;
    };
    const auto along = tangent(neighbour(0, 1), neighbour(0, -1)), across = tangent(neighbour(1, 0), neighbour(-1, 0));
    if (!along || !across) return std::nullopt;
    const Eigen::Vector3d n = along->cross(*across);
    const double norm = n.norm();
    if (!(norm > 1e-6 * along->norm() * across->norm())) return std::nullopt;
    return n / norm;
}

bool FreeSpaceCarver::off_surface(const VoxelGrid& grid, std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& mu,
                                  const Eigen::Vector3d& p, std::uint32_t q) const {
    // The surface the ray returned on: the plane of the return's voxel when it has one, else the
    // normal of the range image at the return, else the horizontal plane (z up) through the
    // return. A voxel on it (the ground beyond a grazing ray's return, seen before by a ring) is
    // not seen through; the rear of a car that drove on, a vertical surface, is.
    Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
    const std::int32_t slot = grid.voxel_at(grid.key_of_local(p));
    if (slot >= 0 && evidence_[static_cast<std::size_t>(slot)].shape == Shape::Planar) {
        const Evidence& e = evidence_[static_cast<std::size_t>(slot)];
        n = Eigen::Vector3d(e.normal[0], e.normal[1], e.normal[2]);
    } else if (const auto image = image_normal(points, q)) {
        n = *image;
    }
    return std::fabs(n.dot(mu - p)) >= margin_;
}

std::size_t FreeSpaceCarver::empty_pixels(const Eigen::Vector3d& s, std::span<const Eigen::Vector3f> no_return) {
    const std::size_t pixels = static_cast<std::size_t>(rows_) * kColumns;
    empty_.assign(pixels, 0);
    // Per pixel, the first ray that fell in it; marked only where no return fell.
    std::vector<std::uint32_t>& ray_of = empty_ray_;
    ray_of.assign(pixels, kNoPixel);
    for (std::size_t i = 0; i < no_return.size(); ++i) {
        const Eigen::Vector3f& u = no_return[i];
        if (!u.allFinite() || !(u.squaredNorm() > 0)) continue;
        const Eigen::Vector3d d = u.cast<double>();
        const int row = static_cast<int>((elevation_deg(d) - el_min_) / kElevationStep);
        if (row < 0 || row >= rows_) continue;
        const int col = static_cast<int>((azimuth_deg(d) + 180.f) / kAzimuthStep) % kColumns;
        const std::size_t px = static_cast<std::size_t>(row) * kColumns + static_cast<std::size_t>(col);
        if (nearest_[px] != kNoPixel) continue;  // a return fell there too: not empty
        empty_[px] = 1;
        if (ray_of[px] == kNoPixel) ray_of[px] = static_cast<std::uint32_t>(i);
    }
    // A pixel empty with the rays beside it in its row, the nearest on either side within
    // kRayGap columns (a sensor sparser than the image leaves columns between its rays): a run of
    // rays that returned nothing, not one ray lost at random. Its return: empty_range_ along the ray.
    constexpr int kRayGap = 4;
    const auto neighbour_empty = [&](std::size_t row, std::size_t col, int step) {
        for (int k = 1; k <= kRayGap; ++k) {
            const std::size_t q = row * kColumns + (col + kColumns + static_cast<std::size_t>(k * step + kColumns)) % kColumns;
            if (empty_[q]) return true;
            if (nearest_[q] != kNoPixel) return false;  // a return beside it
        }
        return false;
    };
    // How far the ray saw: up to the nearest return around it (kRows rows, kRayGap columns either
    // way), empty_range_ at most. A surface too dark to return, in front of what the rays beside it
    // hit, ends the free space there: the wall behind a dark car is not seen through.
    constexpr int kRows = 2;
    const float cap2 = static_cast<float>(empty_range_ * empty_range_);
    const auto seen_to = [&](std::size_t row, std::size_t col) {
        float d2 = cap2;
        for (int dr = -kRows; dr <= kRows; ++dr) {
            const int r = static_cast<int>(row) + dr;
            if (r < 0 || r >= rows_) continue;
            for (int dc = -kRayGap; dc <= kRayGap; ++dc) {
                const std::size_t q = static_cast<std::size_t>(r) * kColumns + (col + static_cast<std::size_t>(dc + kColumns)) % kColumns;
                if (nearest_[q] < real_) d2 = std::min(d2, depth_[q]);
            }
        }
        return d2;
    };
    empty_points_.clear();
    std::vector<std::pair<std::size_t, float>>& accepted = empty_seen_;
    accepted.clear();
    for (std::size_t px = 0; px < pixels; ++px) {
        if (!empty_[px]) continue;
        const std::size_t row = px / kColumns, col = px % kColumns;
        if (!neighbour_empty(row, col, -1) || !neighbour_empty(row, col, 1)) continue;
        accepted.emplace_back(px, seen_to(row, col));
    }
    for (const auto& [px, d2] : accepted) {  // after every pixel is measured: the returns given here are not the rays'
        nearest_[px] = static_cast<std::uint32_t>(real_ + empty_points_.size());
        depth_[px] = d2;
        empty_points_.push_back(s + std::sqrt(static_cast<double>(d2)) * no_return[ray_of[px]].cast<double>().normalized());
    }
    return empty_points_.size();
}

CarvingStats FreeSpaceCarver::carve(VoxelGrid& grid, std::span<const Eigen::Vector3d> points, std::span<const VoxelGrid::Hit> hits,
                                    const Eigen::Vector3d& viewpoint, std::span<const Eigen::Vector3f> no_return) {
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
    // 2. The scan as a range image seen from the viewpoint: per pixel (azimuth x elevation) the
    //    nearest return. Each occupied voxel within the scan's reach, not hit by it, is tested
    //    against the returns of its pixel and of the pixels above and below it: the ray of one
    //    of them went through its surface and returned behind it -> a pass.
    const Eigen::Vector3d s = grid.to_local(viewpoint);
    const std::size_t n = points.size();
    pixel_of_.resize(n);
    elevation_.resize(n);
    range2_.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const Eigen::Vector3d d = grid.to_local(points[i]) - s;
            elevation_[i] = points[i].allFinite() ? elevation_deg(d) : std::numeric_limits<float>::quiet_NaN();
            range2_[i] = static_cast<float>(d.squaredNorm());
        }
    });
    float el_min = 90, el_max = -90;
    for (float el : elevation_)
        if (el == el) el_min = std::min(el_min, el), el_max = std::max(el_max, el);
    if (empty_range_ > 0)  // the rows of the rays that returned nothing too (the sky)
        for (const Eigen::Vector3f& u : no_return)
            if (u.allFinite() && u.squaredNorm() > 0) {
                const float el = elevation_deg(u.cast<double>());
                el_min = std::min(el_min, el), el_max = std::max(el_max, el);
            }
    if (!(el_max >= el_min)) return out;
    el_min_ = el_min;
    real_ = n;
    const int rows = static_cast<int>((el_max - el_min) / kElevationStep) + 1;
    rows_ = rows;
    const std::size_t pixels = static_cast<std::size_t>(rows) * kColumns;
    const auto pixel = [&](const Eigen::Vector3d& d, float el) -> std::uint32_t {
        const int row = static_cast<int>((el - el_min) / kElevationStep);
        if (!(el >= el_min) || row >= rows) return kNoPixel;
        const int col = static_cast<int>((azimuth_deg(d) + 180.f) / kAzimuthStep) % kColumns;
        return static_cast<std::uint32_t>(row * kColumns + col);
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            pixel_of_[i] = elevation_[i] == elevation_[i] ? pixel(grid.to_local(points[i]) - s, elevation_[i]) : kNoPixel;
    });
    nearest_.assign(pixels, kNoPixel);  // point index of the pixel's nearest return
    depth_.assign(pixels, std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t px = pixel_of_[i];
        if (px == kNoPixel) continue;
        const float d = range2_[i];
        if (d < depth_[px]) depth_[px] = d, nearest_[px] = static_cast<std::uint32_t>(i);
    }
    if (empty_range_ > 0 && !no_return.empty()) out.empty = empty_pixels(s, no_return);
    const std::vector<std::uint32_t>& nearest = nearest_;
    const std::vector<float>& depth = depth_;
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
        const std::uint32_t px = pixel(d, elevation_deg(d));
        if (px == kNoPixel) return;
        // A return that can be behind the voxel's surface by the margin is at least
        // margin - alpha farther than its mean (the crossing lies within alpha of it).
        const double behind = range + margin_ - alpha;
        const float need = behind > 0 ? static_cast<float>(behind * behind) : 0.f;
        for (int dr = -1; dr <= 1; ++dr) {
            const std::int64_t q = static_cast<std::int64_t>(px) + dr * kColumns;
            if (q < 0 || q >= static_cast<std::int64_t>(pixels) || nearest[static_cast<std::size_t>(q)] == kNoPixel) continue;
            if (depth[static_cast<std::size_t>(q)] < need) continue;
            ++tested;
            const VoxelStats& st = stats[v];
            const std::uint32_t target = nearest[static_cast<std::size_t>(q)];
            const bool empty = target >= real_;  // a ray that returned nothing: no surface where it ends
            // A planar voxel by its plane; a thick or sparse one, a young one (a car seen from
            // afar) and a stale one (no hit for stale_scans_ scans) by the returns near it.
            const bool young = e.hits <= kYoungHits, stale = stale_scans_ > 0 && stamp - e.last_hit >= static_cast<std::uint32_t>(stale_scans_);
            if (empty && !young && !stale) continue;  // emptiness alone: only a young or stale voxel
            const Eigen::Vector3d p = empty ? empty_points_[target - real_] : grid.to_local(points[target]);
            if ((e.shape == Shape::Planar && crosses_plane(st, e, s, p)) ||
                ((e.shape != Shape::Planar || young || stale) && passes_near(st, e, s, p) &&
                 (empty || off_surface(grid, points, st.mean, p, static_cast<std::uint32_t>(q))))) {
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
    float farthest2 = 0;
    for (float r2 : range2_) farthest2 = std::max(farthest2, r2);  // NaN (non-finite points) never wins
    const double keep = std::sqrt(static_cast<double>(farthest2)) + alpha;
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
