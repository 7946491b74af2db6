#pragma once
// The paper's benchmark (Table I, Fig. 6): every method row run on every frame, the evaluation of
// each frame averaged over the sequence. The frame loop (reading files) is the caller's, and each
// row runs through the pipeline's reconstruct_with(); this module names the rows, and aggregates and
// formats the results.
#include <string>
#include <vector>

#include "lidarsurf/baselines/imls.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/io/point_cloud.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/surface/config.hpp"

namespace lidarsurf {

/// A row of the benchmark: a method (run through the pipeline's reconstruct_with()) and its name.
struct BenchmarkMethod : MethodConfig {
    std::string name;  ///< as in Table I, e.g. "AN+GC kmax=5", "CN k=1", "IMLS"
};

/// The default configuration `base` ("default"), then Table I's rows as the paper wrote them
/// (base with make_paper_literal()): AN+GC and AN with k_max 5 and 3, CN+GC and CN with k 5, 3 and
/// 1; then IMLS (radius alpha * k_max, k = N_min, h = r / 3).
std::vector<BenchmarkMethod> table_one_methods(const ReconstructionConfig& base);

/// From the paper's AN+GC to `base`, one guard added per row (planarity; seeded surface with a
/// sqrt(3) truncation; thickness; base's truncation; snapping), then base with k_max 3 and 7 and
/// base at half the voxel size with twice k_max (docs/benchmarks.md, the ablation).
std::vector<BenchmarkMethod> ablation_methods(const ReconstructionConfig& base);

/// One row's results averaged over the frames it produced a mesh for.
struct MethodAggregate {
    std::string name;
    std::size_t frames = 0;      ///< frames evaluated
    std::size_t empty = 0;       ///< frames where the method produced no triangle (not averaged)
    double seconds = 0;          ///< mean reconstruction time per frame
    double vertices = 0, triangles = 0;
    DirectedError p_to_gt, gt_to_p;  ///< mean over frames of each field (count: total)
    double ae_sym = 0, hd_sym = 0, share_within_delta = 0;
    double accuracy = 0, completeness = 0, chamfer_l1 = 0, precision = 0, recall = 0, fscore = 0;
    std::vector<double> curve_delta, curve_share;  ///< mean share per delta over frames (Fig. 6b)
    std::vector<RangeBin> by_range;                ///< AE P->GT per range bin over all vertices (Fig. 6a)
    /// Against the true scene triangles (when the sequence has them), averaged over truth_frames.
    std::size_t truth_frames = 0;
    TrueSurfaceMetrics truth;   ///< samples: total; every other field: mean over frames
};

struct BenchmarkResult {
    std::string dataset;         ///< what was measured (a directory, a scene name)
    std::size_t frames = 0;      ///< frames in the run
    double delta = 0, threshold = 0;
    std::vector<MethodAggregate> methods;
};

/// Sums per-frame evaluations, then averages.
class BenchmarkAccumulator {
public:
    explicit BenchmarkAccumulator(std::vector<std::string> method_names);
    /// One frame of one method (its true-surface metrics too, when result.truth has them).
    void add(std::size_t method, const EvaluationResult& result, double seconds);
    void add_empty(std::size_t method);
    BenchmarkResult finish(std::string dataset, std::size_t frames) const;

private:
    struct Sum {
        MethodAggregate agg;
        std::vector<double> range_sum;
        std::vector<std::size_t> range_count;
    };
    std::vector<Sum> sums_;
    double delta_ = 0, threshold_ = 0;
};

/// Table I's layout (AE and HD: P->GT, GT->P, sym) followed by the surface metrics and times.
std::string format_table_one(const BenchmarkResult& result);
/// The true-surface table (error, completeness, precision / recall / F-score, time); empty when
/// no method has a frame with a known true surface.
std::string format_true_surface(const BenchmarkResult& result);
/// One line per method, every averaged scalar.
std::string to_csv(const BenchmarkResult& result);
/// Everything, including the curves and the range bins (input of the plotting script).
std::string to_json(const BenchmarkResult& result);

}  // namespace lidarsurf
