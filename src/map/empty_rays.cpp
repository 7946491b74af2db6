#include "lidarsurf/map/empty_rays.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "angles.hpp"
#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

void BeamPattern::validate() const {
    if (elevations_deg.empty()) throw InvalidArgument("beam pattern: no beam");
    for (double e : elevations_deg)
        if (!std::isfinite(e) || std::fabs(e) > 90) throw InvalidArgument("beam pattern: elevations must be finite, in [-90, 90] degrees");
    if (!(azimuth_step_deg > 0 && azimuth_step_deg <= 360)) throw InvalidArgument("beam pattern: the azimuth step must be in (0, 360] degrees");
}

std::vector<Eigen::Vector3f> empty_rays(const BeamPattern& pattern, std::span<const Eigen::Vector3d> points) {
    pattern.validate();
    std::vector<double> beams = pattern.elevations_deg;
    std::sort(beams.begin(), beams.end());
    const auto steps = static_cast<std::size_t>(std::max(1.0, std::round(360.0 / pattern.azimuth_step_deg)));
    const double deg = std::numbers::pi / 180.0;
    std::vector<std::uint8_t> hit(beams.size() * steps, 0);
    for (const Eigen::Vector3d& p : points) {
        if (!p.allFinite() || p.squaredNorm() == 0) continue;
        const double el = detail::elevation_deg(p);  // to 0.001 degree
        auto it = std::lower_bound(beams.begin(), beams.end(), el);  // the nearest beam
        if (it == beams.end() || (it != beams.begin() && el - *(it - 1) < *it - el)) --it;
        double az = detail::azimuth_deg(p);
        if (az < 0) az += 360;
        const auto step = static_cast<std::size_t>(std::llround(az / pattern.azimuth_step_deg)) % steps;
        hit[static_cast<std::size_t>(it - beams.begin()) * steps + step] = 1;
    }
    std::vector<double> cos_az(steps), sin_az(steps);
    for (std::size_t a = 0; a < steps; ++a) {
        const double az = static_cast<double>(a) * pattern.azimuth_step_deg * deg;
        cos_az[a] = std::cos(az), sin_az[a] = std::sin(az);
    }
    std::vector<Eigen::Vector3f> out;
    for (std::size_t b = 0; b < beams.size(); ++b) {
        const double ce = std::cos(beams[b] * deg), se = std::sin(beams[b] * deg);
        for (std::size_t a = 0; a < steps; ++a)
            if (!hit[b * steps + a])
                out.emplace_back(static_cast<float>(ce * cos_az[a]), static_cast<float>(ce * sin_az[a]), static_cast<float>(se));
    }
    return out;
}

std::vector<Eigen::Vector3f> empty_rays(const BeamPattern& pattern, std::span<const Eigen::Vector3d> points, const Eigen::Matrix3d& turn) {
    std::vector<Eigen::Vector3f> rays = empty_rays(pattern, points);
    const Eigen::Matrix3f t = turn.cast<float>();
    for (Eigen::Vector3f& u : rays) u = t * u;
    return rays;
}

}  // namespace lidarsurf
