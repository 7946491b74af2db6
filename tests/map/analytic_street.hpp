#pragma once
// An analytic street for the fused-map tests: flat ground, a wall, a thin pole and boxes (a car
// driving past, cars parked, a walker) seen by a moving sensor through an exact ray caster, so that
// where each surface is (and where a box was and no longer is) is known exactly.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf::test::street {

constexpr double kWallY = 9.0, kPoleX = 12.0, kPoleY = -4.0, kPoleRadius = 0.08;

struct Box {
    Eigen::Vector3d lo, hi;
};
// The car at scan i: 4.5 x 1.8 x 1.5 m, driving along +x at 1.5 m per scan in the lane at y = 3.
inline Box car_at(int i) { return {{-10.0 + 1.5 * i, 2.1, 0.0}, {-5.5 + 1.5 * i, 3.9, 1.5}}; }
inline Eigen::Vector3d sensor_at(int i) { return {0.5 * i, 0.0, 1.7}; }

inline std::optional<double> hit_box(const Eigen::Vector3d& s, const Eigen::Vector3d& u, const Box& b) {
    double t0 = 0, t1 = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (std::fabs(u[a]) < 1e-12) {
            if (s[a] < b.lo[a] || s[a] > b.hi[a]) return std::nullopt;
            continue;
        }
        double ta = (b.lo[a] - s[a]) / u[a], tb = (b.hi[a] - s[a]) / u[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    }
    return t0 <= t1 && t0 > 0 ? std::optional<double>(t0) : std::nullopt;
}

// What a scan says beside its returns: the rays that returned nothing (unit directions), when asked.
// `dark` boxes absorb the rays that hit them first (no return); `dropout` loses that share of the
// returns at random (a fixed pattern of rays per scan, seeded by the scan's number).
struct ScanExtras {
    std::vector<Box> dark;
    double dropout = 0;
    std::vector<Eigen::Vector3f>* no_return = nullptr;
};

// One scan with `boxes` standing in the street: 0.4 degree azimuth, 0.5 degree elevation from -24
// to +2 degrees, returns within 40 m.
inline std::vector<Eigen::Vector3d> scan_with(int i, const std::vector<Box>& boxes, const ScanExtras& extras = {}) {
    const Eigen::Vector3d s = sensor_at(i);
    std::vector<Eigen::Vector3d> points;
    std::uint64_t state = 0x9E3779B97F4A7C15ull * static_cast<std::uint64_t>(i + 1);
    const auto uniform = [&] {  // splitmix64
        std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
    };
    for (double el = -24.0; el <= 2.0; el += 0.5)
        for (double az = 0; az < 360.0; az += 0.4) {
            const double e = el * M_PI / 180, a = az * M_PI / 180;
            const Eigen::Vector3d u(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
            double t = std::numeric_limits<double>::infinity();
            if (u.z() < 0) t = std::min(t, -s.z() / u.z());                  // ground z = 0
            if (u.y() > 0) t = std::min(t, (kWallY - s.y()) / u.y());        // wall y = 9
            // Pole: a vertical cylinder.
            const Eigen::Vector2d d(s.x() - kPoleX, s.y() - kPoleY), v(u.x(), u.y());
            const double qa = v.squaredNorm(), qb = 2 * d.dot(v), qc = d.squaredNorm() - kPoleRadius * kPoleRadius;
            if (const double disc = qb * qb - 4 * qa * qc; qa > 0 && disc >= 0) {
                const double tp = (-qb - std::sqrt(disc)) / (2 * qa);
                if (tp > 0 && s.z() + tp * u.z() < 6.0) t = std::min(t, tp);
            }
            for (const Box& b : boxes)
                if (const auto tb = hit_box(s, u, b)) t = std::min(t, *tb);
            bool absorbed = false;
            for (const Box& b : extras.dark)
                if (const auto tb = hit_box(s, u, b); tb && *tb < t) absorbed = true, t = *tb;
            const bool lost = extras.dropout > 0 && uniform() < extras.dropout;
            if (t <= 40.0 && !absorbed && !lost) points.push_back(s + t * u);
            else if (extras.no_return) extras.no_return->push_back(u.cast<float>());
        }
    return points;
}
// The scan with the driving car, or without it.
inline std::vector<Eigen::Vector3d> scan(int i, bool with_car) {
    return with_car ? scan_with(i, {car_at(i)}) : scan_with(i, {});
}

inline bool in_trail(const Eigen::Vector3d& p, int last) {  // where the car was, away from where it ends
    const Box end = car_at(last);
    return p.y() > 2.3 && p.y() < 3.7 && p.z() > 0.45 && p.z() < 1.45 && p.x() > -10 && p.x() < end.lo.x() - 1.0;
}
inline bool on_static(const Eigen::Vector3d& p) {
    return std::fabs(p.z()) < 0.05 || std::fabs(p.y() - kWallY) < 0.05 ||
           (Eigen::Vector2d(p.x() - kPoleX, p.y() - kPoleY).norm() < kPoleRadius + 0.05);
}

}  // namespace lidarsurf::test::street
