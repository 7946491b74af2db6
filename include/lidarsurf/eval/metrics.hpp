#pragma once
// Accuracy of a mesh against ground-truth points, under two protocols (docs/evaluation.md):
//  - the paper's (Sec. IV-A/C): nearest-neighbour distances between the mesh vertices P and the
//    ground-truth points GT; Average Error and Hausdorff distance for P->GT, GT->P and sym; the
//    cumulative delta-error curve (Fig. 6b) and the error by range (Fig. 6a);
//  - the surface-sampled one of recent lidar mapping papers (SHINE, VDBFusion, PUMA on Mai City):
//    points sampled on the triangles; accuracy (mesh->GT), completeness (GT->mesh surface),
//    Chamfer-L1, precision / recall / F-score at a threshold, with truncated distances.
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"

namespace lidarsurf {

struct EvaluationConfig {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  ///< sensor position: range crop and range bins
    double max_range = 0;          ///< metres; keep only vertices, samples and GT within it (0 = all)
    double delta = 0.2;            ///< reported share of vertices with P->GT error <= delta (Fig. 6b)
    double curve_max = 1.0;        ///< the cumulative curve spans [0, curve_max] ...
    double curve_step = 0.01;      ///< ... in steps of this (metres)
    double range_bin = 5.0;        ///< width of the range bins of Fig. 6a (metres)
    double threshold = 0.1;        ///< precision / recall / F-score threshold (metres)
    double truncation_accuracy = 0.2;     ///< mesh->GT distances are clipped to this (metres)
    double truncation_completeness = 2.0; ///< GT->mesh distances are clipped to this (metres)
    double sample_spacing = 0.05;  ///< mesh samples: one per sample_spacing^2 of area ...
    std::size_t max_samples = 2'000'000;  ///< ... at most this many
    bool crop_to_gt_box = true;    ///< drop mesh samples outside the GT bounding box (+ threshold)
    std::uint64_t seed = 1;        ///< sampling seed
    int threads = 0;               ///< 0 = all cores

    /// Throws InvalidArgument naming the first bad field.
    void validate() const;
};

/// Error statistics of one direction, from nearest-neighbour distances.
struct DirectedError {
    std::size_t count = 0;
    double mean = 0;       ///< Average Error (AE)
    double max = 0;        ///< Hausdorff distance of that direction (HD)
    double median = 0, p90 = 0;
};

struct RangeBin {
    double lo = 0, hi = 0;  ///< metres from EvaluationConfig::origin
    std::size_t count = 0;
    double mean = 0;        ///< AE P->GT of the vertices in the bin
};

/// The paper's protocol on mesh vertices.
struct VertexMetrics {
    DirectedError p_to_gt, gt_to_p;
    double ae_sym = 0, hd_sym = 0;   ///< means of the two directions
    double share_within_delta = 0;   ///< fraction of vertices with P->GT error <= delta
    std::vector<double> curve_delta, curve_share;  ///< cumulative delta-error curve (Fig. 6b)
    std::vector<RangeBin> by_range;                ///< AE P->GT by range (Fig. 6a); empty bins kept
};

/// The surface-sampled protocol.
struct SurfaceMetrics {
    std::size_t samples = 0;       ///< points sampled on the mesh (after the crops)
    double accuracy = 0;           ///< mean clipped distance mesh samples -> GT points
    double completeness = 0;       ///< mean clipped distance GT points -> mesh surface (exact)
    double chamfer_l1 = 0;         ///< (accuracy + completeness) / 2
    double precision = 0, recall = 0, fscore = 0;  ///< at EvaluationConfig::threshold
    DirectedError gt_to_surface;   ///< unclipped GT -> surface distances
};

struct TrueSurfaceMetrics {
    std::size_t samples = 0;      ///< mesh surface samples within the range crop
    DirectedError error;          ///< samples -> true surface (unclipped)
    DirectedError vertex_error;   ///< vertices -> true surface (unclipped)
    DirectedError completeness;   ///< GT points -> mesh surface (unclipped)
    double precision = 0;         ///< share of samples within the threshold of the true surface
    double recall = 0;            ///< share of GT points within the threshold of the mesh
    double fscore = 0;            ///< 2 P R / (P + R)
};

struct EvaluationResult {
    std::size_t mesh_vertices = 0, mesh_triangles = 0, gt_points = 0;  ///< after the range crop
    double threshold = 0, delta = 0;
    VertexMetrics vertex;
    SurfaceMetrics surface;
    std::optional<TrueSurfaceMetrics> truth;  ///< when evaluate() was given the true surface
};

/// Error statistics of a set of distances (mean, max, median, p90). Empty input gives zeros.
DirectedError summarize(std::vector<double> distances);

/// Share of the distances that are <= t (0 for none).
double share_at_most(const std::vector<double>& distances, double t);

/// Exact distance of every point to the surface (in parallel, in the caller's TBB arena).
std::vector<double> distances_to_surface(const MeshDistance& surface, const std::vector<Eigen::Vector3d>& points);

/// Points sampled uniformly on the triangles (area-weighted), `spacing` apart on average, at most
/// `max_samples`; deterministic for a seed. Every triangle of positive area has at least one sample
/// point only if the budget allows; zero-area triangles get none.
std::vector<Eigen::Vector3d> sample_surface(const Mesh& mesh, double spacing, std::size_t max_samples, std::uint64_t seed);

/// Evaluates `mesh` against `gt`. Throws InvalidInput when the mesh has no vertex or no triangle,
/// or when nothing of the mesh or of the GT remains after the range crop; non-finite GT points are
/// rejected (InvalidInput).
EvaluationResult evaluate(const Mesh& mesh, const std::vector<Eigen::Vector3d>& gt, const EvaluationConfig& config);
/// The same, plus the true-surface metrics against `truth` (same frame; eval/true_surface.hpp),
/// from the same mesh samples and GT-to-mesh distances.
EvaluationResult evaluate(const Mesh& mesh, const std::vector<Eigen::Vector3d>& gt, const EvaluationConfig& config,
                          const MeshDistance& truth);

}  // namespace lidarsurf
