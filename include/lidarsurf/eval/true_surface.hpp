#pragma once
// Accuracy against the exact geometry the simulator scanned (docs/evaluation.md, "Protocol 3"):
// every distance on the mesh side is measured to the true scene triangles, not to sampled points,
// so neither the ground truth's own sampling gaps nor its ring pattern enter the error.
//  - error:        mesh surface samples (area-weighted) -> true triangles, exact point-to-triangle;
//  - vertex error: mesh vertices -> true triangles;
//  - completeness: noise-free ground-truth sensor points (which lie on the true surface) -> mesh
//                  surface, exact point-to-triangle;
//  - precision / recall / F-score at EvaluationConfig::threshold from those two directions.
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"

namespace lidarsurf {

/// Evaluates `mesh` against the true surface `truth` (same frame) and the noise-free GT points
/// `gt`, which sample the part of the true surface the sensor could see (completeness). Uses the
/// range crop, threshold, sample spacing, seed and threads of `config`. Throws InvalidInput when
/// the mesh has no triangle or nothing remains after the crop.
TrueSurfaceMetrics evaluate_true_surface(const Mesh& mesh, const MeshDistance& truth, const std::vector<Eigen::Vector3d>& gt,
                                         const EvaluationConfig& config);

/// The metrics from what evaluate() has already computed (same frame as `truth`): the mesh
/// samples and vertices within the range crop, and the distances of the cropped GT points to the
/// mesh surface. Shared by evaluate_true_surface() and evaluate(..., truth).
TrueSurfaceMetrics true_surface_metrics(const std::vector<Eigen::Vector3d>& samples, const std::vector<Eigen::Vector3d>& vertices,
                                        const std::vector<double>& gt_to_mesh, const MeshDistance& truth, double threshold);

}  // namespace lidarsurf
