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

    TrueSurfaceMetrics m;
    tbb::task_arena arena(config.threads > 0 ? config.threads : tbb::task_arena::automatic);
    arena.execute([&] {
        const std::vector<double> d_s = distances_to_surface(truth, samples);
        const std::vector<double> d_v = distances_to_surface(truth, vertices);
        const MeshDistance surface(mesh);
        const std::vector<double> d_c = distances_to_surface(surface, gt);
        m.samples = samples.size();
        m.precision = share_at_most(d_s, config.threshold);
        m.recall = share_at_most(d_c, config.threshold);
        m.fscore = m.precision + m.recall > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;
        m.error = summarize(d_s);
        m.vertex_error = summarize(d_v);
        m.completeness = summarize(d_c);
    });
    return m;
}

}  // namespace lidarsurf
