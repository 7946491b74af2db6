// lidarsurf map-benchmark: fused maps of a simulated drive (moving objects included) against the
// exact static scene (eval/map_metrics, docs/evaluation.md "Maps"). Each row is one fusion, run as
// its own process (`lidarsurf fuse`, or a peer program such as VDBFusion's) so that its time and
// peak memory are its own; then every mesh is scored with the same ground truth and crop.
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "file_roles.hpp"
#include "progress.hpp"
#include "lidarsurf/eval/map_metrics.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"

extern char** environ;

namespace fs = std::filesystem;

namespace lidarsurf::cli {

CLI::App* add_map_benchmark_command(CLI::App& app, MapBenchmarkOptions& o) {
    CLI::App* c = app.add_subcommand("map-benchmark", "Fuse a simulated drive with each method and score the maps against the static scene");
    c->add_option("dir", o.dir, "Sequence directory written by lidarsurf simulate (scene.ply, gt/, poses.txt)")->required();
    c->add_option("--out", o.out, "Output directory (default DIR/map_benchmark)");
    c->add_option("--frames", o.frames, "Fuse only the first N frames (0 = all)")->capture_default_str();
    c->add_option("--rows", o.rows,
                  "Comma-separated rows: default, no-carving, paper, remesh-every-1, and with --vdbfusion: "
                  "vdbfusion-carving, vdbfusion, vdbfusion-kitti")
        ->capture_default_str();
    c->add_option("--fuse-options", o.fuse_options,
                  "More options for every lidarsurf row, as one string (an ablation: \"--truncation-voxels 1.5\")");
    c->add_option("--fuse-input", o.fuse_input,
                  "The lidarsurf rows fuse this recording of the drive (a bag of its scans, with --fuse-options \"--poses TUM\") "
                  "instead of DIR's scans; the scoring is DIR's");
    c->add_option("--vdbfusion", o.vdbfusion, "VDBFusion peer program (make map-peers builds build-peers/lidarsurf_vdbfusion_peer)");
    c->add_option("--gt-stride", o.gt_stride, "Ground truth from every this-many-th GT scan")->capture_default_str();
    c->add_option("--max-distance", o.eval.max_distance, "Score only within this horizontal distance of the drive (metres)")->capture_default_str();
    c->add_option("--threshold", o.eval.threshold, "Precision / recall threshold (metres)")->capture_default_str();
    c->add_option("--ghost-distance", o.eval.ghost_distance, "Mesh farther than this from the static scene is ghost (metres)")
        ->capture_default_str();
    c->add_option("--threads", o.threads, "Worker threads of every row and of the scoring (0 = all cores)")->capture_default_str();
    c->add_flag("-q,--quiet", o.quiet, "No progress report on stderr");
    c->footer("Example:\n  lidarsurf simulate --frames 170 --pedestrians 6 --cyclists 3 -o drive\n"
              "  lidarsurf map-benchmark drive --vdbfusion build-peers/lidarsurf_vdbfusion_peer\n"
              "Writes OUT/table.md, OUT/results.json and each row's mesh and fusion report in OUT/rows/.");
    return c;
}

namespace {

struct Row {
    std::string name, label;
    std::vector<std::string> argv;  // the program and its arguments
    bool peer = false;
};

// Runs argv as a child process; returns its wall time (s) and peak resident memory (MiB).
std::pair<double, double> run_child(const std::vector<std::string>& argv) {
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = 0;
    const auto t0 = std::chrono::steady_clock::now();
    if (const int err = posix_spawn(&pid, args[0], nullptr, nullptr, args.data(), environ); err != 0)
        throw IoError(argv[0] + ": cannot run it (" + std::strerror(err) + ")");
    int status = 0;
    rusage usage{};
    while (wait4(pid, &status, 0, &usage) < 0)
        if (errno != EINTR) throw IoError(argv[0] + ": lost the child process");
    const double seconds = ms_since(t0) / 1e3;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::string line;
        for (const std::string& a : argv) line += a + " ";
        throw InvalidInput("a row failed (" + (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : std::string("killed")) +
                           "): " + line);
    }
    return {seconds, static_cast<double>(usage.ru_maxrss) / 1024.0};
}

std::vector<std::string> split(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}


}  // namespace

int run_map_benchmark(const MapBenchmarkOptions& o) {
    if (o.frames < 0 || o.gt_stride < 1 || o.threads < 0) throw InvalidArgument("--frames must be >= 0, --gt-stride >= 1, --threads >= 0");
    o.eval.validate();
    const KittiSequence seq{o.dir};
    std::size_t frames = seq.frame_count();
    if (o.frames > 0) frames = std::min(frames, static_cast<std::size_t>(o.frames));
    if (!fs::exists(seq.scene())) throw IoError(seq.scene().string() + ": no static scene (map-benchmark needs a simulated sequence)");
    const std::vector<Eigen::Isometry3d> poses = read_poses(seq.poses());
    if (poses.size() < frames) throw InvalidInput(seq.poses().string() + ": fewer poses than scans");
    const fs::path out = o.out.empty() ? seq.dir / "map_benchmark" : fs::path(o.out);
    FileRoles files;
    files.input_sequence(seq.dir);
    if (!o.fuse_input.empty()) files.input(o.fuse_input);
    files.output_directory(out, "--out");
    files.check();
    fs::create_directories(out / "rows");

    // The rows, as command lines.
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    const std::string n = std::to_string(frames), threads = std::to_string(o.threads);
    std::istringstream more(o.fuse_options);
    const std::vector<std::string> ablation{std::istream_iterator<std::string>(more), std::istream_iterator<std::string>()};
    std::vector<Row> rows;
    for (const std::string& name : split(o.rows)) {
        const std::string mesh = (out / "rows" / (name + ".ply")).string(), json = (out / "rows" / (name + ".json")).string();
        std::vector<std::string> fuse = {self, "fuse", o.fuse_input.empty() ? seq.dir.string() : o.fuse_input, "-o", mesh, "--json", json, "--frames", n, "--threads", threads, "-q"};
        auto with = [&](std::vector<std::string> extra) {
            std::vector<std::string> a = fuse;
            a.insert(a.end(), extra.begin(), extra.end());
            a.insert(a.end(), ablation.begin(), ablation.end());
            return a;
        };
        auto peer = [&](std::vector<std::string> extra) {
            if (o.vdbfusion.empty()) throw InvalidArgument("row " + name + " needs --vdbfusion (the peer program; make map-peers)");
            std::vector<std::string> a = {fs::absolute(o.vdbfusion).string(), seq.dir.string(), mesh, "--json", json, "--frames", n};
            a.insert(a.end(), extra.begin(), extra.end());
            return a;
        };
        if (name == "default") rows.push_back({name, "lidarsurf default (carving)", with({}), false});
        else if (name == "no-carving") rows.push_back({name, "lidarsurf default, no carving", with({"--carve", "0"}), false});
        else if (name == "paper") rows.push_back({name, "the paper's AN+GC, fused", with({"--method", "paper"}), false});
        else if (name == "remesh-every-1") rows.push_back({name, "lidarsurf default, mesh after every scan", with({"--remesh-every", "1"}), false});
        else if (name == "vdbfusion-carving")
            rows.push_back({name, "VDBFusion 0.2 m, space carving", peer({"--voxel-size", "0.2", "--sdf-trunc", "0.6", "--space-carving", "1"}), true});
        else if (name == "vdbfusion")
            rows.push_back({name, "VDBFusion 0.2 m, min weight 5", peer({"--voxel-size", "0.2", "--sdf-trunc", "0.6", "--min-weight", "5"}), true});
        else if (name == "vdbfusion-kitti")
            rows.push_back({name, "VDBFusion, its KITTI settings (0.1 m, min weight 5)",
                            peer({"--voxel-size", "0.1", "--sdf-trunc", "0.3", "--min-weight", "5"}), true});
        else throw InvalidArgument("unknown row '" + name + "' (see --help)");
    }
    if (rows.empty()) throw InvalidArgument("--rows: no row");
    if (!o.fuse_options.empty())
        for (Row& r : rows)
            if (!r.peer) r.label += " [" + o.fuse_options + "]";

    // 1. Fuse, each row in its own process.
    Progress progress("map-benchmark", "rows", rows.size() + 1, o.quiet);
    std::vector<std::pair<double, double>> cost;
    for (std::size_t r = 0; r < rows.size(); ++r) {
        progress.update(r, rows[r].name);
        cost.push_back(run_child(rows[r].argv));
    }
    progress.update(rows.size(), "ground truth");

    // 2. The ground truth: static-scene GT points within the crop, from every gt_stride-th scan.
    const Mesh scene = read_mesh(seq.scene());
    const MeshDistance truth(scene);
    std::vector<Eigen::Vector3d> drive;
    for (std::size_t i = 0; i < frames; ++i) drive.push_back(poses[i].translation());
    const DriveCrop crop(drive, o.eval.max_distance);
    MapGroundTruth gt_builder(truth, crop, o.eval.gt_spacing);
    for (std::size_t i = 0; i < frames; i += static_cast<std::size_t>(o.gt_stride)) {
        PointCloud gt = read_points(seq.ground_truth(i));
        for (Eigen::Vector3d& p : gt.points) p = poses[i] * p;
        gt_builder.add(gt.points);
    }
    const std::vector<Eigen::Vector3d> gt = gt_builder.points();
    // The movers' paths: where they were at each scan (objects/, when the drive has movers).
    SweptVolume swept;
    for (std::size_t i = 0; i < frames; ++i)
        if (fs::exists(seq.objects(i))) swept.add(read_mesh(seq.objects(i)));
    // Height reference: the median height of the GT points within 5 m of the drive (the road).
    MapEvaluationConfig eval = o.eval;
    eval.threads = o.threads;
    {
        std::vector<double> road;
        const DriveCrop near(drive, 5.0);
        for (const Eigen::Vector3d& p : gt)
            if (near.contains(p)) road.push_back(p.z());
        eval.ground_z = summarize(road).median;
    }

    // 3. Score every map.
    nlohmann::json results = nlohmann::json::array();
    std::ostringstream table;
    char line[1024];
    std::snprintf(line, sizeof line,
                  "| method | precision | recall | F@%.2g | accuracy (m) | completeness (m) | Chamfer-L1 (m) | ghost area (>%.2g m) | "
                  "on the movers' paths | integrate per scan | peak memory |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
                  eval.threshold, eval.ghost_distance);
    table << line;
    std::ostringstream boundary;
    boundary << "| method |";
    for (std::size_t b = 0; b <= eval.height_bands.size(); ++b) {
        const double lo = b == 0 ? -1 : eval.height_bands[b - 1];
        if (b == 0) std::snprintf(line, sizeof line, " below %.2g m |", eval.height_bands[0]);
        else if (b == eval.height_bands.size()) std::snprintf(line, sizeof line, " above %.2g m |", lo);
        else std::snprintf(line, sizeof line, " %.2g-%.2g m |", lo, eval.height_bands[b]);
        boundary << line;
    }
    boundary << "\n|---|";
    for (std::size_t b = 0; b <= eval.height_bands.size(); ++b) boundary << "---|";
    boundary << "\n";
    std::string remesh_line;
    for (std::size_t r = 0; r < rows.size(); ++r) {
        const Row& row = rows[r];
        const Mesh mesh = read_mesh(out / "rows" / (row.name + ".ply"));
        const MapMetrics m = evaluate_map(mesh, truth, gt, crop, eval, &swept);
        std::ifstream report_file(out / "rows" / (row.name + ".json"));
        const nlohmann::json report = nlohmann::json::parse(report_file);
        const double integrate_s = report.at("seconds").at("insert").get<double>() + report.at("seconds").value("carve", 0.0);
        const double per_scan_ms = 1e3 * integrate_s / static_cast<double>(frames);
        std::snprintf(line, sizeof line, "| %s | %.1f %% | %.1f %% | %.1f %% | %.3f | %.3f | %.3f | %.0f m², %.2f %% | %.1f m² | %.1f ms | %.0f MiB |\n",
                      row.label.c_str(), 100 * m.precision, 100 * m.recall, 100 * m.fscore, m.accuracy, m.completeness, m.chamfer_l1,
                      m.ghost_area, 100 * m.ghost_share(), m.path_ghost_area, per_scan_ms, cost[r].second);
        table << line;
        boundary << "| " << row.label << " |";
        nlohmann::json bands = nlohmann::json::array();
        for (const HeightBand& b : m.boundary_by_height) {
            std::snprintf(line, sizeof line, " %.1f %% |", 100 * b.boundary_share());
            boundary << line;
            bands.push_back({{"lo", std::isfinite(b.lo) ? nlohmann::json(b.lo) : nlohmann::json()},
                             {"hi", std::isfinite(b.hi) ? nlohmann::json(b.hi) : nlohmann::json()},
                             {"edges", b.edges},
                             {"boundary_edges", b.boundary_edges}});
        }
        boundary << "\n";
        nlohmann::json j = {{"row", row.name},
                            {"label", row.label},
                            {"command", row.argv},
                            {"precision", m.precision},
                            {"recall", m.recall},
                            {"fscore", m.fscore},
                            {"accuracy", m.accuracy},
                            {"completeness", m.completeness},
                            {"chamfer_l1", m.chamfer_l1},
                            {"mesh_area", m.mesh_area},
                            {"ghost_area", m.ghost_area},
                            {"ghost_share", m.ghost_share()},
                            {"path_ghost_area", m.path_ghost_area},
                            {"samples", m.samples},
                            {"gt_points", m.gt_points},
                            {"integrate_ms_per_scan", per_scan_ms},
                            {"wall_seconds", cost[r].first},
                            {"peak_resident_mib", cost[r].second},
                            {"boundary_by_height", bands}};
        if (report.contains("per_frame")) {
            std::vector<double> per_frame_ms;
            for (const auto& f : report.at("per_frame"))
                per_frame_ms.push_back(f.value("integrate_ms", 0.0) + f.value("remesh_ms", 0.0));
            const DirectedError t = summarize(per_frame_ms);
            j["per_frame_ms_median"] = t.median;
            j["per_frame_ms_p90"] = t.p90;
            j["per_frame_ms_max"] = t.max;
            if (row.name == "remesh-every-1") {
                std::snprintf(line, sizeof line, "Meshing after every scan (integrate + extract): median %.1f ms, p90 %.1f ms, max %.1f ms per scan.\n",
                              t.median, t.p90, t.max);
                remesh_line = line;
            }
        }
        results.push_back(j);
    }
    progress.finish();
    std::ostringstream doc;
    std::snprintf(line, sizeof line,
                  "%zu frames of %s; ground truth: %zu static-scene GT points (one per %.2g m cell, every %d-th GT scan) within %.3g m of the "
                  "drive; %d threads (0 = all cores).\n\n",
                  frames, o.dir.c_str(), gt.size(), eval.gt_spacing, o.gt_stride, eval.max_distance, o.threads);
    doc << line << table.str() << "\n" << remesh_line << (remesh_line.empty() ? "" : "\n")
        << "Boundary edges (holes) by height above the road:\n\n" << boundary.str();
    {
        AtomicFile f(out / "table.md");
        f.stream() << doc.str();
        f.commit();
    }
    {
        AtomicFile f(out / "results.json");
        f.stream() << nlohmann::json{{"sequence", o.dir}, {"frames", frames}, {"gt_points", gt.size()}, {"rows", results}}.dump(1) << "\n";
        f.commit();
    }
    std::printf("%s", doc.str().c_str());
    return 0;
}

}  // namespace lidarsurf::cli
