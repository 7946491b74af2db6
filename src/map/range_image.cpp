#include "lidarsurf/map/range_image.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include "angles.hpp"

namespace lidarsurf {
namespace {
using detail::azimuth_deg;
using detail::elevation_deg;
}  // namespace

std::uint32_t RangeImage::pixel(const Eigen::Vector3d& d, float el) const {
    const int row = static_cast<int>((el - el_min_) / kElevationStep);
    if (!(el >= el_min_) || row >= rows_) return kNoPixel;
    const int col = static_cast<int>((azimuth_deg(d) + 180.f) / kAzimuthStep) % kColumns;
    return static_cast<std::uint32_t>(row * kColumns + col);
}

void RangeImage::build(const Eigen::Vector3d& origin, std::span<const Eigen::Vector3d> points, const Eigen::Vector3d& viewpoint,
                       std::span<const Eigen::Vector3f> no_return, double empty_range) {
    points_ = points;
    origin_ = origin;
    s_ = viewpoint - origin;
    rows_ = 0;
    real_ = points.size();
    empty_points_.clear();
    const std::size_t n = points.size();
    pixel_of_.resize(n);
    elevation_.resize(n);
    range2_.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            const Eigen::Vector3d d = (points[i] - origin) - s_;
            elevation_[i] = points[i].allFinite() ? elevation_deg(d) : std::numeric_limits<float>::quiet_NaN();
            range2_[i] = static_cast<float>(d.squaredNorm());
        }
    });
    float farthest2 = 0;
    for (float r2 : range2_) farthest2 = std::max(farthest2, r2);  // NaN (non-finite points) never wins
    farthest_ = std::sqrt(static_cast<double>(farthest2));
    float el_min = 90, el_max = -90;
    for (float el : elevation_)
        if (el == el) el_min = std::min(el_min, el), el_max = std::max(el_max, el);
    if (empty_range > 0)  // the rows of the rays that returned nothing too (the sky)
        for (const Eigen::Vector3f& u : no_return)
            if (u.allFinite() && u.squaredNorm() > 0) {
                const float el = elevation_deg(u.cast<double>());
                el_min = std::min(el_min, el), el_max = std::max(el_max, el);
            }
    if (!(el_max >= el_min)) return;
    el_min_ = el_min;
    rows_ = static_cast<int>((el_max - el_min) / kElevationStep) + 1;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            pixel_of_[i] = elevation_[i] == elevation_[i] ? pixel((points[i] - origin) - s_, elevation_[i]) : kNoPixel;
    });
    nearest_.assign(pixels(), kNoPixel);
    depth_.assign(pixels(), std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t px = pixel_of_[i];
        if (px == kNoPixel) continue;
        const float d = range2_[i];
        if (d < depth_[px]) depth_[px] = d, nearest_[px] = static_cast<std::uint32_t>(i);
    }
    if (empty_range > 0 && !no_return.empty()) mark_empty(no_return, empty_range);
}

std::optional<Eigen::Vector3d> RangeImage::normal(std::uint32_t q) const {
    // Tangents from the returns of the neighbouring pixels (the nearest within two columns and
    // within two rows) on the same surface: a range within 5 % (0.3 m at least) of the return's.
    // The ground far away has its rings metres apart: no vertical tangent there.
    const int row = static_cast<int>(q / kColumns), col = static_cast<int>(q % kColumns);
    const float r = std::sqrt(depth_[q]), tolerance = std::max(0.3f, 0.05f * r);
    const Eigen::Vector3d& p = points_[nearest_[q]];
    const auto neighbour = [&](int dr, int dc) -> const Eigen::Vector3d* {
        for (int k = 1; k <= 2; ++k) {
            const int rr = row + k * dr, cc = (col + k * dc + kColumns) % kColumns;
            if (rr < 0 || rr >= rows_) return nullptr;
            const std::size_t i = static_cast<std::size_t>(rr) * kColumns + static_cast<std::size_t>(cc);
            if (nearest_[i] == kNoPixel || nearest_[i] >= real_) continue;  // no return, or an empty pixel's
            return std::fabs(std::sqrt(depth_[i]) - r) <= tolerance ? &points_[nearest_[i]] : nullptr;
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

void RangeImage::mark_empty(std::span<const Eigen::Vector3f> no_return, double empty_range) {
    const std::size_t pixels = this->pixels();
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
    // rays that returned nothing, not one ray lost at random. Its return: empty_range along the ray.
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
    // way), empty_range at most. A surface too dark to return, in front of what the rays beside it
    // hit, ends the free space there: the wall behind a dark car is not seen through.
    constexpr int kRows = 2;
    const float cap2 = static_cast<float>(empty_range * empty_range);
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
        empty_points_.push_back(s_ + std::sqrt(static_cast<double>(d2)) * no_return[ray_of[px]].cast<double>().normalized());
    }
}

}  // namespace lidarsurf
