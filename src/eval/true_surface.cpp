#include "lidarsurf/eval/true_surface.hpp"

#include <tbb/task_arena.h>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

TrueSurfaceMetrics evaluate_true_surface(const Mesh& mesh, const MeshDistance& truth, const std::vector<Eigen::Vector3d>& gt_in,
                                         const EvaluationConfig& config) {
    config.validate();
    mesh.check();
    if (mesh.vertices.empty() || mesh.triangles.empty()) throw InvalidInput("the mesh to evaluate has no triangle");
    const bool crop = config.max_range > 0;
    auto in_range = [&](const Eigen::Vector3d& p) { return !crop || (p - config.origin).norm() <= config.max_range; };
    auto cropped = [&](std::vector<Eigen::Vector3d> v) {
        std::erase_if(v, [&](const Eigen::Vector3d& p) { return !p.allFinite() || !in_range(p); });
        return v;
    };
    const std::vector<Eigen::Vector3d> vertices = cropped(mesh.vertices);
    const std::vector<Eigen::Vector3d> samples = cropped(sample_surface(mesh, config.sample_spacing, config.max_samples, config.seed));
    const std::vector<Eigen::Vector3d> gt = cropped(gt_in);
    if (vertices.empty() || samples.empty()) throw InvalidInput("no part of the mesh lies within the evaluation range");
    if (gt.empty()) throw InvalidInput("no ground-truth point lies within the evaluation range");

    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    return arena.execute([&] { return true_surface_metrics(samples, vertices, distances_to_surface(MeshDistance(mesh), gt), truth, config.threshold); });
}

TrueSurfaceMetrics true_surface_metrics(const std::vector<Eigen::Vector3d>& samples, const std::vector<Eigen::Vector3d>& vertices,
                                        const std::vector<double>& gt_to_mesh, const MeshDistance& truth, double threshold) {
    const std::vector<double> d_s = distances_to_surface(truth, samples);
    TrueSurfaceMetrics m;
    m.samples = samples.size();
    m.precision = share_at_most(d_s, threshold);
    m.recall = share_at_most(gt_to_mesh, threshold);
    m.fscore = m.precision + m.recall > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;
    m.error = summarize(d_s);
    m.vertex_error = summarize(distances_to_surface(truth, vertices));
    m.completeness = summarize(gt_to_mesh);
    return m;
}

}  // namespace lidarsurf
