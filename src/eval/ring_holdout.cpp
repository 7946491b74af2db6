#include "lidarsurf/eval/ring_holdout.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include <tbb/task_arena.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"

namespace lidarsurf {
namespace {

double azimuth_deg(const Eigen::Vector3d& p) { return std::atan2(p.y(), p.x()) * 180.0 / std::numbers::pi; }

// The step from a to b wrapped into (-180, 180] degrees.
double turn(double a, double b) {
    double d = b - a;
    while (d > 180) d -= 360;
    while (d <= -180) d += 360;
    return d;
}

HoldoutDistances summarise(double lo, double hi, const std::vector<double>& d, const std::vector<double>& thresholds) {
    HoldoutDistances h;
    h.lo = lo;
    h.hi = hi;
    h.count = d.size();
    for (double t : thresholds) h.within.push_back(share_at_most(d, t));
    const DirectedError e = summarize(d);
    h.mean = e.mean;
    h.median = e.median;
    h.p90 = e.p90;
    return h;
}

}  // namespace

std::vector<std::uint16_t> rings_from_order(std::span<const Eigen::Vector3d> pts) {
    if (pts.size() < 2) throw InvalidInput("ring split: the scan has fewer than 2 points");
    std::vector<double> azimuth(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) azimuth[i] = azimuth_deg(pts[i]);
    // The direction of rotation: the sign of the summed small turns (KITTI: counter-clockwise).
    double summed = 0;
    std::size_t small = 0;
    for (std::size_t i = 1; i < pts.size(); ++i) {
        const double d = turn(azimuth[i - 1], azimuth[i]);
        if (std::fabs(d) < 10) {
            summed += d;
            ++small;
        }
    }
    if (2 * small < pts.size() - 1 || summed == 0)
        throw InvalidInput("ring split: the points are not stored ring after ring (consecutive points do not sweep the azimuth); "
                           "give the ring field (--ring-field)");
    const double sign = summed > 0 ? 1.0 : -1.0;
    // Azimuth relative to the cut, in [0, 360) along the rotation. The cut is taken just after
    // the scan's last point, which ends the last ring (the lowest beam, which sees the ground
    // all around; the first ring, the highest beam, may see only part of the turn). A ring ends
    // where the sweep crosses the cut (the relative azimuth falls back by more than half a turn),
    // or where the azimuth turns back by more than kTurnBack (a ring that saw only part of the
    // revolution, followed by the next one). A backward crossing (a point jittering just
    // behind the start) takes one crossing back, and a new ring needs more crossings than any
    // point before reached, so such a point stays in the ring being swept.
    constexpr double kTurnBack = 20;  // degrees; KITTI's rings never step back by more than 7
    const double cut = azimuth.back() + sign * 1e-6;
    auto relative = [&](double azimuth_of_point) {
        const double a = std::fmod(sign * (azimuth_of_point - cut), 360.0);
        return a < 0 ? a + 360 : a;
    };
    std::vector<std::uint16_t> rings(pts.size());
    long crossings = 0, most = 0;
    std::size_t ring = 0;
    double prev = relative(azimuth[0]);
    for (std::size_t i = 1; i < pts.size(); ++i) {
        const double a = relative(azimuth[i]);
        bool restart = false;
        if (prev - a > 180) {
            if (++crossings > most) {
                most = crossings;
                restart = true;
            }
        } else if (a - prev > 180) {
            --crossings;
        } else if (a - prev < -kTurnBack) {
            restart = true;
        }
        if (restart && ++ring > kMaxRing)
            throw InvalidInput("ring split: more than " + format_value(kMaxRing + 1) + " rings; the points are not stored ring after ring");
        rings[i] = static_cast<std::uint16_t>(ring);
        prev = a;
    }
    if (ring == 0) throw InvalidInput("ring split: the azimuth never restarts, so the points are not stored ring after ring; give the ring field (--ring-field)");
    return rings;
}

RingSplit split_rings(const PointCloud& cloud, const std::vector<std::uint16_t>& rings) {
    if (rings.size() != cloud.points.size())
        throw InvalidInput("ring split: " + format_value(rings.size()) + " ring numbers for " + format_value(cloud.points.size()) + " points");
    RingSplit split;
    std::vector<char> seen(65536, 0);
    for (std::size_t i = 0; i < rings.size(); ++i) {
        (rings[i] % 2 == 0 ? split.even : split.odd).points.push_back(cloud.points[i]);
        if (!seen[rings[i]]) {
            seen[rings[i]] = 1;
            ++split.rings;
        }
    }
    if (split.even.points.empty() || split.odd.points.empty())
        throw InvalidInput("ring split: the scan has no " + std::string(split.even.points.empty() ? "even" : "odd") + " ring");
    return split;
}

void RingHoldoutConfig::validate() const {
    auto fail = [](const std::string& m) { throw InvalidArgument("ring hold-out: " + m); };
    if (!origin.allFinite()) fail("origin must be finite");
    if (!std::isfinite(max_range) || max_range <= 0) fail("max range must be finite and > 0 (got " + format_value(max_range) + ")");
    if (!std::isfinite(range_bin) || range_bin <= 0) fail("range bin must be finite and > 0 (got " + format_value(range_bin) + ")");
    if (max_range / range_bin > 1000) fail("more than 1000 range bins");
    for (double t : thresholds)
        if (!std::isfinite(t) || t <= 0) fail("thresholds must be finite and > 0 (got " + format_value(t) + ")");
    if (threads < 0 || threads > 1024) fail("threads must be in [0, 1024] (got " + format_value(threads) + ")");
}

RingHoldoutResult measure_ring_holdout(const Mesh& mesh, const std::vector<Eigen::Vector3d>& held_out, const RingHoldoutConfig& config) {
    config.validate();
    if (mesh.triangles.empty()) throw InvalidInput("ring hold-out: the mesh has no triangle");
    std::vector<Eigen::Vector3d> points;
    for (const Eigen::Vector3d& p : held_out)
        if (p.allFinite() && (p - config.origin).norm() <= config.max_range) points.push_back(p);
    if (points.empty())
        throw InvalidInput("ring hold-out: no held-out point lies within " + format_value(config.max_range) + " m of the sensor");
    std::vector<double> d;
    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        const MeshDistance surface(mesh);
        d = distances_to_surface(surface, points);
    });
    RingHoldoutResult res;
    res.held_out = held_out.size();
    res.mesh_triangles = mesh.triangles.size();
    res.thresholds = config.thresholds;
    res.all = summarise(0, config.max_range, d, config.thresholds);
    const auto bins = static_cast<std::size_t>(std::ceil(config.max_range / config.range_bin - 1e-9));
    std::vector<std::vector<double>> by_bin(bins);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double r = (points[i] - config.origin).norm();
        by_bin[std::min(bins - 1, static_cast<std::size_t>(r / config.range_bin))].push_back(d[i]);
    }
    for (std::size_t b = 0; b < bins; ++b)
        res.by_range.push_back(summarise(static_cast<double>(b) * config.range_bin,
                                         std::min(config.max_range, static_cast<double>(b + 1) * config.range_bin), by_bin[b], config.thresholds));
    return res;
}

RingHoldoutResult ring_holdout(const PointCloud& cloud, const std::function<Mesh(const PointCloud&)>& reconstruct,
                               const RingHoldoutConfig& config) {
    config.validate();
    const RingSplit split = split_rings(cloud, cloud.rings.empty() ? rings_from_order(cloud) : cloud.rings);
    RingHoldoutResult res = measure_ring_holdout(reconstruct(split.even), split.odd.points, config);
    res.rings = split.rings;
    res.reconstructed = split.even.points.size();
    return res;
}

}  // namespace lidarsurf
