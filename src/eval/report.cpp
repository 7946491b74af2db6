#include "lidarsurf/eval/report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace lidarsurf {
namespace {

std::string num(double v) {
    if (!std::isfinite(v)) return "null";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

std::string directed_json(const DirectedError& e) {
    return "{\"count\": " + std::to_string(e.count) + ", \"mean\": " + num(e.mean) + ", \"max\": " + num(e.max) +
           ", \"median\": " + num(e.median) + ", \"p90\": " + num(e.p90) + "}";
}

template <typename T, typename F>
std::string array_json(const std::vector<T>& v, F&& item) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i) {
        if (i) s += ", ";
        s += item(v[i]);
    }
    return s + "]";
}

}  // namespace

std::string format_table(const EvaluationResult& r) {
    const VertexMetrics& v = r.vertex;
    const SurfaceMetrics& s = r.surface;
    char buf[2048];
    std::snprintf(buf, sizeof buf,
                  "mesh: %zu vertices, %zu triangles; ground truth: %zu points\n"
                  "paper protocol (mesh vertices P, ground-truth points GT), metres:\n"
                  "            AE        HD    median       p90\n"
                  "  P->GT  %8.4f  %8.4f  %8.4f  %8.4f\n"
                  "  GT->P  %8.4f  %8.4f  %8.4f  %8.4f\n"
                  "  sym    %8.4f  %8.4f\n"
                  "  vertices within %.2f m of GT: %.1f%%\n"
                  "surface protocol (%zu points sampled on the mesh), threshold %.2f m:\n"
                  "  accuracy %.4f m, completeness %.4f m, Chamfer-L1 %.4f m\n"
                  "  precision %.1f%%, recall %.1f%%, F-score %.1f%%\n"
                  "  GT->surface (exact, unclipped): median %.4f m, p90 %.4f m, mean %.4f m\n",
                  r.mesh_vertices, r.mesh_triangles, r.gt_points, v.p_to_gt.mean, v.p_to_gt.max, v.p_to_gt.median, v.p_to_gt.p90,
                  v.gt_to_p.mean, v.gt_to_p.max, v.gt_to_p.median, v.gt_to_p.p90, v.ae_sym, v.hd_sym, r.delta,
                  100 * v.share_within_delta, s.samples, r.threshold, s.accuracy, s.completeness, s.chamfer_l1, 100 * s.precision,
                  100 * s.recall, 100 * s.fscore, s.gt_to_surface.median, s.gt_to_surface.p90, s.gt_to_surface.mean);
    std::string out = buf;
    out += "AE P->GT by range:";
    for (const RangeBin& b : v.by_range)
        if (b.count > 0) {
            std::snprintf(buf, sizeof buf, " [%g,%g) %.3f (%zu)", b.lo, b.hi, b.mean, b.count);
            out += buf;
        }
    return out + "\n";
}

std::string to_json(const EvaluationResult& r) {
    const VertexMetrics& v = r.vertex;
    const SurfaceMetrics& s = r.surface;
    std::ostringstream o;
    o << "{\n  \"mesh_vertices\": " << r.mesh_vertices << ",\n  \"mesh_triangles\": " << r.mesh_triangles
      << ",\n  \"gt_points\": " << r.gt_points << ",\n  \"paper\": {\n    \"p_to_gt\": " << directed_json(v.p_to_gt)
      << ",\n    \"gt_to_p\": " << directed_json(v.gt_to_p) << ",\n    \"ae_sym\": " << num(v.ae_sym)
      << ",\n    \"hd_sym\": " << num(v.hd_sym) << ",\n    \"delta\": " << num(r.delta)
      << ",\n    \"share_within_delta\": " << num(v.share_within_delta)
      << ",\n    \"curve\": {\"delta\": " << array_json(v.curve_delta, num) << ", \"share\": " << array_json(v.curve_share, num)
      << "},\n    \"by_range\": "
      << array_json(v.by_range,
                    [](const RangeBin& b) {
                        return "{\"lo\": " + num(b.lo) + ", \"hi\": " + num(b.hi) + ", \"count\": " + std::to_string(b.count) +
                               ", \"ae\": " + (b.count ? num(b.mean) : std::string("null")) + "}";
                    })
      << "\n  },\n  \"surface\": {\n    \"samples\": " << s.samples << ",\n    \"threshold\": " << num(r.threshold)
      << ",\n    \"accuracy\": " << num(s.accuracy) << ",\n    \"completeness\": " << num(s.completeness)
      << ",\n    \"chamfer_l1\": " << num(s.chamfer_l1) << ",\n    \"precision\": " << num(s.precision)
      << ",\n    \"recall\": " << num(s.recall) << ",\n    \"fscore\": " << num(s.fscore)
      << ",\n    \"gt_to_surface\": " << directed_json(s.gt_to_surface) << "\n  }\n}\n";
    return o.str();
}

namespace {
std::string ring_row(const char* label, const HoldoutDistances& h) {
    char buf[256];
    std::string row;
    std::snprintf(buf, sizeof buf, "  %-10s %8zu", label, h.count);
    row += buf;
    for (double w : h.within) {
        std::snprintf(buf, sizeof buf, "  %7.1f%%", 100 * w);
        row += buf;
    }
    std::snprintf(buf, sizeof buf, "  %7.4f  %7.4f  %7.4f\n", h.mean, h.median, h.p90);
    return row + buf;
}

std::string holdout_json(const HoldoutDistances& h) {
    return "{\"lo\": " + num(h.lo) + ", \"hi\": " + num(h.hi) + ", \"count\": " + std::to_string(h.count) +
           ", \"within\": " + array_json(h.within, num) + ", \"mean\": " + num(h.mean) + ", \"median\": " + num(h.median) +
           ", \"p90\": " + num(h.p90) + "}";
}
}  // namespace

std::string format_table(const RingHoldoutResult& r) {
    char buf[64];
    std::string out = "odd-ring points to the mesh of the even rings (metres):\n  range        points";
    for (double t : r.thresholds) {
        std::snprintf(buf, sizeof buf, "  <=%5.3g m", t);
        out += buf;
    }
    out += "     mean   median      p90\n";
    for (const HoldoutDistances& b : r.by_range) {
        std::snprintf(buf, sizeof buf, "%g-%g m", b.lo, b.hi);
        out += ring_row(buf, b);
    }
    return out + ring_row("all", r.all);
}

std::string to_json(const RingHoldoutResult& r) {
    return "{\"ring_holdout\": {\"rings\": " + std::to_string(r.rings) + ", \"reconstructed\": " + std::to_string(r.reconstructed) +
           ", \"held_out\": " + std::to_string(r.held_out) + ", \"mesh_triangles\": " + std::to_string(r.mesh_triangles) +
           ", \"thresholds\": " + array_json(r.thresholds, num) + ", \"all\": " + holdout_json(r.all) +
           ", \"by_range\": " + array_json(r.by_range, holdout_json) + "}}\n";
}

}  // namespace lidarsurf
