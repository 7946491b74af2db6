#include "lidarsurf/sim/simulator.hpp"

#include <algorithm>
#include <optional>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::sim {
namespace {

/// The first hit over two scenes: the static world and this frame's moving objects.
class UnionScene final : public RayScene {
public:
    UnionScene(const RayScene& a, const RayScene* b) : a_(a), b_(b) {}
    std::optional<RayReturn> first_return(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range) const override {
        auto ha = a_.first_return(o, d, max_range);
        if (!b_) return ha;
        auto hb = b_->first_return(o, d, ha ? ha->range : max_range);
        if (hb && (!ha || hb->range < ha->range)) return hb;
        return ha;
    }

private:
    const RayScene& a_;
    const RayScene* b_;
};

/// A scene seen through surfaces that absorb: a ray whose first hit is on `dark` returns nothing.
class AbsorbingScene final : public RayScene {
public:
    AbsorbingScene(const RayScene& lit, const RayScene* dark) : lit_(lit), dark_(dark) {}
    std::optional<RayReturn> first_return(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range) const override {
        auto hit = lit_.first_return(o, d, max_range);
        if (!dark_) return hit;
        if (auto absorbed = dark_->intersect(o, d, hit ? hit->range : max_range); absorbed && (!hit || *absorbed < hit->range))
            return std::nullopt;
        return hit;
    }

private:
    const RayScene& lit_;
    const RayScene* dark_;
};

std::uint64_t frame_seed(std::uint64_t seed, std::size_t index) {
    std::uint64_t x = seed * 0x9E3779B97F4A7C15ull + index + 1;
    x = (x ^ (x >> 31)) * 0xBF58476D1CE4E5B9ull;
    return x ^ (x >> 29);
}

}  // namespace

void SimulatorConfig::validate() const {
    if (frames < 1 || frames > 100000) throw InvalidArgument("frames must be in [1, 100000]");
    if (gt_beams < 0 || gt_beams > 4096) throw InvalidArgument("ground-truth beams must be in [0, 4096]");
    if (!(sweep_seconds >= 0 && sweep_seconds <= 1)) throw InvalidArgument("sweep seconds must be in [0, 1]");
    sensor.validate();
}

Simulator::Simulator(World world, SimulatorConfig config)
    : world_(std::move(world)), config_(std::move(config)), static_scene_((config_.validate(), world_.static_mesh)) {
    if (!world_.dark_mesh.triangles.empty()) dark_scene_.emplace(world_.dark_mesh);
}

double Simulator::fraction(std::size_t index) const {
    return config_.frames == 1 ? 0.5 : static_cast<double>(index) / static_cast<double>(config_.frames - 1);
}

SensorModel Simulator::ground_truth_sensor() const { return SensorModel::ground_truth_for(config_.sensor, std::max(1, config_.gt_beams)); }

Eigen::Isometry3d Simulator::pose_at_time(double seconds) const {
    const double duration = world_.time_at(1.0);
    return world_.pose_at(duration > 0 ? seconds / duration : 0.0, config_.sensor.mount_height);
}

SimulatedFrame Simulator::frame(std::size_t index) const {
    if (index >= frame_count()) throw InvalidArgument("frame index out of range");
    SimulatedFrame f;
    f.index = index;
    const double s = fraction(index);
    f.time = world_.time_at(s);
    f.pose = world_.pose_at(s, config_.sensor.mount_height);
    f.movers = world_.movers_at(f.time);
    std::optional<MeshScene> movers;
    if (!f.movers.empty()) movers.emplace(f.movers);
    const UnionScene lit(static_scene_, movers ? &*movers : nullptr);
    const AbsorbingScene scene(lit, dark_scene_ ? &*dark_scene_ : nullptr);
    if (config_.sweep_seconds > 0) {
        const std::size_t steps = azimuth_steps(config_.sensor);
        std::vector<Eigen::Isometry3d> poses(steps);
        for (std::size_t a = 0; a < steps; ++a)
            poses[a] = a == 0 ? f.pose : pose_at_time(f.time + config_.sweep_seconds * static_cast<double>(a) / static_cast<double>(steps));
        std::vector<std::uint32_t> step;
        f.scan = simulate_sweep(scene, config_.sensor, poses, frame_seed(config_.seed, index), &step);
        f.times.resize(step.size());
        for (std::size_t i = 0; i < step.size(); ++i) f.times[i] = static_cast<float>(config_.sweep_seconds * step[i] / static_cast<double>(steps));
    } else {
        f.scan = simulate_scan(scene, config_.sensor, f.pose, frame_seed(config_.seed, index));
    }
    if (config_.gt_beams > 0) {  // the ground truth sees the dark surfaces too: they are there
        const UnionScene all(lit, dark_scene_ ? &*dark_scene_ : nullptr);
        f.ground_truth = simulate_scan(all, ground_truth_sensor(), f.pose, 0);
    }
    return f;
}

}  // namespace lidarsurf::sim
