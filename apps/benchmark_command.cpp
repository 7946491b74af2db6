// lidarsurf benchmark: the paper's Table I and Fig. 6 on a sequence in the KITTI layout.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "commands.hpp"
#include "lidarsurf/eval/benchmark.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/point_reader.hpp"

#ifndef LIDARSURF_SOURCE_DIR
#define LIDARSURF_SOURCE_DIR ""
#endif
#ifndef LIDARSURF_DATA_DIR
#define LIDARSURF_DATA_DIR ""
#endif

namespace fs = std::filesystem;

namespace lidarsurf::cli {
namespace {

std::vector<BenchmarkMethod> select_methods(const std::vector<BenchmarkMethod>& all, const std::string& list) {
    if (list.empty()) return all;
    std::vector<BenchmarkMethod> out;
    std::stringstream ss(list);
    std::string name;
    while (std::getline(ss, name, ',')) {
        while (!name.empty() && name.front() == ' ') name.erase(name.begin());
        bool found = false;
        for (const auto& m : all)
            if (m.name == name) {
                out.push_back(m);
                found = true;
            }
        if (!found) {
            std::string names;
            for (const auto& m : all) names += "\n  " + m.name;
            throw InvalidArgument("unknown benchmark method '" + name + "'; the rows are:" + names);
        }
    }
    return out;
}

/// The plotting script: $LIDARSURF_PLOT_SCRIPT, the installed copy, or the source tree's.
fs::path plot_script() {
    if (const char* env = std::getenv("LIDARSURF_PLOT_SCRIPT")) return env;
    for (const fs::path& p : {fs::path(LIDARSURF_DATA_DIR) / "plot_benchmark.py", fs::path(LIDARSURF_SOURCE_DIR) / "scripts" / "plot_benchmark.py"}) {
        std::error_code ec;
        if (!p.empty() && fs::exists(p, ec)) return p;
    }
    return {};
}

std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

}  // namespace

CLI::App* add_benchmark_command(CLI::App& app, BenchmarkOptions& o) {
    auto* b = app.add_subcommand("benchmark", "Run the paper's Table I (every mode and IMLS) over a simulated sequence");
    b->footer(
        "Examples:\n"
        "  lidarsurf simulate -o town && lidarsurf benchmark town\n"
        "  lidarsurf benchmark town --frames 10 --methods 'AN+GC kmax=5,IMLS'\n"
        "Reads DIR/velodyne and DIR/gt (KITTI layout, sensor frame); writes DIR/benchmark/table.txt,\n"
        "results.csv, results.json and, with python3-matplotlib, fig6a_range.png and fig6b_delta.png.\n");
    b->add_option("dir", o.dir, "Sequence directory (as written by lidarsurf simulate)")->required();
    b->add_option("--out", o.out, "Output directory (default DIR/benchmark)");
    b->add_option("--frames", o.frames, "Use only the first N frames (0 = all)")->capture_default_str();
    b->add_option("--stride", o.stride, "Use every S-th frame")->capture_default_str();
    b->add_option("--methods", o.methods, "Comma-separated rows to run (default: all of Table I)");
    b->add_option("--max-range", o.max_range, "Evaluate only within this range of the sensor (0 = all)")->capture_default_str();
    b->add_flag("--literal", o.literal, "Paper-literal rows: no planarity guard, no truncation, full dilation");
    b->add_flag("--no-plots", o.no_plots, "Do not draw the figures");
    b->add_option("--voxel", o.config.voxel_size, "Voxel size alpha in metres")->capture_default_str();
    b->add_option("--tau", o.config.tau, "Gaussian confidence threshold tau")->capture_default_str();
    b->add_option("--nmin", o.config.n_min, "Minimum points N_min")->capture_default_str();
    b->add_option("--threads", o.config.threads, "Worker threads (0 = all cores)")->capture_default_str();
    return b;
}

int run_benchmark(const BenchmarkOptions& o) {
    if (o.frames < 0) throw InvalidArgument("--frames must be >= 0");
    if (o.stride < 1) throw InvalidArgument("--stride must be >= 1");
    ReconstructionConfig base = o.config;
    if (o.literal) {
        base.min_planarity = 0;
        base.truncation_voxels = 0;
        base.seeded_surface = false;
    }
    base.validate();
    const std::vector<BenchmarkMethod> methods = select_methods(table_one_methods(base), o.methods);
    EvaluationConfig ec;
    ec.max_range = o.max_range;
    ec.threads = base.threads;
    ec.validate();

    const KittiSequence seq{o.dir};
    std::size_t available = seq.frame_count();
    if (available == 0) throw InvalidInput(o.dir + ": no scan in velodyne/ (expected 000000.bin, ...)");
    std::vector<std::size_t> frames;
    for (std::size_t i = 0; i < available; i += static_cast<std::size_t>(o.stride)) {
        if (o.frames > 0 && frames.size() == static_cast<std::size_t>(o.frames)) break;
        frames.push_back(i);
    }
    const fs::path out = o.out.empty() ? seq.dir / "benchmark" : fs::path(o.out);
    std::error_code ec_fs;
    fs::create_directories(out, ec_fs);
    if (ec_fs) throw IoError(out.string() + ": cannot create the directory (" + ec_fs.message() + ")");

    std::vector<std::string> names;
    for (const auto& m : methods) names.push_back(m.name);
    BenchmarkAccumulator acc(names);
    const auto t_start = std::chrono::steady_clock::now();
    for (std::size_t f = 0; f < frames.size(); ++f) {
        const std::size_t i = frames[f];
        PointCloud scan = read_points(seq.scan(i));
        drop_non_finite(scan);
        PointCloud gt = read_points(seq.ground_truth(i));
        drop_non_finite(gt);
        for (std::size_t m = 0; m < methods.size(); ++m) {
            const auto t0 = std::chrono::steady_clock::now();
            const Mesh mesh = run_benchmark_method(methods[m], scan, Eigen::Vector3d::Zero());
            const double seconds = ms_since(t0) / 1e3;
            if (mesh.empty()) {
                acc.add_empty(m);
                continue;
            }
            acc.add(m, evaluate(mesh, gt.points, ec), seconds);
        }
        std::fprintf(stderr, "benchmark: frame %zu (%zu/%zu), %zu methods, %.0f s elapsed\n", i, f + 1, frames.size(), methods.size(),
                     ms_since(t_start) / 1e3);
    }
    std::string label = o.dir + (o.literal ? " (paper-literal rows)" : "");
    const BenchmarkResult result = acc.finish(label, frames.size());
    const std::string table = format_table_one(result);
    std::printf("%s", table.c_str());
    write_text((out / "table.txt").string(), table);
    write_text((out / "results.csv").string(), to_csv(result));
    const fs::path json = out / "results.json";
    write_text(json.string(), to_json(result));
    std::printf("results: %s, %s, %s\n", (out / "table.txt").c_str(), (out / "results.csv").c_str(), json.c_str());
    if (o.no_plots) return 0;
    const fs::path script = plot_script();
    if (script.empty()) {
        std::fprintf(stderr, "lidarsurf: warning: figures not drawn: plot_benchmark.py not found (set LIDARSURF_PLOT_SCRIPT)\n");
        return 0;
    }
    std::fflush(stdout);
    const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
    const std::string cmd = python + " " + quoted(script.string()) + " " + quoted(json.string()) + " " + quoted(out.string());
    if (std::system(cmd.c_str()) != 0)
        std::fprintf(stderr, "lidarsurf: warning: figures not drawn: '%s' failed (is python3-matplotlib installed?)\n", cmd.c_str());
    return 0;
}

}  // namespace lidarsurf::cli
