// lidarsurf benchmark: the paper's Table I and Fig. 6, and the true-surface table, on a
// sequence in the KITTI layout.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>

#include "commands.hpp"
#include "file_roles.hpp"
#include "progress.hpp"
#include "lidarsurf/eval/benchmark.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/sim/mesh_builder.hpp"

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

/// A method whose meshes were made by another tool (scripts/peers_open3d.py): DIR/NAME/NNNNNN.ply
/// per frame and DIR/NAME/times.txt ("frame seconds" lines).
struct ExternalMethod {
    std::string name;
    fs::path dir;
    std::map<std::size_t, double> seconds;
};

std::vector<ExternalMethod> external_methods(const std::string& peers) {
    std::vector<ExternalMethod> out;
    if (peers.empty()) return out;
    std::error_code ec;
    if (!fs::is_directory(peers, ec)) throw IoError(peers + ": not a directory (expected one sub-directory of meshes per method)");
    for (const auto& entry : fs::directory_iterator(peers, ec)) {
        if (!entry.is_directory()) continue;
        ExternalMethod m{entry.path().filename().string(), entry.path(), {}};
        const fs::path times = entry.path() / "times.txt";
        if (fs::exists(times)) {
            std::istringstream in(read_text_file(times));
            std::size_t frame = 0;
            double seconds = 0;
            while (in >> frame >> seconds) m.seconds[frame] = seconds;
        }
        out.push_back(std::move(m));
    }
    if (ec) throw IoError(peers + ": cannot list the directory (" + ec.message() + ")");
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
    if (out.empty()) throw InvalidInput(peers + ": no sub-directory of meshes");
    return out;
}

/// The frame's true surface in the sensor frame: the static scene and that frame's moving
/// objects, both stored in the world frame, moved by the inverse of the sensor-to-world pose.
Mesh true_surface(const Mesh& scene, const KittiSequence& seq, std::size_t frame, const Eigen::Isometry3d& pose) {
    sim::MeshBuilder builder;
    builder.append(scene);
    if (fs::exists(seq.objects(frame))) builder.append(read_mesh(seq.objects(frame)));
    Mesh truth = builder.take();
    const Eigen::Isometry3d to_sensor = pose.inverse();
    for (auto& v : truth.vertices) v = to_sensor * v;
    return truth;
}

std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

}  // namespace

CLI::App* add_benchmark_command(CLI::App& app, BenchmarkOptions& o) {
    auto* b = app.add_subcommand("benchmark", "Run the default, the paper's Table I (every mode, as written) and IMLS over a simulated sequence");
    b->footer(
        "Examples:\n"
        "  lidarsurf simulate -o town && lidarsurf benchmark town\n"
        "  lidarsurf benchmark town --frames 10 --methods 'AN+GC kmax=5,IMLS'\n"
        "  lidarsurf benchmark town --methods 'AN+GC kmax=5' --peers town/peers\n"
        "  lidarsurf benchmark town --methods default --slab-from-level 0   (the default row with other settings)\n"
        "Reads DIR/velodyne and DIR/gt (KITTI layout, sensor frame); with DIR/scene.ply and poses.txt\n"
        "also the true surface (plus DIR/objects/NNNNNN.ply). Writes DIR/benchmark/table.txt,\n"
        "results.csv, results.json and, with python3-matplotlib, fig6a_range.png and fig6b_delta.png.\n");
    b->add_option("dir", o.dir, "Sequence directory (as written by lidarsurf simulate)")->required();
    b->add_option("--out", o.out, "Output directory (default DIR/benchmark)");
    b->add_option("--frames", o.frames, "Use only the first N frames (0 = all)")->capture_default_str();
    b->add_option("--stride", o.stride, "Use every S-th frame")->capture_default_str();
    b->add_option("--methods", o.methods, "Comma-separated rows to run (default: every row: default, Table I, IMLS; or the ablation)");
    b->add_option("--peers", o.peers, "Also evaluate other tools' meshes: DIR/NAME/NNNNNN.ply (scripts/peers_open3d.py)");
    b->add_option("--max-range", o.max_range, "Evaluate only within this range of the sensor (0 = all)")->capture_default_str();
    b->add_flag("--ablation", o.ablation, "Run the ablation rows (paper AN+GC to the default, one guard at a time) instead of Table I");
    b->add_flag("--no-plots", o.no_plots, "Do not draw the figures");
    b->add_flag("-q,--quiet", o.quiet, "No progress report on stderr");
    // The configuration of the default row (and the ablation's end point); Table I's rows take
    // alpha, tau and N_min from it, the rest from the paper.
    add_config_options(b, o.config, false);
    add_run_options(b, o.config);
    return b;
}

int run_benchmark(const BenchmarkOptions& o) {
    if (o.frames < 0) throw InvalidArgument("--frames must be >= 0");
    if (o.stride < 1) throw InvalidArgument("--stride must be >= 1");
    const ReconstructionConfig& base = o.config;
    base.validate();
    const std::vector<BenchmarkMethod> methods =
        select_methods(o.ablation ? ablation_methods(base) : table_one_methods(base), o.methods);
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
    FileRoles files;
    files.input_sequence(seq.dir);
    if (!o.peers.empty()) files.input_tree(o.peers);
    for (const char* name : {"table.txt", "results.csv", "results.json"}) files.output(out / name, "--out");
    std::error_code ec_fs;
    fs::create_directories(out, ec_fs);
    if (ec_fs) throw IoError(out.string() + ": cannot create the directory (" + ec_fs.message() + ")");
    files.check();

    const std::vector<ExternalMethod> peers = external_methods(o.peers);
    // The true surface: the scene mesh and the poses that place it in each sensor frame.
    const bool has_truth = fs::exists(seq.scene()) && fs::exists(seq.poses());
    Mesh scene;
    std::vector<Eigen::Isometry3d> poses;
    if (has_truth) {
        scene = read_mesh(seq.scene());
        poses = read_poses(seq.poses());
        if (poses.size() < available)
            throw InvalidInput(seq.poses().string() + ": " + std::to_string(poses.size()) + " poses for " + std::to_string(available) + " scans");
    } else {
        std::fprintf(stderr, "benchmark: no %s and poses.txt: the true-surface table is skipped\n", seq.scene().c_str());
    }

    std::vector<std::string> names;
    for (const auto& m : methods) names.push_back(m.name);
    for (const auto& m : peers) names.push_back(m.name);
    BenchmarkAccumulator acc(names);
    Progress progress("benchmark", "frames", frames.size(), o.quiet);
    for (std::size_t f = 0; f < frames.size(); ++f) {
        const std::size_t i = frames[f];
        PointCloud scan = read_points(seq.scan(i));
        drop_non_finite(scan);
        PointCloud gt = read_points(seq.ground_truth(i));
        drop_non_finite(gt);
        std::optional<MeshDistance> truth;
        if (has_truth) truth.emplace(true_surface(scene, seq, i, poses[i]));
        auto add = [&](std::size_t row, const Mesh& mesh, double seconds) {
            if (mesh.empty()) return acc.add_empty(row);
            acc.add(row, truth ? evaluate(mesh, gt.points, ec, *truth) : evaluate(mesh, gt.points, ec), seconds);
        };
        for (std::size_t m = 0; m < methods.size(); ++m) {
            const auto t0 = std::chrono::steady_clock::now();
            const Mesh mesh = reconstruct_with(methods[m], scan, Eigen::Vector3d::Zero());
            add(m, mesh, ms_since(t0) / 1e3);
        }
        for (std::size_t p = 0; p < peers.size(); ++p) {
            const fs::path file = peers[p].dir / (KittiSequence::frame_name(i) + ".ply");
            const auto t = peers[p].seconds.find(i);
            add(methods.size() + p, fs::exists(file) ? read_mesh(file) : Mesh{}, t == peers[p].seconds.end() ? 0.0 : t->second);
        }
        progress.update(f + 1, "frame " + KittiSequence::frame_name(i) + ", " + std::to_string(methods.size() + peers.size()) + " rows");
    }
    progress.finish();
    std::string label = o.dir + (o.ablation ? " (ablation)" : "");
    const BenchmarkResult result = acc.finish(label, frames.size());
    const std::string table = format_table_one(result) + "\n" + format_true_surface(result);
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
