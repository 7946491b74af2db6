#include "lidarsurf/eval/map_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"
#include "lidarsurf/core/voxel_key.hpp"
#include "lidarsurf/eval/metrics.hpp"

namespace lidarsurf {

void MapEvaluationConfig::validate() const {
    auto positive = [](double v, const char* name) {
        if (!std::isfinite(v) || v <= 0) throw InvalidArgument(std::string(name) + " must be finite and > 0 (got " + format_value(v) + ")");
    };
    if (!std::isfinite(max_distance) || max_distance < 0) throw InvalidArgument("max distance must be finite and >= 0 (got " + format_value(max_distance) + ")");
    positive(threshold, "threshold");
    positive(ghost_distance, "ghost distance");
    positive(truncation_accuracy, "accuracy truncation");
    positive(truncation_completeness, "completeness truncation");
    positive(sample_spacing, "sample spacing");
    positive(gt_spacing, "GT spacing");
    if (!std::isfinite(ground_z)) throw InvalidArgument("ground z must be finite");
    if (max_samples == 0) throw InvalidArgument("max samples must be > 0");
    if (!std::is_sorted(height_bands.begin(), height_bands.end())) throw InvalidArgument("height bands must be increasing");
    if (threads < 0) throw InvalidArgument("threads must be >= 0");
}

DriveCrop::DriveCrop(const std::vector<Eigen::Vector3d>& drive, double max_distance) : max_distance_(max_distance) {
    if (drive.empty()) throw InvalidInput("the drive has no position");
    std::vector<Eigen::Vector3d> flat;
    flat.reserve(drive.size());
    for (const Eigen::Vector3d& p : drive) flat.emplace_back(p.x(), p.y(), 0.0);
    tree_ = std::make_unique<KdTree>(std::move(flat));  // throws InvalidInput on a non-finite position
}
DriveCrop::~DriveCrop() = default;
DriveCrop::DriveCrop(DriveCrop&&) noexcept = default;

bool DriveCrop::contains(const Eigen::Vector3d& p) const {
    if (max_distance_ <= 0) return true;
    return tree_->nearest({p.x(), p.y(), 0.0}).squared_distance <= max_distance_ * max_distance_;
}

MapGroundTruth::MapGroundTruth(const MeshDistance& truth, const DriveCrop& crop, double gt_spacing, double on_surface)
    : truth_(truth), crop_(crop), spacing_(gt_spacing), on_surface_(on_surface) {
    if (!std::isfinite(gt_spacing) || gt_spacing <= 0) throw InvalidArgument("GT spacing must be finite and > 0");
}

void MapGroundTruth::add(const std::vector<Eigen::Vector3d>& points) {
    // The cells this scan reaches first (one candidate each), then which candidates lie on the
    // static scene (in parallel); a cell whose candidate was on a moving object stays open.
    std::map<std::uint64_t, Eigen::Vector3d> fresh;
    for (const Eigen::Vector3d& p : points) {
        if (!p.allFinite()) continue;
        const Eigen::Vector3d c = (p / spacing_).array().floor();
        if (!(c.cwiseAbs().maxCoeff() < kMaxLatticeIndex)) continue;
        const std::uint64_t key = pack_key(c.cast<int>());
        if (cells_.count(key) || fresh.count(key)) continue;
        fresh.emplace(key, p);
    }
    std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> candidates(fresh.begin(), fresh.end());
    std::vector<std::uint8_t> keep(candidates.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            keep[i] = crop_.contains(candidates[i].second) && truth_.distance(candidates[i].second) <= on_surface_;
    });
    for (std::size_t i = 0; i < candidates.size(); ++i)
        if (keep[i]) cells_.emplace(candidates[i].first, candidates[i].second);
}

std::vector<Eigen::Vector3d> MapGroundTruth::points() const {
    std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> sorted(cells_.begin(), cells_.end());
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Eigen::Vector3d> out;
    out.reserve(sorted.size());
    for (const auto& [key, p] : sorted) out.push_back(p);
    return out;
}

SweptVolume::SweptVolume(double pad) : pad_(pad) {
    if (!(pad >= 0) || !std::isfinite(pad)) throw InvalidArgument("swept volume: the pad must be finite and >= 0");
}

std::uint64_t SweptVolume::cell_key(long x, long y) const {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x)) << 32) | static_cast<std::uint32_t>(y);
}

void SweptVolume::add(const Mesh& movers) {
    // Connected components by shared vertices (union-find), a box each.
    std::vector<std::uint32_t> parent(movers.vertices.size());
    for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
    const auto root = [&](std::uint32_t v) {
        while (parent[v] != v) v = parent[v] = parent[parent[v]];
        return v;
    };
    for (const auto& t : movers.triangles)
        for (int e = 1; e < 3; ++e) parent[root(t[e])] = root(t[0]);
    std::unordered_map<std::uint32_t, Eigen::AlignedBox3d> parts;
    for (const auto& t : movers.triangles)
        for (int e = 0; e < 3; ++e) parts[root(t[0])].extend(movers.vertices[t[e]]);
    for (auto& [r, box] : parts) {
        if (!box.min().allFinite() || !box.max().allFinite()) continue;
        box.min().array() -= pad_;
        box.max().array() += pad_;
        const auto id = static_cast<std::uint32_t>(boxes_.size());
        boxes_.push_back(box);
        for (long x = static_cast<long>(std::floor(box.min().x() / kCell)); x <= static_cast<long>(std::floor(box.max().x() / kCell)); ++x)
            for (long y = static_cast<long>(std::floor(box.min().y() / kCell)); y <= static_cast<long>(std::floor(box.max().y() / kCell)); ++y)
                cells_[cell_key(x, y)].push_back(id);
    }
}

bool SweptVolume::contains(const Eigen::Vector3d& p) const {
    const auto it = cells_.find(cell_key(static_cast<long>(std::floor(p.x() / kCell)), static_cast<long>(std::floor(p.y() / kCell))));
    if (it == cells_.end()) return false;
    for (const std::uint32_t b : it->second)
        if (boxes_[b].contains(p)) return true;
    return false;
}

MapMetrics evaluate_map(const Mesh& mesh, const MeshDistance& truth, const std::vector<Eigen::Vector3d>& gt_in, const DriveCrop& crop,
                        const MapEvaluationConfig& config, const SweptVolume* swept) {
    config.validate();
    mesh.check();
    if (mesh.triangles.empty()) throw InvalidInput("the map to evaluate has no triangle");
    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    return arena.execute([&] {
        MapMetrics m;
        // Samples: area-weighted, so each stands for the same area of the whole mesh.
        double total_area = 0;
        for (std::size_t i = 0; i < mesh.triangles.size(); ++i) total_area += mesh.triangle_area(i);
        std::vector<Eigen::Vector3d> all = sample_surface(mesh, config.sample_spacing, config.max_samples, config.seed);
        if (all.empty()) throw InvalidInput("the map to evaluate has no area");
        const double area_per_sample = total_area / static_cast<double>(all.size());
        std::vector<std::uint8_t> inside(all.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, all.size(), 4096), [&](const auto& r) {
            for (std::size_t i = r.begin(); i != r.end(); ++i) inside[i] = crop.contains(all[i]);
        });
        std::vector<Eigen::Vector3d> samples;
        for (std::size_t i = 0; i < all.size(); ++i)
            if (inside[i]) samples.push_back(all[i]);
        std::vector<Eigen::Vector3d> gt;
        for (const Eigen::Vector3d& p : gt_in)
            if (p.allFinite() && crop.contains(p)) gt.push_back(p);
        if (samples.empty()) throw InvalidInput("no part of the map lies within the evaluation crop");
        if (gt.empty()) throw InvalidInput("no ground-truth point lies within the evaluation crop");
        m.samples = samples.size();
        m.gt_points = gt.size();
        m.mesh_area = area_per_sample * static_cast<double>(samples.size());

        const std::vector<double> to_truth = distances_to_surface(truth, samples);
        const std::vector<double> to_mesh = distances_to_surface(MeshDistance(mesh), gt);
        double acc = 0, comp = 0;
        std::size_t precise = 0, recalled = 0, ghosts = 0, path_ghosts = 0;
        for (std::size_t i = 0; i < to_truth.size(); ++i) {
            const double d = to_truth[i];
            acc += std::min(d, config.truncation_accuracy);
            precise += d <= config.threshold;
            ghosts += d > config.ghost_distance;
            path_ghosts += d > config.ghost_distance && swept && swept->contains(samples[i]);
        }
        for (double d : to_mesh) {
            comp += std::min(d, config.truncation_completeness);
            recalled += d <= config.threshold;
        }
        m.accuracy = acc / static_cast<double>(to_truth.size());
        m.completeness = comp / static_cast<double>(to_mesh.size());
        m.chamfer_l1 = 0.5 * (m.accuracy + m.completeness);
        m.precision = static_cast<double>(precise) / static_cast<double>(to_truth.size());
        m.recall = static_cast<double>(recalled) / static_cast<double>(to_mesh.size());
        m.fscore = m.precision + m.recall > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;
        m.ghost_area = area_per_sample * static_cast<double>(ghosts);
        m.path_ghost_area = area_per_sample * static_cast<double>(path_ghosts);

        // Boundary edges (one triangle) by the height of their midpoint, within the crop.
        std::vector<std::uint64_t> edges;
        edges.reserve(3 * mesh.triangles.size());
        for (const auto& t : mesh.triangles)
            for (int e = 0; e < 3; ++e) {
                const std::uint32_t a = t[e], b = t[(e + 1) % 3];
                edges.push_back(std::uint64_t{std::min(a, b)} << 32 | std::max(a, b));
            }
        std::sort(edges.begin(), edges.end());
        constexpr double inf = std::numeric_limits<double>::infinity();
        std::vector<double> limits{-inf};
        limits.insert(limits.end(), config.height_bands.begin(), config.height_bands.end());
        limits.push_back(inf);
        for (std::size_t b = 0; b + 1 < limits.size(); ++b) m.boundary_by_height.push_back({limits[b], limits[b + 1], 0, 0});
        for (std::size_t i = 0; i < edges.size();) {
            std::size_t j = i;
            while (j < edges.size() && edges[j] == edges[i]) ++j;
            const Eigen::Vector3d mid = 0.5 * (mesh.vertices[edges[i] >> 32] + mesh.vertices[edges[i] & 0xffffffffu]);
            if (crop.contains(mid)) {
                const double h = mid.z() - config.ground_z;
                const std::size_t band =
                    static_cast<std::size_t>(std::upper_bound(limits.begin() + 1, limits.end() - 1, h) - (limits.begin() + 1));
                ++m.boundary_by_height[band].edges;
                m.boundary_by_height[band].boundary_edges += (j - i) == 1;
            }
            i = j;
        }
        return m;
    });
}

}  // namespace lidarsurf
