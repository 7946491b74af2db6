// The no-return rays of an organized cloud (see organized_rays.hpp).
#include "organized_rays.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace lidarsurf::detail {
namespace {

constexpr double kFitRange = 8.0;                     // metres: nearer returns carry the beams' origin offsets in their angles
constexpr double kTolerance = 0.5 * M_PI / 180;       // radians
constexpr double kInliers = 0.95;

double wrap(double a) { return std::remainder(a, 2 * M_PI); }

double median(std::vector<double>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

}  // namespace

std::vector<Eigen::Vector3f> organized_no_return_directions(std::uint32_t height, std::uint32_t width, const std::vector<Eigen::Vector3d>& points,
                                                            const std::vector<std::uint32_t>& cells, const std::vector<std::uint32_t>& empty) {
    if (height < 2 || width < 2 || empty.empty()) return {};
    // The far returns: their elevation and azimuth from the sensor's origin.
    struct Ray {
        std::uint32_t row, col;
        double el, az;
    };
    std::vector<Ray> rays;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector3d& p = points[i];
        if (p.norm() < kFitRange) continue;
        rays.push_back({cells[i] / width, cells[i] % width, std::atan2(p.z(), std::hypot(p.x(), p.y())), std::atan2(p.y(), p.x())});
    }
    // Rows: the median elevation; columns: the circular mean azimuth, less each row's offset (the
    // beams' azimuth offsets), fitted in turn four times.
    std::vector<std::vector<double>> by_row(height);
    for (const Ray& r : rays) by_row[r.row].push_back(r.el);
    std::vector<std::optional<double>> elevation(height), offset(height, 0.0);
    for (std::uint32_t r = 0; r < height; ++r)
        if (by_row[r].size() >= 3) elevation[r] = median(by_row[r]);
    std::vector<std::optional<double>> azimuth(width);
    for (int pass = 0; pass < 4; ++pass) {
        std::vector<Eigen::Vector2d> sum(width, Eigen::Vector2d::Zero());
        for (const Ray& r : rays) {
            const double a = r.az - offset[r.row].value_or(0.0);
            sum[r.col] += Eigen::Vector2d(std::cos(a), std::sin(a));
        }
        for (std::uint32_t c = 0; c < width; ++c)
            azimuth[c] = sum[c].norm() > 0 ? std::optional<double>(std::atan2(sum[c].y(), sum[c].x())) : std::nullopt;
        for (auto& v : by_row) v.clear();
        for (const Ray& r : rays) by_row[r.row].push_back(wrap(r.az - *azimuth[r.col]));
        for (std::uint32_t r = 0; r < height; ++r) offset[r] = by_row[r].size() >= 3 ? std::optional<double>(median(by_row[r])) : std::nullopt;
    }
    // The grid must explain the returns.
    std::size_t fit = 0, total = 0;
    for (const Ray& r : rays) {
        if (!elevation[r.row] || !offset[r.row]) continue;
        ++total;
        fit += std::abs(r.el - *elevation[r.row]) < kTolerance && std::abs(wrap(r.az - *azimuth[r.col] - *offset[r.row])) < kTolerance;
    }
    if (total < 3 || static_cast<double>(fit) < kInliers * static_cast<double>(total)) return {};
    std::vector<Eigen::Vector3f> out;
    for (std::uint32_t cell : empty) {
        const std::uint32_t r = cell / width, c = cell % width;
        if (!elevation[r] || !offset[r] || !azimuth[c]) continue;
        const double el = *elevation[r], az = *azimuth[c] + *offset[r];
        out.emplace_back(static_cast<float>(std::cos(el) * std::cos(az)), static_cast<float>(std::cos(el) * std::sin(az)), static_cast<float>(std::sin(el)));
    }
    return out;
}

}  // namespace lidarsurf::detail
