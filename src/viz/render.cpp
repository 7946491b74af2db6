#include "lidarsurf/viz/render.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/sim/mesh_scene.hpp"

namespace lidarsurf::viz {
namespace {

/// A perceptually ordered ramp (blue - cyan - green - yellow - red) for t in [0, 1].
Eigen::Vector3d ramp(double t) {
    static const Eigen::Vector3d stops[5] = {{0.19, 0.31, 0.72}, {0.16, 0.66, 0.80}, {0.38, 0.76, 0.36}, {0.95, 0.80, 0.25}, {0.85, 0.27, 0.22}};
    t = std::clamp(t, 0.0, 1.0) * 4.0;
    const int i = std::min(3, static_cast<int>(t));
    return stops[i] + (t - i) * (stops[i + 1] - stops[i]);
}

double quantile(std::vector<double> v, double q) {
    const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
}

}  // namespace

Colouring parse_colouring(std::string_view name) {
    if (name == "height") return Colouring::Height;
    if (name == "level") return Colouring::Level;
    if (name == "grey" || name == "gray") return Colouring::Grey;
    if (name == "intensity") return Colouring::Intensity;
    throw InvalidArgument("unknown colouring '" + std::string(name) + "' (height, level, intensity, grey)");
}

void RenderConfig::validate() const {
    if (width < 16 || height < 16 || width > 8192 || height > 8192) throw InvalidArgument("image size must be in [16, 8192] pixels");
    if (!(fov_deg > 1 && fov_deg < 170)) throw InvalidArgument("field of view must be in (1, 170) degrees");
    if ((eye && !eye->allFinite()) || (target && !target->allFinite())) throw InvalidArgument("camera position must be finite");
    // Embree works in single precision: beyond ~1e7 m a ray's origin loses the metre (and far
    // beyond it the ray tracer aborts), so a camera out there is refused.
    constexpr double kMaxCoordinate = 1e7;
    if ((eye && eye->cwiseAbs().maxCoeff() > kMaxCoordinate) || (target && target->cwiseAbs().maxCoeff() > kMaxCoordinate))
        throw InvalidArgument("camera coordinates must be within 1e7 m of the origin");
    if (eye && target && (*eye - *target).norm() < 1e-9) throw InvalidArgument("the camera's eye and target must differ");
}

Image render(const Mesh& mesh, const RenderConfig& config) {
    config.validate();
    if (mesh.triangles.empty()) throw InvalidInput("nothing to render: the mesh has no triangle");
    if (config.colouring == Colouring::Level && mesh.levels.size() != mesh.vertices.size())
        throw InvalidInput("colouring by level needs the per-vertex levels k' (a mesh written by lidarsurf reconstruct)");
    if (config.colouring == Colouring::Intensity && mesh.intensity.size() != mesh.vertices.size())
        throw InvalidInput("colouring by intensity needs the per-vertex intensity (a mesh made from points that had one)");
    const sim::MeshScene scene(mesh);

    // Robust framing: median vertex as the target, the 80th percentile horizontal spread as scale.
    std::vector<double> xs, ys, zs;
    for (const auto& p : mesh.vertices) {
        xs.push_back(p.x());
        ys.push_back(p.y());
        zs.push_back(p.z());
    }
    const Eigen::Vector3d median(quantile(xs, 0.5), quantile(ys, 0.5), quantile(zs, 0.5));
    const Eigen::Vector3d target = config.target.value_or(median);
    std::vector<double> spread;
    for (const auto& p : mesh.vertices) spread.push_back((p - target).head<2>().norm());
    const double r = std::max(1.0, quantile(spread, 0.6));
    const Eigen::Vector3d eye = config.eye.value_or(target + r * Eigen::Vector3d(-0.9, -0.75, 0.75));
    const double z_lo = quantile(zs, 0.02), z_hi = std::max(z_lo + 1e-6, quantile(zs, 0.98));
    // Intensity: a grey ramp over the 2nd-98th percentiles of the vertices' finite values.
    double i_lo = 0, i_hi = 1;
    if (config.colouring == Colouring::Intensity) {
        std::vector<double> values;
        for (float v : mesh.intensity)
            if (std::isfinite(v)) values.push_back(v);
        if (!values.empty()) i_lo = quantile(values, 0.02), i_hi = std::max(i_lo + 1e-6, quantile(values, 0.98));
    }

    const Eigen::Vector3d fwd = (target - eye).normalized();
    Eigen::Vector3d right = fwd.cross(Eigen::Vector3d::UnitZ());
    if (right.norm() < 1e-6) right = Eigen::Vector3d::UnitX();
    right.normalize();
    const Eigen::Vector3d up = right.cross(fwd);
    const double tan_half = std::tan(config.fov_deg * std::numbers::pi / 360.0);
    const Eigen::Vector3d key = Eigen::Vector3d(0.4, 0.3, 1.0).normalized();

    Image img;
    img.width = config.width;
    img.height = config.height;
    img.rgb.resize(static_cast<std::size_t>(img.width) * img.height * 3);
    tbb::parallel_for(0, img.height, [&](int y) {
        for (int x = 0; x < img.width; ++x) {
            const double u = (2.0 * (x + 0.5) / img.width - 1.0) * tan_half;
            const double v = (1.0 - 2.0 * (y + 0.5) / img.height) * tan_half * img.height / img.width;
            const Eigen::Vector3d dir = (fwd + u * right + v * up).normalized();
            Eigen::Vector3d c;
            if (const auto hit = scene.cast(eye, dir, 1e5)) {
                Eigen::Vector3d n = hit->normal;
                if (n.dot(dir) > 0) n = -n;
                const Eigen::Vector3d p = eye + hit->range * dir;
                Eigen::Vector3d albedo(0.75, 0.75, 0.75);
                const auto& tri = mesh.triangles[hit->triangle];
                if (config.colouring == Colouring::Height) albedo = ramp((p.z() - z_lo) / (z_hi - z_lo));
                else if (config.colouring == Colouring::Level)
                    albedo = ramp((std::max({mesh.levels[tri[0]], mesh.levels[tri[1]], mesh.levels[tri[2]]}) - 1) / 4.0);
                else if (config.colouring == Colouring::Intensity) {
                    double sum = 0;
                    int n_finite = 0;
                    for (auto corner : tri)
                        if (std::isfinite(mesh.intensity[corner])) sum += mesh.intensity[corner], ++n_finite;
                    albedo = n_finite ? Eigen::Vector3d::Constant(0.08 + 0.9 * std::clamp((sum / n_finite - i_lo) / (i_hi - i_lo), 0.0, 1.0))
                                      : Eigen::Vector3d(0.55, 0.65, 0.8);  // no return near: pale blue
                }
                const double shade = 0.25 + 0.55 * std::max(0.0, n.dot(key)) + 0.25 * std::max(0.0, -n.dot(dir));
                c = albedo * shade;
            } else {
                c = Eigen::Vector3d(0.93, 0.95, 0.98) * (0.85 + 0.15 * (1.0 - double(y) / img.height));  // sky
            }
            auto* px = &img.rgb[(static_cast<std::size_t>(y) * img.width + x) * 3];
            for (int a = 0; a < 3; ++a) px[a] = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(c[a], 0.0, 1.0)));
        }
    });
    return img;
}

}  // namespace lidarsurf::viz
