#include "lidarsurf/sim/analytic_scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lidarsurf::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double hit_ground(const GroundRect& g, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    if (std::fabs(d.z()) < 1e-15) return kInf;
    const double t = (g.height - o.z()) / d.z();
    if (t <= 0) return kInf;
    const Eigen::Vector3d p = o + t * d;
    return (std::fabs(p.x() - g.cx) <= g.hx && std::fabs(p.y() - g.cy) <= g.hy) ? t : kInf;
}

double hit_box(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    double t0 = 0, t1 = kInf;  // slab method
    for (int a = 0; a < 3; ++a) {
        if (std::fabs(d[a]) < 1e-15) {
            if (o[a] < b.lo[a] || o[a] > b.hi[a]) return kInf;
            continue;
        }
        double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return kInf;
    }
    return t0 > 0 ? t0 : kInf;  // the sensor is never inside a box
}

double hit_cylinder(const Cylinder& c, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    double best = kInf;
    const double ox = o.x() - c.cx, oy = o.y() - c.cy;
    const double a = d.x() * d.x() + d.y() * d.y();
    if (a > 1e-15) {
        const double b = 2 * (ox * d.x() + oy * d.y()), cc = ox * ox + oy * oy - c.radius * c.radius;
        const double disc = b * b - 4 * a * cc;
        if (disc >= 0) {
            const double t = (-b - std::sqrt(disc)) / (2 * a);
            const double z = o.z() + t * d.z();
            if (t > 0 && z >= c.z0 && z <= c.z1) best = t;
        }
    }
    for (double zc : {c.z0, c.z1}) {  // caps
        if (std::fabs(d.z()) < 1e-15) continue;
        const double t = (zc - o.z()) / d.z();
        if (t <= 0 || t >= best) continue;
        const double x = ox + t * d.x(), y = oy + t * d.y();
        if (x * x + y * y <= c.radius * c.radius) best = t;
    }
    return best;
}

double dist_ground(const GroundRect& g, const Eigen::Vector3d& p) {
    const double dx = std::max(std::fabs(p.x() - g.cx) - g.hx, 0.0), dy = std::max(std::fabs(p.y() - g.cy) - g.hy, 0.0);
    return std::sqrt(dx * dx + dy * dy + (p.z() - g.height) * (p.z() - g.height));
}

double dist_box(const Box& b, const Eigen::Vector3d& p) {
    const Eigen::Vector3d outside = (b.lo - p).cwiseMax(p - b.hi).cwiseMax(0.0);
    if (outside.squaredNorm() > 0) return outside.norm();
    return (p - b.lo).cwiseMin(b.hi - p).minCoeff();  // inside: nearest face
}

double dist_cylinder(const Cylinder& c, const Eigen::Vector3d& p) {
    const double r = std::hypot(p.x() - c.cx, p.y() - c.cy);
    if (r < c.radius && p.z() > c.z0 && p.z() < c.z1) return std::min({c.radius - r, p.z() - c.z0, c.z1 - p.z()});
    const double dr = std::max(r - c.radius, 0.0), dz = std::max({c.z0 - p.z(), p.z() - c.z1, 0.0});
    return std::sqrt(dr * dr + dz * dz);
}

}  // namespace

std::optional<RayReturn> AnalyticScene::first_return(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                                     double max_range) const {
    double best = kInf;
    for (const auto& g : grounds) best = std::min(best, hit_ground(g, o, d));
    for (const auto& b : boxes) best = std::min(best, hit_box(b, o, d));
    for (const auto& c : cylinders) best = std::min(best, hit_cylinder(c, o, d));
    if (best > max_range) return std::nullopt;
    return RayReturn{best};
}

double AnalyticScene::distance(const Eigen::Vector3d& p) const {
    double best = kInf;
    for (const auto& g : grounds) best = std::min(best, dist_ground(g, p));
    for (const auto& b : boxes) best = std::min(best, dist_box(b, p));
    for (const auto& c : cylinders) best = std::min(best, dist_cylinder(c, p));
    return best;
}

AnalyticScene AnalyticScene::demo() {
    AnalyticScene s;
    const double ground = -1.73;  // KITTI: sensor 1.73 m above the road, sensor frame origin
    s.grounds.push_back({ground, 0, 0, 30, 30});
    s.boxes.push_back({{6.0, 2.0, ground}, {10.2, 3.8, ground + 1.5}});       // a car-sized box
    s.boxes.push_back({{-12.0, -15.0, ground}, {-11.0, 12.0, ground + 4.0}});  // a wall
    s.cylinders.push_back({5.0, -4.0, 0.12, ground, ground + 4.0});            // a pole
    s.cylinders.push_back({-6.0, 7.0, 0.4, ground, ground + 3.0});             // a trunk
    return s;
}

}  // namespace lidarsurf::sim
