#include "lidarsurf/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <string>

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/kd_tree.hpp"
#include "lidarsurf/eval/true_surface.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"
#include "lidarsurf/core/format_value.hpp"

namespace lidarsurf {
namespace {

double quantile_sorted(const std::vector<double>& v, double q) {
    if (v.empty()) return 0;
    const double pos = q * static_cast<double>(v.size() - 1);
    const auto i = static_cast<std::size_t>(pos);
    const double t = pos - static_cast<double>(i);
    return i + 1 < v.size() ? v[i] * (1 - t) + v[i + 1] * t : v[i];
}

// Nearest-neighbour distance of every query to `tree`, in parallel.
std::vector<double> nearest_distances(const std::vector<Eigen::Vector3d>& queries, const KdTree& tree) {
    std::vector<double> d(queries.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) d[i] = std::sqrt(tree.nearest(queries[i]).squared_distance);
    });
    return d;
}

double clipped_mean(const std::vector<double>& d, double clip) {
    if (d.empty()) return 0;
    double s = 0;
    for (double x : d) s += std::min(x, clip);
    return s / static_cast<double>(d.size());
}

// Uniform double in [0, 1) from a 64-bit engine (portable, unlike std::uniform_real_distribution).
double unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

}  // namespace

void EvaluationConfig::validate() const {
    auto fail = [](const std::string& m) { throw InvalidArgument("evaluate: " + m); };
    auto positive = [&](double v, const char* name) {
        if (!std::isfinite(v) || v <= 0) fail(std::string(name) + " must be finite and > 0 (got " + format_value(v) + ")");
    };
    if (!origin.allFinite()) fail("origin must be finite");
    if (!std::isfinite(max_range) || max_range < 0) fail("max range must be finite and >= 0 (got " + format_value(max_range) + ")");
    positive(delta, "delta");
    positive(curve_max, "curve max");
    positive(curve_step, "curve step");
    if (curve_max / curve_step > 1e5) fail("the cumulative curve would have more than 1e5 points");
    positive(range_bin, "range bin");
    positive(threshold, "threshold");
    positive(truncation_accuracy, "accuracy truncation");
    positive(truncation_completeness, "completeness truncation");
    positive(sample_spacing, "sample spacing");
    if (max_samples == 0 || max_samples > 100'000'000) fail("max samples must be in [1, 1e8]");
    if (threads < 0 || threads > 1024) fail("threads must be in [0, 1024] (got " + format_value(threads) + ")");
}

double share_at_most(const std::vector<double>& d, double t) {
    if (d.empty()) return 0;
    return static_cast<double>(std::count_if(d.begin(), d.end(), [t](double x) { return x <= t; })) / static_cast<double>(d.size());
}

std::vector<double> distances_to_surface(const MeshDistance& surface, const std::vector<Eigen::Vector3d>& points) {
    std::vector<double> d(points.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 512), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) d[i] = surface.distance(points[i]);
    });
    return d;
}

DirectedError summarize(std::vector<double> d) {
    DirectedError e;
    e.count = d.size();
    if (d.empty()) return e;
    std::sort(d.begin(), d.end());
    e.mean = std::accumulate(d.begin(), d.end(), 0.0) / static_cast<double>(d.size());
    e.max = d.back();
    e.median = quantile_sorted(d, 0.5);
    e.p90 = quantile_sorted(d, 0.9);
    return e;
}

std::vector<Eigen::Vector3d> sample_surface(const Mesh& mesh, double spacing, std::size_t max_samples, std::uint64_t seed) {
    std::vector<double> cumulative(mesh.triangles.size());
    double total = 0;
    for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
        total += mesh.triangle_area(i);
        cumulative[i] = total;
    }
    std::vector<Eigen::Vector3d> out;
    if (!(total > 0)) return out;
    const double wanted = std::ceil(total / (spacing * spacing));
    const std::size_t n = wanted >= static_cast<double>(max_samples) ? max_samples : static_cast<std::size_t>(wanted);
    out.reserve(n);
    std::mt19937_64 rng(seed);
    for (std::size_t s = 0; s < n; ++s) {
        const double u = unit(rng) * total;
        std::size_t i = static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin());
        i = std::min(i, cumulative.size() - 1);
        const auto& t = mesh.triangles[i];
        // Uniform barycentric sample (Osada et al. 2002).
        const double r1 = std::sqrt(unit(rng)), r2 = unit(rng);
        out.push_back((1 - r1) * mesh.vertices[t[0]] + r1 * (1 - r2) * mesh.vertices[t[1]] + r1 * r2 * mesh.vertices[t[2]]);
    }
    return out;
}

namespace {

EvaluationResult evaluate_impl(const Mesh& mesh, const std::vector<Eigen::Vector3d>& gt_in, const EvaluationConfig& config,
                               const MeshDistance* truth) {
    config.validate();
    mesh.check();
    if (mesh.vertices.empty() || mesh.triangles.empty()) throw InvalidInput("the mesh to evaluate has no triangle");
    for (const auto& p : gt_in)
        if (!p.allFinite()) throw InvalidInput("the ground truth has a non-finite point");
    for (const auto& p : mesh.vertices)
        if (!p.allFinite()) throw InvalidInput("the mesh has a non-finite vertex");

    const bool crop = config.max_range > 0;
    auto in_range = [&](const Eigen::Vector3d& p) { return !crop || (p - config.origin).norm() <= config.max_range; };
    std::vector<Eigen::Vector3d> cropped_vertices, cropped_gt;
    for (const auto& p : mesh.vertices)
        if (in_range(p)) cropped_vertices.push_back(p);
    for (const auto& p : gt_in)
        if (in_range(p)) cropped_gt.push_back(p);
    if (cropped_vertices.empty()) throw InvalidInput("no mesh vertex lies within the evaluation range");
    if (cropped_gt.empty()) throw InvalidInput("no ground-truth point lies within the evaluation range");
    // The trees own the cropped sets (no second copy); the metrics read them back from the trees.
    const KdTree gt_tree(std::move(cropped_gt));
    const KdTree vertex_tree(std::move(cropped_vertices));
    const std::vector<Eigen::Vector3d>& gt = gt_tree.points();
    const std::vector<Eigen::Vector3d>& vertices = vertex_tree.points();

    EvaluationResult res;
    res.mesh_vertices = vertices.size();
    res.gt_points = gt.size();
    res.threshold = config.threshold;
    res.delta = config.delta;

    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        // The paper's protocol on vertices.
        const std::vector<double> d_p = nearest_distances(vertices, gt_tree);
        const std::vector<double> d_g = nearest_distances(gt, vertex_tree);
        VertexMetrics& vm = res.vertex;
        vm.p_to_gt = summarize(d_p);
        vm.gt_to_p = summarize(d_g);
        vm.ae_sym = 0.5 * (vm.p_to_gt.mean + vm.gt_to_p.mean);
        vm.hd_sym = 0.5 * (vm.p_to_gt.max + vm.gt_to_p.max);
        vm.share_within_delta = share_at_most(d_p, config.delta);
        {
            std::vector<double> sorted = d_p;
            std::sort(sorted.begin(), sorted.end());
            const auto steps = static_cast<std::size_t>(std::floor(config.curve_max / config.curve_step + 1e-9));
            for (std::size_t s = 0; s <= steps; ++s) {
                const double t = static_cast<double>(s) * config.curve_step;
                const auto below = std::upper_bound(sorted.begin(), sorted.end(), t) - sorted.begin();
                vm.curve_delta.push_back(t);
                vm.curve_share.push_back(static_cast<double>(below) / static_cast<double>(sorted.size()));
            }
        }
        {
            std::vector<double> sum;
            std::vector<std::size_t> count;
            for (std::size_t i = 0; i < vertices.size(); ++i) {
                const auto b = static_cast<std::size_t>((vertices[i] - config.origin).norm() / config.range_bin);
                if (b >= sum.size()) {
                    sum.resize(b + 1, 0.0);
                    count.resize(b + 1, 0);
                }
                sum[b] += d_p[i];
                ++count[b];
            }
            for (std::size_t b = 0; b < sum.size(); ++b)
                vm.by_range.push_back({static_cast<double>(b) * config.range_bin, static_cast<double>(b + 1) * config.range_bin,
                                       count[b], count[b] ? sum[b] / static_cast<double>(count[b]) : 0.0});
        }

        // The surface-sampled protocol.
        std::vector<Eigen::Vector3d> samples = sample_surface(mesh, config.sample_spacing, config.max_samples, config.seed);
        Eigen::Vector3d lo = gt.front(), hi = gt.front();
        for (const auto& p : gt) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
        lo.array() -= config.threshold;
        hi.array() += config.threshold;
        std::erase_if(samples, [&](const Eigen::Vector3d& p) { return !in_range(p); });
        const std::vector<double> d_c = distances_to_surface(MeshDistance(mesh), gt);
        // The true surface sees every sample in range; protocol 2 only those in the GT box.
        if (truth) res.truth = true_surface_metrics(samples, vertices, d_c, *truth, config.threshold);
        if (config.crop_to_gt_box)
            std::erase_if(samples, [&](const Eigen::Vector3d& p) { return (p.array() < lo.array()).any() || (p.array() > hi.array()).any(); });
        SurfaceMetrics& sm = res.surface;
        sm.samples = samples.size();
        const std::vector<double> d_s = nearest_distances(samples, gt_tree);
        sm.accuracy = clipped_mean(d_s, config.truncation_accuracy);
        sm.completeness = clipped_mean(d_c, config.truncation_completeness);
        sm.chamfer_l1 = 0.5 * (sm.accuracy + sm.completeness);
        sm.precision = share_at_most(d_s, config.threshold);
        sm.recall = share_at_most(d_c, config.threshold);
        sm.fscore = sm.precision + sm.recall > 0 ? 2 * sm.precision * sm.recall / (sm.precision + sm.recall) : 0.0;
        sm.gt_to_surface = summarize(d_c);
    });
    std::size_t tri = 0;
    for (const auto& t : mesh.triangles)
        if (in_range(mesh.vertices[t[0]]) || in_range(mesh.vertices[t[1]]) || in_range(mesh.vertices[t[2]])) ++tri;
    res.mesh_triangles = tri;
    return res;
}

}  // namespace

EvaluationResult evaluate(const Mesh& mesh, const std::vector<Eigen::Vector3d>& gt, const EvaluationConfig& config) {
    return evaluate_impl(mesh, gt, config, nullptr);
}

EvaluationResult evaluate(const Mesh& mesh, const std::vector<Eigen::Vector3d>& gt, const EvaluationConfig& config,
                          const MeshDistance& truth) {
    return evaluate_impl(mesh, gt, config, &truth);
}

}  // namespace lidarsurf
