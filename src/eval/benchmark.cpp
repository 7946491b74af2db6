#include "lidarsurf/eval/benchmark.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <nlohmann/json.hpp>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/pipeline.hpp"

namespace lidarsurf {

namespace {

BenchmarkMethod method_row(std::string name, const ReconstructionConfig& config) {
    BenchmarkMethod m;
    m.name = std::move(name);
    m.config = config;
    m.config.validate();
    return m;
}

}  // namespace

std::vector<BenchmarkMethod> table_one_methods(const ReconstructionConfig& base) {
    std::vector<BenchmarkMethod> rows;
    rows.push_back(method_row("default", base));
    auto add = [&](const char* label, Mode mode, int level) {
        ReconstructionConfig c = base;
        c.mode = mode;
        c.make_paper_literal();
        const bool adaptive = c.adaptive();
        (adaptive ? c.k_max : c.k) = level;
        rows.push_back(method_row(std::string(label) + (adaptive ? " kmax=" : " k=") + std::to_string(level), c));
    };
    for (int k : {5, 3}) add("AN+GC", Mode::AdaptiveGaussian, k);
    for (int k : {5, 3}) add("AN", Mode::Adaptive, k);
    for (int k : {5, 3, 1}) add("CN+GC", Mode::ConstantGaussian, k);
    for (int k : {5, 3, 1}) add("CN", Mode::Constant, k);
    BenchmarkMethod imls;
    imls.name = "IMLS";
    imls.imls = true;
    imls.config = base;
    imls.imls_config = ImlsConfig::matching(base, base.threads);
    imls.imls_config.validate();
    rows.push_back(std::move(imls));
    return rows;
}

std::vector<BenchmarkMethod> ablation_methods(const ReconstructionConfig& base) {
    std::vector<BenchmarkMethod> rows;
    ReconstructionConfig c = base;
    c.make_paper_literal();
    rows.push_back(method_row("paper AN+GC", c));
    c.min_planarity = base.min_planarity;
    rows.push_back(method_row("+planarity", c));
    c.seeded_surface = base.seeded_surface;
    c.seed_dilation = base.seed_dilation;
    c.truncation_voxels = std::sqrt(3.0);
    rows.push_back(method_row("+seeded, trunc sqrt3", c));
    c.max_thickness = base.max_thickness;
    rows.push_back(method_row("+thickness", c));
    c.truncation_voxels = base.truncation_voxels;
    rows.push_back(method_row("+trunc 1", c));
    c.snap_to_plane = base.snap_to_plane;
    c.min_component_triangles = base.min_component_triangles;
    rows.push_back(method_row("+snap", c));
    c.slab_from_level = base.slab_from_level;
    c.slab_radial_extension = 0;
    rows.push_back(method_row("+slab", c));
    c.slab_radial_extension = base.slab_radial_extension;
    rows.push_back(method_row("+radial slabs", c));
    c.bridge_reach = base.bridge_reach;
    c.bridge_range = base.bridge_range;
    rows.push_back(method_row("+bridges (default)", c));
    for (int k : {3, 7}) {
        ReconstructionConfig ck = base;
        ck.k_max = k;
        rows.push_back(method_row("default kmax=" + std::to_string(k), ck));
    }
    ReconstructionConfig fine = base;
    fine.voxel_size = base.voxel_size / 2;
    fine.k_max = 2 * base.k_max;
    rows.push_back(method_row("default alpha/2 kmax*2", fine));
    return rows;
}

BenchmarkAccumulator::BenchmarkAccumulator(std::vector<std::string> names) {
    for (auto& n : names) {
        Sum s;
        s.agg.name = std::move(n);
        sums_.push_back(std::move(s));
    }
}

namespace {

void add_directed(DirectedError& sum, const DirectedError& e) {
    sum.count += e.count;
    sum.mean += e.mean;
    sum.max += e.max;
    sum.median += e.median;
    sum.p90 += e.p90;
}

void divide(DirectedError& e, double n) {
    e.mean /= n;
    e.max /= n;
    e.median /= n;
    e.p90 /= n;
}

}  // namespace

void BenchmarkAccumulator::add(std::size_t i, const EvaluationResult& r, double seconds) {
    Sum& s = sums_.at(i);
    MethodAggregate& a = s.agg;
    delta_ = r.delta;
    threshold_ = r.threshold;
    ++a.frames;
    a.seconds += seconds;
    a.vertices += static_cast<double>(r.mesh_vertices);
    a.triangles += static_cast<double>(r.mesh_triangles);
    if (const auto& truth = r.truth) {
        ++a.truth_frames;
        a.truth.samples += truth->samples;
        add_directed(a.truth.error, truth->error);
        add_directed(a.truth.vertex_error, truth->vertex_error);
        add_directed(a.truth.completeness, truth->completeness);
        a.truth.precision += truth->precision;
        a.truth.recall += truth->recall;
        a.truth.fscore += truth->fscore;
    }
    add_directed(a.p_to_gt, r.vertex.p_to_gt);
    add_directed(a.gt_to_p, r.vertex.gt_to_p);
    a.ae_sym += r.vertex.ae_sym;
    a.hd_sym += r.vertex.hd_sym;
    a.share_within_delta += r.vertex.share_within_delta;
    a.accuracy += r.surface.accuracy;
    a.completeness += r.surface.completeness;
    a.chamfer_l1 += r.surface.chamfer_l1;
    a.precision += r.surface.precision;
    a.recall += r.surface.recall;
    a.fscore += r.surface.fscore;
    if (a.curve_share.empty()) {
        a.curve_delta = r.vertex.curve_delta;
        a.curve_share.assign(r.vertex.curve_share.size(), 0.0);
    }
    for (std::size_t j = 0; j < a.curve_share.size() && j < r.vertex.curve_share.size(); ++j) a.curve_share[j] += r.vertex.curve_share[j];
    for (std::size_t b = 0; b < r.vertex.by_range.size(); ++b) {
        if (b >= s.range_sum.size()) {
            s.range_sum.resize(b + 1, 0.0);
            s.range_count.resize(b + 1, 0);
            a.by_range.resize(b + 1);
        }
        const RangeBin& bin = r.vertex.by_range[b];
        a.by_range[b].lo = bin.lo;
        a.by_range[b].hi = bin.hi;
        s.range_sum[b] += bin.mean * static_cast<double>(bin.count);
        s.range_count[b] += bin.count;
    }
}

void BenchmarkAccumulator::add_empty(std::size_t i) { ++sums_.at(i).agg.empty; }

BenchmarkResult BenchmarkAccumulator::finish(std::string dataset, std::size_t frames) const {
    BenchmarkResult res;
    res.dataset = std::move(dataset);
    res.frames = frames;
    res.delta = delta_;
    res.threshold = threshold_;
    for (const Sum& s : sums_) {
        MethodAggregate a = s.agg;
        const double n = a.frames ? static_cast<double>(a.frames) : 1.0;
        for (double* v : {&a.seconds, &a.vertices, &a.triangles, &a.ae_sym, &a.hd_sym, &a.share_within_delta, &a.accuracy, &a.completeness,
                          &a.chamfer_l1, &a.precision, &a.recall, &a.fscore})
            *v /= n;
        for (DirectedError* e : {&a.p_to_gt, &a.gt_to_p}) divide(*e, n);
        if (a.truth_frames > 0) {
            const double t = static_cast<double>(a.truth_frames);
            for (DirectedError* e : {&a.truth.error, &a.truth.vertex_error, &a.truth.completeness}) divide(*e, t);
            for (double* v : {&a.truth.precision, &a.truth.recall, &a.truth.fscore}) *v /= t;
        }
        for (double& v : a.curve_share) v /= n;
        for (std::size_t b = 0; b < a.by_range.size(); ++b) {
            a.by_range[b].count = s.range_count[b];
            a.by_range[b].mean = s.range_count[b] ? s.range_sum[b] / static_cast<double>(s.range_count[b]) : 0.0;
        }
        res.methods.push_back(std::move(a));
    }
    return res;
}

std::string format_table_one(const BenchmarkResult& r) {
    std::ostringstream o;
    char buf[512];
    std::snprintf(buf, sizeof buf, "%s: %zu frames, averages per frame (metres)\n", r.dataset.c_str(), r.frames);
    o << buf;
    std::snprintf(buf, sizeof buf, "%-14s | %-22s | %-22s | %s\n", "", "Average Error (m)", "Hausdorff Distance (m)", "");
    o << buf;
    std::snprintf(buf, sizeof buf, "%-14s | %6s %6s %6s   | %6s %6s %6s   | %7s %6s %6s %6s %6s %8s %6s\n", "method", "P->GT", "GT->P", "sym",
                  "P->GT", "GT->P", "sym", "<=delta", "acc", "comp", "prec", "F", "time s", "empty");
    o << buf << std::string(130, '-') << "\n";
    for (const auto& m : r.methods) {
        if (m.frames == 0) {
            std::snprintf(buf, sizeof buf, "%-14s | no frame produced a mesh (%zu empty)\n", m.name.c_str(), m.empty);
            o << buf;
            continue;
        }
        std::snprintf(buf, sizeof buf, "%-14s | %6.3f %6.3f %6.3f   | %6.2f %6.2f %6.2f   | %6.1f%% %6.3f %6.3f %5.1f%% %5.1f%% %8.3f %6zu\n",
                      m.name.c_str(), m.p_to_gt.mean, m.gt_to_p.mean, m.ae_sym, m.p_to_gt.max, m.gt_to_p.max, m.hd_sym,
                      100 * m.share_within_delta, m.accuracy, m.completeness, 100 * m.precision, 100 * m.fscore, m.seconds, m.empty);
        o << buf;
    }
    std::snprintf(buf, sizeof buf, "delta = %.2f m; acc/comp: clipped mean distances of mesh samples to GT and of GT to the mesh; "
                  "prec/F at %.2f m\n", r.delta, r.threshold);
    o << buf;
    return o.str();
}

std::string format_true_surface(const BenchmarkResult& r) {
    bool any = false;
    for (const auto& m : r.methods) any = any || m.truth_frames > 0;
    if (!any) return {};
    std::ostringstream o;
    char buf[512];
    std::snprintf(buf, sizeof buf, "%s: against the true scene triangles, averages per frame (metres)\n", r.dataset.c_str());
    o << buf;
    std::snprintf(buf, sizeof buf, "%-22s | %-22s | %-22s | %6s %6s %6s | %8s %9s\n", "", "mesh -> true surface", "GT -> mesh (completeness)",
                  "", "", "", "", "");
    o << buf;
    std::snprintf(buf, sizeof buf, "%-22s | %6s %6s %6s   | %6s %6s %6s   | %6s %6s %6s | %8s %9s\n", "method", "mean", "median", "p90", "mean",
                  "median", "p90", "prec", "recall", "F", "time s", "triangles");
    o << buf << std::string(118, '-') << "\n";
    for (const auto& m : r.methods) {
        if (m.truth_frames == 0) {
            std::snprintf(buf, sizeof buf, "%-22s | no frame with a mesh and a known true surface (%zu empty)\n", m.name.c_str(), m.empty);
            o << buf;
            continue;
        }
        const TrueSurfaceMetrics& t = m.truth;
        std::snprintf(buf, sizeof buf, "%-22s | %6.3f %6.3f %6.3f   | %6.3f %6.3f %6.3f   | %5.1f%% %5.1f%% %5.1f%% | %8.3f %9.0f\n",
                      m.name.c_str(), t.error.mean, t.error.median, t.error.p90, t.completeness.mean, t.completeness.median,
                      t.completeness.p90, 100 * t.precision, 100 * t.recall, 100 * t.fscore, m.seconds, m.triangles);
        o << buf;
    }
    std::snprintf(buf, sizeof buf, "exact point-to-triangle distances; prec/recall/F at %.2f m; empty frames are not averaged\n", r.threshold);
    o << buf;
    return o.str();
}

std::string to_csv(const BenchmarkResult& r) {
    std::ostringstream o;
    o << "method,frames,empty,ae_p_to_gt,ae_gt_to_p,ae_sym,hd_p_to_gt,hd_gt_to_p,hd_sym,median_p_to_gt,p90_p_to_gt,share_within_delta,"
         "accuracy,completeness,chamfer_l1,precision,recall,fscore,vertices,triangles,seconds,truth_frames,true_error_mean,true_error_median,"
         "true_error_p90,true_vertex_error_mean,true_completeness_mean,true_completeness_median,true_precision,true_recall,true_fscore\n";
    char buf[1024];
    for (const auto& m : r.methods) {
        const TrueSurfaceMetrics& t = m.truth;
        std::snprintf(buf, sizeof buf,
                      "\"%s\",%zu,%zu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.1f,%.1f,%.6g,"
                      "%zu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n",
                      m.name.c_str(), m.frames, m.empty, m.p_to_gt.mean, m.gt_to_p.mean, m.ae_sym, m.p_to_gt.max, m.gt_to_p.max, m.hd_sym,
                      m.p_to_gt.median, m.p_to_gt.p90, m.share_within_delta, m.accuracy, m.completeness, m.chamfer_l1, m.precision,
                      m.recall, m.fscore, m.vertices, m.triangles, m.seconds, m.truth_frames, t.error.mean, t.error.median, t.error.p90,
                      t.vertex_error.mean, t.completeness.mean, t.completeness.median, t.precision, t.recall, t.fscore);
        o << buf;
    }
    return o.str();
}

std::string to_json(const BenchmarkResult& r) {
    using nlohmann::json;
    json methods = json::array();
    auto directed = [](const DirectedError& e) { return json{{"mean", e.mean}, {"max", e.max}, {"median", e.median}, {"p90", e.p90}}; };
    for (const auto& m : r.methods) {
        json bins = json::array();
        for (const auto& b : m.by_range)
            bins.push_back({{"lo", b.lo}, {"hi", b.hi}, {"count", b.count}, {"ae", b.count ? json(b.mean) : json(nullptr)}});
        methods.push_back({{"name", m.name},
                           {"frames", m.frames},
                           {"empty", m.empty},
                           {"seconds", m.seconds},
                           {"vertices", m.vertices},
                           {"triangles", m.triangles},
                           {"p_to_gt", directed(m.p_to_gt)},
                           {"gt_to_p", directed(m.gt_to_p)},
                           {"ae_sym", m.ae_sym},
                           {"hd_sym", m.hd_sym},
                           {"share_within_delta", m.share_within_delta},
                           {"accuracy", m.accuracy},
                           {"completeness", m.completeness},
                           {"chamfer_l1", m.chamfer_l1},
                           {"precision", m.precision},
                           {"recall", m.recall},
                           {"fscore", m.fscore},
                           {"curve", {{"delta", m.curve_delta}, {"share", m.curve_share}}},
                           {"by_range", bins},
                           {"truth", m.truth_frames == 0 ? json(nullptr)
                                                         : json{{"frames", m.truth_frames},
                                                                {"samples", m.truth.samples},
                                                                {"error", directed(m.truth.error)},
                                                                {"vertex_error", directed(m.truth.vertex_error)},
                                                                {"completeness", directed(m.truth.completeness)},
                                                                {"precision", m.truth.precision},
                                                                {"recall", m.truth.recall},
                                                                {"fscore", m.truth.fscore}}}});
    }
    json j = {{"dataset", r.dataset}, {"frames", r.frames}, {"delta", r.delta}, {"threshold", r.threshold}, {"methods", methods}};
    return j.dump(2) + "\n";
}

}  // namespace lidarsurf
