#include "lidarsurf/sim/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"
#include "splitmix.hpp"

namespace lidarsurf::sim {
namespace {

std::vector<double> even_beams(int beams, double top_deg, double bottom_deg) {
    std::vector<double> e;
    for (int i = 0; i < beams; ++i) e.push_back(beams == 1 ? top_deg : top_deg + (bottom_deg - top_deg) * i / (beams - 1));
    return e;
}

// Counter-based draws, so ray i gets the same noise on any thread.
using detail::splitmix64;
using detail::unit_interval;

}  // namespace

void SensorModel::validate() const {
    if (elevations_deg.empty()) throw InvalidArgument("sensor '" + name + "': no beam");
    if (elevations_deg.size() > 4096) throw InvalidArgument("sensor '" + name + "': more than 4096 beams");
    for (double e : elevations_deg)
        if (!std::isfinite(e) || e < -90 || e > 90) throw InvalidArgument("sensor '" + name + "': beam elevation outside [-90, 90] deg");
    if (!(azimuth_step_deg >= 0.001 && azimuth_step_deg <= 360))
        throw InvalidArgument("sensor '" + name + "': azimuth step must be in [0.001, 360] deg");
    if (!(min_range >= 0 && max_range > min_range && std::isfinite(max_range)))
        throw InvalidArgument("sensor '" + name + "': ranges must satisfy 0 <= min_range < max_range");
    if (!(range_noise >= 0 && range_noise < 10)) throw InvalidArgument("sensor '" + name + "': range noise must be in [0, 10) m");
    if (!(intensity_noise >= 0 && intensity_noise <= 1)) throw InvalidArgument("sensor '" + name + "': intensity noise must be in [0, 1]");
    if (!(dropout >= 0 && dropout < 1)) throw InvalidArgument("sensor '" + name + "': dropout must be in [0, 1)");
    if (!(std::fabs(mount_height) < 100)) throw InvalidArgument("sensor '" + name + "': mount height must be finite, |h| < 100 m");
}

std::size_t SensorModel::rays_per_revolution() const {
    return static_cast<std::size_t>(std::lround(360.0 / azimuth_step_deg)) * elevations_deg.size();
}

SensorModel SensorModel::hdl64() {
    SensorModel s;
    s.name = "hdl64";
    s.elevations_deg = even_beams(64, 2.0, -24.8);
    s.dropout = 0.02;
    return s;
}

SensorModel SensorModel::vlp16() {
    SensorModel s;
    s.name = "vlp16";
    s.elevations_deg = even_beams(16, 15.0, -15.0);
    s.azimuth_step_deg = 0.2;
    s.max_range = 100.0;
    s.range_noise = 0.03;
    s.dropout = 0.02;
    return s;
}

SensorModel SensorModel::hdl32() {
    SensorModel s;
    s.name = "hdl32";
    s.elevations_deg = even_beams(32, 10.67, -30.67);
    s.azimuth_step_deg = 0.16;
    s.max_range = 100.0;
    s.dropout = 0.02;
    return s;
}

SensorModel SensorModel::os1_128() {
    SensorModel s;
    s.name = "os1-128";
    s.elevations_deg = even_beams(128, 22.5, -22.5);
    s.azimuth_step_deg = 360.0 / 2048.0;
    s.min_range = 0.3;
    s.range_noise = 0.03;
    s.dropout = 0.02;
    return s;
}

SensorModel SensorModel::ground_truth() { return ground_truth_for(hdl64(), 316); }

SensorModel SensorModel::ground_truth_for(const SensorModel& sensor, int beams) {
    if (beams < 1 || beams > 4096) throw InvalidArgument("ground-truth beams must be in [1, 4096]");
    sensor.validate();
    double top = sensor.elevations_deg.front(), bottom = top;
    for (double e : sensor.elevations_deg) {
        top = std::max(top, e);
        bottom = std::min(bottom, e);
    }
    SensorModel s = sensor;
    s.name = sensor.name + "-gt" + format_value(beams);
    s.elevations_deg = even_beams(beams, top, bottom);
    s.azimuth_step_deg = std::min(0.09, sensor.azimuth_step_deg / 2);
    s.range_noise = 0.0;
    s.intensity_noise = 0.0;
    s.dropout = 0.0;
    return s;
}

std::vector<std::string> SensorModel::preset_names() { return {"hdl64", "vlp16", "hdl32", "os1-128", "gt316"}; }

SensorModel SensorModel::preset(std::string_view name) {
    if (name == "hdl64") return hdl64();
    if (name == "vlp16") return vlp16();
    if (name == "hdl32") return hdl32();
    if (name == "os1-128" || name == "os1_128") return os1_128();
    if (name == "gt316") return ground_truth();
    std::string list;
    for (const auto& n : preset_names()) list += (list.empty() ? "" : ", ") + n;
    throw InvalidArgument("unknown sensor '" + std::string(name) + "' (presets: " + list + ", or a .json file)");
}

SensorModel SensorModel::from_json(std::string_view text) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw FormatError(std::string("sensor JSON: ") + e.what());
    }
    if (!j.is_object()) throw FormatError("sensor JSON: expected an object");
    SensorModel s;
    s.elevations_deg.clear();
    try {
        for (const auto& [key, value] : j.items()) {
            if (key == "name") s.name = value.get<std::string>();
            else if (key == "elevations_deg") s.elevations_deg = value.get<std::vector<double>>();
            else if (key == "azimuth_step_deg") s.azimuth_step_deg = value.get<double>();
            else if (key == "min_range") s.min_range = value.get<double>();
            else if (key == "max_range") s.max_range = value.get<double>();
            else if (key == "range_noise") s.range_noise = value.get<double>();
            else if (key == "intensity_noise") s.intensity_noise = value.get<double>();
            else if (key == "dropout") s.dropout = value.get<double>();
            else if (key == "mount_height") s.mount_height = value.get<double>();
            else if (key != "beams" && key != "elevation_max_deg" && key != "elevation_min_deg")
                throw FormatError("sensor JSON: unknown field '" + key + "'");
        }
        if (j.contains("beams")) {
            if (!s.elevations_deg.empty()) throw FormatError("sensor JSON: give either elevations_deg or beams, not both");
            if (!j.contains("elevation_max_deg") || !j.contains("elevation_min_deg"))
                throw FormatError("sensor JSON: beams needs elevation_max_deg and elevation_min_deg");
            // Read as a double: get<int> on 1e20 would be an out-of-range conversion (found by
            // fuzz_sensor_json), and 8.7 beams is not a sensor.
            const double beams = j.at("beams").get<double>();
            if (!(beams >= 1 && beams <= 4096) || beams != std::floor(beams))
                throw InvalidArgument("sensor JSON: beams must be a whole number in [1, 4096]");
            s.elevations_deg = even_beams(static_cast<int>(beams), j.at("elevation_max_deg").get<double>(), j.at("elevation_min_deg").get<double>());
        }
    } catch (const nlohmann::json::exception& e) {
        throw FormatError(std::string("sensor JSON: ") + e.what());
    }
    s.validate();
    return s;
}

std::string SensorModel::to_json() const {
    nlohmann::json j = {{"name", name},
                        {"elevations_deg", elevations_deg},
                        {"azimuth_step_deg", azimuth_step_deg},
                        {"min_range", min_range},
                        {"max_range", max_range},
                        {"range_noise", range_noise},
                        {"intensity_noise", intensity_noise},
                        {"dropout", dropout},
                        {"mount_height", mount_height}};
    return j.dump(2) + "\n";
}

std::size_t azimuth_steps(const SensorModel& sensor) { return static_cast<std::size_t>(std::lround(360.0 / sensor.azimuth_step_deg)); }

PointCloud simulate_scan(const RayScene& scene, const SensorModel& sensor, const Eigen::Isometry3d& pose, std::uint64_t seed) {
    return simulate_sweep(scene, sensor, {pose}, seed);
}

PointCloud simulate_sweep(const RayScene& scene, const SensorModel& sensor, const std::vector<Eigen::Isometry3d>& step_poses,
                          std::uint64_t seed, std::vector<std::uint32_t>* point_steps) {
    sensor.validate();
    const std::size_t steps = azimuth_steps(sensor);
    if (step_poses.size() != 1 && step_poses.size() != steps)
        throw InvalidArgument("a sweep needs one pose, or one per azimuth step (" + std::to_string(steps) + ")");
    const std::size_t beams = sensor.elevations_deg.size();
    const double deg = std::numbers::pi / 180.0;
    std::vector<Eigen::Vector3d> hits(steps * beams);
    std::vector<float> reflect(steps * beams, 0.0f);
    std::vector<std::uint8_t> valid(steps * beams, 0);
    const std::uint64_t key = splitmix64(seed);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, steps, 16), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t a = r.begin(); a != r.end(); ++a) {
            const Eigen::Isometry3d& pose = step_poses[step_poses.size() == 1 ? 0 : a];
            const Eigen::Matrix3d rot = pose.linear();
            const Eigen::Vector3d origin = pose.translation();
            const double az = static_cast<double>(a) * sensor.azimuth_step_deg * deg;
            for (std::size_t b = 0; b < beams; ++b) {
                const std::size_t ray = a * beams + b;
                const double el = sensor.elevations_deg[b] * deg;
                const Eigen::Vector3d local(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
                const auto hit = scene.first_return(origin, rot * local, sensor.max_range);
                if (!hit || hit->range < sensor.min_range) continue;
                const std::uint64_t r0 = splitmix64(key ^ (2 * ray)), r1 = splitmix64(key ^ (2 * ray + 1));
                if (sensor.dropout > 0 && unit_interval(splitmix64(r0 ^ r1)) < sensor.dropout) continue;
                double noisy = hit->range;
                const double u1 = 1.0 - unit_interval(r0), u2 = unit_interval(r1);
                const double radius = std::sqrt(-2.0 * std::log(u1));  // Box-Muller: two independent unit normals
                if (sensor.range_noise > 0) noisy += sensor.range_noise * radius * std::cos(2 * std::numbers::pi * u2);
                double reflectivity = hit->reflectivity;
                if (std::isfinite(reflectivity))
                    reflectivity = std::clamp(reflectivity + sensor.intensity_noise * radius * std::sin(2 * std::numbers::pi * u2), 0.0, 1.0);
                hits[ray] = noisy * local;
                reflect[ray] = static_cast<float>(reflectivity);
                valid[ray] = 1;
            }
        }
    });
    PointCloud cloud;
    if (point_steps) point_steps->clear();
    bool known = true;  // the scene's reflectivity at every hit
    for (std::size_t i = 0; i < hits.size(); ++i) {
        if (!valid[i]) continue;
        cloud.points.push_back(hits[i]);
        cloud.intensities.push_back(reflect[i]);
        known = known && std::isfinite(reflect[i]);
        if (point_steps) point_steps->push_back(static_cast<std::uint32_t>(i / beams));
    }
    if (!known || cloud.points.empty()) cloud.intensities.clear();
    return cloud;
}

PointCloud simulate_scan(const RayScene& scene, const SensorModel& sensor, const Eigen::Vector3d& origin, std::uint64_t seed) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = origin;
    PointCloud cloud = simulate_scan(scene, sensor, pose, seed);
    for (auto& p : cloud.points) p += origin;
    return cloud;
}

std::optional<BeamPattern> drive_pattern(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return std::nullopt;
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path.string() + ": cannot read");
    std::ostringstream text;
    text << in.rdbuf();
    return SensorModel::from_json(text.str()).pattern();
}

}  // namespace lidarsurf::sim
