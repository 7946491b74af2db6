#include "lidarsurf/sim/mesh_builder.hpp"

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::sim {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

/// Two unit vectors completing `axis` (unit) to a right-handed orthonormal frame.
void frame_of(const Eigen::Vector3d& axis, Eigen::Vector3d& u, Eigen::Vector3d& v) {
    const Eigen::Vector3d helper = std::fabs(axis.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    u = helper.cross(axis).normalized();
    v = axis.cross(u);
}

/// The `segments` points of a circle of `radius` around `axis` (not unit), as offsets.
std::vector<Eigen::Vector3d> circle(const Eigen::Vector3d& axis, double radius, int segments) {
    Eigen::Vector3d u, v;
    frame_of(axis.normalized(), u, v);
    std::vector<Eigen::Vector3d> offsets;
    for (int i = 0; i < segments; ++i) {
        const double t = kTwoPi * i / segments;
        offsets.push_back(radius * (std::cos(t) * u + std::sin(t) * v));
    }
    return offsets;
}

}  // namespace

void MeshBuilder::set_reflectivity(float reflectivity) {
    if (!(reflectivity >= 0 && reflectivity <= 1)) throw InvalidArgument("reflectivity must be in [0, 1]");
    if (!reflective_) mesh_.intensity.assign(mesh_.vertices.size(), kDefaultReflectivity);
    reflective_ = true;
    reflectivity_ = reflectivity;
}

std::uint32_t MeshBuilder::vertex(const Eigen::Vector3d& p) {
    mesh_.vertices.push_back(p);
    if (reflective_) mesh_.intensity.push_back(reflectivity_);
    return static_cast<std::uint32_t>(mesh_.vertices.size() - 1);
}

void MeshBuilder::triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) { mesh_.triangles.push_back({a, b, c}); }

void MeshBuilder::quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    triangle(a, b, c);
    triangle(a, c, d);
}

void MeshBuilder::box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double yaw) {
    if (!(half.array() > 0).all()) throw InvalidArgument("box half extents must be positive");
    const Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    std::uint32_t c[8];
    for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d s((i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0);
        c[i] = vertex(centre + r * s.cwiseProduct(half));
    }
    // Corner i has bit 0 = +x, bit 1 = +y, bit 2 = +z.
    quad(c[0], c[2], c[3], c[1]);  // -z
    quad(c[4], c[5], c[7], c[6]);  // +z
    quad(c[0], c[1], c[5], c[4]);  // -y
    quad(c[2], c[6], c[7], c[3]);  // +y
    quad(c[0], c[4], c[6], c[2]);  // -x
    quad(c[1], c[3], c[7], c[5]);  // +x
}

void MeshBuilder::box_between(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) { box(0.5 * (lo + hi), 0.5 * (hi - lo)); }

void MeshBuilder::cylinder(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, int segments) {
    const Eigen::Vector3d axis = b - a;
    if (!(radius > 0) || axis.norm() <= 0 || segments < 3) throw InvalidArgument("degenerate cylinder");
    const std::uint32_t ca = vertex(a), cb = vertex(b);
    std::vector<std::uint32_t> ra, rb;
    for (const Eigen::Vector3d& off : circle(axis, radius, segments)) {
        ra.push_back(vertex(a + off));
        rb.push_back(vertex(b + off));
    }
    for (int i = 0; i < segments; ++i) {
        const int j = (i + 1) % segments;
        quad(ra[i], ra[j], rb[j], rb[i]);  // side, outward
        triangle(ca, ra[j], ra[i]);        // cap at a faces -axis
        triangle(cb, rb[i], rb[j]);        // cap at b faces +axis
    }
}

void MeshBuilder::cone(const Eigen::Vector3d& base, const Eigen::Vector3d& apex, double radius, int segments) {
    const Eigen::Vector3d axis = apex - base;
    if (!(radius > 0) || axis.norm() <= 0 || segments < 3) throw InvalidArgument("degenerate cone");
    const std::uint32_t cb = vertex(base), tip = vertex(apex);
    std::vector<std::uint32_t> ring;
    for (const Eigen::Vector3d& off : circle(axis, radius, segments)) ring.push_back(vertex(base + off));
    for (int i = 0; i < segments; ++i) {
        const int j = (i + 1) % segments;
        triangle(ring[i], ring[j], tip);
        triangle(cb, ring[j], ring[i]);
    }
}

void MeshBuilder::ellipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& radii, int rings) {
    if (!(radii.array() > 0).all() || rings < 2) throw InvalidArgument("degenerate ellipsoid");
    const int sectors = 2 * rings;
    const std::uint32_t south = vertex(centre - Eigen::Vector3d(0, 0, radii.z()));
    std::vector<std::vector<std::uint32_t>> band;
    for (int r = 1; r < rings; ++r) {
        const double phi = std::numbers::pi * r / rings - std::numbers::pi / 2;  // latitude, south to north
        std::vector<std::uint32_t> ring;
        for (int s = 0; s < sectors; ++s) {
            const double th = kTwoPi * s / sectors;
            ring.push_back(vertex(centre + Eigen::Vector3d(radii.x() * std::cos(phi) * std::cos(th),
                                                           radii.y() * std::cos(phi) * std::sin(th), radii.z() * std::sin(phi))));
        }
        band.push_back(std::move(ring));
    }
    const std::uint32_t north = vertex(centre + Eigen::Vector3d(0, 0, radii.z()));
    for (int s = 0; s < sectors; ++s) {
        const int t = (s + 1) % sectors;
        triangle(south, band.front()[t], band.front()[s]);
        triangle(north, band.back()[s], band.back()[t]);
        for (std::size_t r = 0; r + 1 < band.size(); ++r) quad(band[r][s], band[r][t], band[r + 1][t], band[r + 1][s]);
    }
}

void MeshBuilder::height_field(double x0, double x1, double y0, double y1, double cell,
                               const std::function<double(double, double)>& height) {
    if (!(cell > 0) || !(x1 > x0) || !(y1 > y0)) throw InvalidArgument("degenerate height field");
    const int nx = static_cast<int>(std::ceil((x1 - x0) / cell)), ny = static_cast<int>(std::ceil((y1 - y0) / cell));
    const std::uint32_t first = static_cast<std::uint32_t>(mesh_.vertices.size());
    for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
            const double x = std::min(x0 + i * cell, x1), y = std::min(y0 + j * cell, y1);
            vertex({x, y, height(x, y)});
        }
    auto id = [&](int i, int j) { return first + static_cast<std::uint32_t>(j * (nx + 1) + i); };
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) quad(id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
}

void MeshBuilder::append(const Mesh& other) {
    const auto offset = static_cast<std::uint32_t>(mesh_.vertices.size());
    if (!reflective_ && !other.intensity.empty()) set_reflectivity(reflectivity_);
    mesh_.vertices.insert(mesh_.vertices.end(), other.vertices.begin(), other.vertices.end());
    if (reflective_) {
        if (other.intensity.size() == other.vertices.size()) mesh_.intensity.insert(mesh_.intensity.end(), other.intensity.begin(), other.intensity.end());
        else mesh_.intensity.resize(mesh_.vertices.size(), reflectivity_);
    }
    for (const auto& t : other.triangles) mesh_.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}

}  // namespace lidarsurf::sim
