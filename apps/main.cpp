// lidarsurf command-line tool. The only place where library exceptions become messages and
// exit codes: 0 success, 1 internal error, 2 bad arguments, 3 bad input data, 4 file system error.
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "lidarsurf/baselines/imls.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/holdout.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/eval/report.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/io/point_writer.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/version.hpp"

namespace fs = std::filesystem;
using namespace lidarsurf;

namespace {

Eigen::Vector3d parse_vec3(const std::string& text, const char* what) {
    std::stringstream ss(text);
    Eigen::Vector3d v;
    std::string item;
    int i = 0;
    while (std::getline(ss, item, ',')) {
        if (i == 3) break;
        try {
            std::size_t used = 0;
            v[i] = std::stod(item, &used);
            if (used != item.size()) throw std::invalid_argument(item);
        } catch (const std::exception&) {
            throw InvalidArgument(std::string(what) + " must be three numbers x,y,z (got '" + text + "')");
        }
        ++i;
    }
    if (i != 3 || ss.rdbuf()->in_avail() > 0 || !v.allFinite())
        throw InvalidArgument(std::string(what) + " must be three finite numbers x,y,z (got '" + text + "')");
    return v;
}

void refuse_overwriting_input(const fs::path& input, const fs::path& output) {
    std::error_code ec;
    if (fs::exists(output, ec) && fs::equivalent(input, output, ec))
        throw InvalidArgument("output '" + output.string() + "' is the input file; refusing to overwrite it");
}

// 2: the user's arguments; 3: the data; 4: the file system.
int exit_code(const Error& e) {
    if (dynamic_cast<const InvalidArgument*>(&e)) return 2;
    if (dynamic_cast<const FormatError*>(&e) || dynamic_cast<const InvalidInput*>(&e)) return 3;
    if (dynamic_cast<const IoError*>(&e)) return 4;
    return 1;
}

// Options shared by `reconstruct` and `evaluate --holdout`.
struct ReconstructOptions {
    std::string format = "auto", origin = "0,0,0", mode = "an+gc", method = "paper";
    int bin_fields = 4;
    ReconstructionConfig config;  // paper defaults, defined once in ReconstructionConfig
    ImlsConfig imls;              // only the fields given on the command line are used
    bool imls_radius = false, imls_k = false, imls_h = false, imls_truncation = false;
};

void add_reconstruct_options(CLI::App* app, ReconstructOptions& o) {
    ReconstructionConfig& c = o.config;
    app->add_option("--method", o.method, "paper (Roldao et al., --mode selects the variant) | imls (baseline)")->capture_default_str();
    app->add_option("--voxel", c.voxel_size, "Voxel size alpha in metres")->capture_default_str();
    app->add_option("--tau", c.tau, "Gaussian confidence threshold tau, Eq. (3)")->capture_default_str();
    app->add_option("--nmin", c.n_min, "Minimum points N_min in a neighbourhood, Eq. (1)")->capture_default_str();
    app->add_option("--kmax", c.k_max, "Largest neighbourhood level k_max (adaptive modes)")->capture_default_str();
    app->add_option("--k", c.k, "Neighbourhood level k (constant modes cn, cn+gc)")->capture_default_str();
    app->add_option("--mode", o.mode, "an+gc | an | cn+gc | cn (Sec. IV-B)")->capture_default_str();
    app->add_option("--origin", o.origin, "Sensor position x,y,z (orients the normals, Eq. 2)")->capture_default_str();
    app->add_option("--min-planarity", c.min_planarity, "Reject neighbourhoods with lambda2 < this * lambda1 (0 = paper-literal)")->capture_default_str();
    app->add_option("--truncation", c.truncation_voxels, "TSDF truncation in voxels (0 = none)")->capture_default_str();
    app->add_option("--seeded", c.seeded_surface, "Keep only the surface connected to the data (0 = every defined cube)")->capture_default_str();
    app->add_option("--seed-dilation", c.seed_dilation, "Seed cubes within this many cubes of an occupied voxel")->capture_default_str();
    app->add_option("--threads", c.threads, "Worker threads (0 = all cores)")->capture_default_str();
    app->add_option("--format", o.format, "Input format: auto | bin | ply | pcd | xyz")->capture_default_str();
    app->add_option("--bin-fields", o.bin_fields, "float32 values per point in .bin input (KITTI 4, nuScenes 5)")->capture_default_str();
    auto given = [](bool& flag) { return [&flag](const std::string&) { flag = true; }; };
    app->add_option("--imls-radius", o.imls.radius, "IMLS support radius r in metres (default alpha * k_max)")->each(given(o.imls_radius));
    app->add_option("--imls-k", o.imls.normal_k, "IMLS neighbours for the normals (default N_min)")->each(given(o.imls_k));
    app->add_option("--imls-h", o.imls.bandwidth, "IMLS Gaussian bandwidth h in metres (default r / 3)")->each(given(o.imls_h));
    app->add_option("--imls-truncation", o.imls.truncation_voxels, "IMLS truncation in voxels (default 0 = none, as the paper)")
        ->each(given(o.imls_truncation));
}

// The method and its settings, validated before any file is read.
struct Method {
    bool imls = false;
    ReconstructionConfig config;
    ImlsConfig imls_config;
    Eigen::Vector3d sensor = Eigen::Vector3d::Zero();
    PointReadOptions read;
};

Method resolve_method(const ReconstructOptions& o) {
    Method m;
    m.config = o.config;
    m.config.mode = parse_mode(o.mode);
    m.config.validate();
    if (o.method == "imls") m.imls = true;
    else if (o.method != "paper") throw InvalidArgument("unknown method '" + o.method + "' (expected paper or imls)");
    m.imls_config = ImlsConfig::matching(m.config);
    if (o.imls_radius) {
        m.imls_config.radius = o.imls.radius;
        m.imls_config.bandwidth = o.imls.radius / 3.0;
    }
    if (o.imls_k) m.imls_config.normal_k = o.imls.normal_k;
    if (o.imls_h) m.imls_config.bandwidth = o.imls.bandwidth;
    if (o.imls_truncation) m.imls_config.truncation_voxels = o.imls.truncation_voxels;
    m.imls_config.validate();
    m.sensor = parse_vec3(o.origin, "--origin");
    m.read.format = parse_point_format(o.format);
    m.read.bin_fields = o.bin_fields;
    return m;
}

std::string method_name(const Method& m) { return m.imls ? "imls" : "mode " + std::string(to_string(m.config.mode)); }

// Runs the chosen method; `summary` receives one line of counts and times.
Mesh run_method(const Method& m, const PointCloud& cloud, std::string& summary) {
    Mesh mesh;
    if (m.imls) {
        ImlsSummary s;
        mesh = reconstruct_imls(cloud, m.sensor, m.imls_config, &s);
        summary = s.to_string();
    } else {
        Reconstructor rec(m.config, m.sensor);
        rec.integrate(cloud);
        mesh = rec.extract_mesh();
        summary = rec.summary().to_string();
    }
    if (mesh.empty())
        throw InvalidInput("the reconstruction produced no triangle (" + summary + "); the cloud may be too sparse for n_min=" +
                           std::to_string(m.config.n_min) + " at voxel size " + std::to_string(m.config.voxel_size));
    return mesh;
}

double ms_since(std::chrono::steady_clock::time_point t0) {
    return 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int run_reconstruct(const std::string& input, const std::string& output, const std::string& mesh_format_name,
                    const ReconstructOptions& o) {
    const Method m = resolve_method(o);
    const MeshFormat mesh_format = parse_mesh_format(mesh_format_name);
    refuse_overwriting_input(input, output);

    auto t0 = std::chrono::steady_clock::now();
    const PointCloud cloud = read_points(input, m.read);
    const double read_ms = ms_since(t0);
    std::string summary;
    const Mesh mesh = run_method(m, cloud, summary);
    t0 = std::chrono::steady_clock::now();
    write_mesh(mesh, output, mesh_format);
    std::printf("%s: %s; %s; read %.1f ms, write %.1f ms -> %s\n", input.c_str(), method_name(m).c_str(), summary.c_str(), read_ms,
                ms_since(t0), output.c_str());
    return 0;
}

struct EvaluateOptions {
    std::vector<std::string> inputs;
    std::string json, mesh_out, gt_format = "auto";
    int gt_bin_fields = 4;
    double holdout = 0, gt_spacing = 0.02;
    std::uint64_t seed = 1;
    EvaluationConfig eval;
};

void write_text(const std::string& path, const std::string& text) {
    AtomicFile file(path);
    file.stream() << text;
    file.commit();
}

// Ground truth as points: a point file, or a mesh (.obj, or .ply with faces) sampled densely.
std::vector<Eigen::Vector3d> read_ground_truth(const std::string& path, const EvaluateOptions& o) {
    std::string ext = fs::path(path).extension().string();
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (o.gt_format == "auto" && (ext == ".obj" || ext == ".ply")) {
        Mesh gt = read_mesh(path);
        if (!gt.triangles.empty()) return sample_surface(gt, o.gt_spacing, 20'000'000, o.seed);
        return std::move(gt.vertices);
    }
    PointReadOptions read;
    read.format = parse_point_format(o.gt_format);
    read.bin_fields = o.gt_bin_fields;
    PointCloud cloud = read_points(path, read);
    const std::size_t dropped = drop_non_finite(cloud);
    if (dropped) std::fprintf(stderr, "lidarsurf: %zu non-finite ground-truth points dropped\n", dropped);
    return std::move(cloud.points);
}

int run_evaluate(EvaluateOptions& o, const ReconstructOptions& ro) {
    EvaluationConfig& ec = o.eval;
    ec.seed = o.seed;
    if (!std::isfinite(o.gt_spacing) || o.gt_spacing <= 0) throw InvalidArgument("--gt-spacing must be finite and > 0");
    for (const std::string& in : o.inputs)
        if (!o.json.empty()) refuse_overwriting_input(in, o.json);
    Mesh mesh;
    std::vector<Eigen::Vector3d> gt;
    std::string header;
    if (o.holdout != 0) {
        if (o.inputs.size() != 1) throw InvalidArgument("evaluate --holdout takes one scan (got " + std::to_string(o.inputs.size()) + " inputs)");
        const Method m = resolve_method(ro);
        ec.origin = m.sensor;
        ec.threads = m.config.threads;
        ec.validate();
        if (!o.mesh_out.empty()) refuse_overwriting_input(o.inputs[0], o.mesh_out);
        PointCloud cloud = read_points(o.inputs[0], m.read);
        const std::size_t dropped = drop_non_finite(cloud);
        const HoldoutSplit split = split_holdout(cloud, o.holdout, o.seed);
        std::string summary;
        mesh = run_method(m, split.kept, summary);
        gt = split.held_out.points;
        char buf[256];
        std::snprintf(buf, sizeof buf, "hold-out %.3g (seed %llu): %zu points reconstructed, %zu held out, %zu non-finite dropped",
                      o.holdout, static_cast<unsigned long long>(o.seed), split.kept.points.size(), gt.size(), dropped);
        header = o.inputs[0] + ": " + method_name(m) + "; " + buf + "\n  " + summary + "\n";
        if (!o.mesh_out.empty()) write_mesh(mesh, o.mesh_out);
    } else {
        if (o.inputs.size() != 2)
            throw InvalidArgument("evaluate takes MESH GT (or --holdout FRACTION SCAN); got " + std::to_string(o.inputs.size()) + " input(s)");
        ec.origin = parse_vec3(ro.origin, "--origin");
        ec.threads = ro.config.threads;
        ec.validate();
        mesh = read_mesh(o.inputs[0]);
        gt = read_ground_truth(o.inputs[1], o);
        header = o.inputs[0] + " against " + o.inputs[1] + "\n";
    }
    const EvaluationResult result = evaluate(mesh, gt, ec);
    std::printf("%s%s", header.c_str(), format_table(result).c_str());
    if (!o.json.empty()) write_text(o.json, to_json(result));
    return 0;
}

int run_simulate(const std::string& scene, const std::string& output, const std::string& gt_output, std::uint64_t seed) {
    if (scene != "demo") throw InvalidArgument("unknown scene '" + scene + "' (available: demo)");
    const auto world = sim::AnalyticScene::demo();
    const PointCloud cloud = sim::simulate_scan(world, sim::SensorModel::hdl64(), Eigen::Vector3d::Zero(), seed);
    if (!gt_output.empty()) {
        const PointCloud gt = sim::simulate_scan(world, sim::SensorModel::ground_truth(), Eigen::Vector3d::Zero(), seed);
        write_points(gt, gt_output);
        std::printf("ground truth: %zu noise-free points (316 beams) -> %s\n", gt.points.size(), gt_output.c_str());
    }
    write_points(cloud, output);
    std::printf("simulated %zu points (scene %s, HDL-64E at 0,0,0, seed %llu) -> %s\n", cloud.points.size(), scene.c_str(),
                static_cast<unsigned long long>(seed), output.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"lidarsurf " LIDARSURF_VERSION_STRING " - surface reconstruction from lidar scans (Roldao et al., ITSC 2019)"};
    app.require_subcommand(1);
    app.set_version_flag("--version", LIDARSURF_VERSION_STRING);

    ReconstructOptions ro;
    std::string input, output, mesh_format = "auto";
    auto* rc = app.add_subcommand("reconstruct", "Reconstruct a triangle mesh from one lidar scan");
    rc->footer(
        "Examples:\n"
        "  lidarsurf reconstruct 000000.bin -o mesh.ply\n"
        "  lidarsurf reconstruct scan.pcd -o mesh.obj --mode cn --k 3 --origin 0,0,1.73\n"
        "  lidarsurf reconstruct sweep.bin --bin-fields 5 -o mesh.ply --voxel 0.1 --threads 2\n"
        "  lidarsurf reconstruct 000000.bin -o imls.ply --method imls\n");
    rc->add_option("input", input, "Input point cloud (.bin KITTI, .ply, .pcd, .xyz/.csv/.txt)")->required();
    rc->add_option("-o,--output", output, "Output mesh (.ply binary by default, .obj)")->required();
    rc->add_option("--mesh-format", mesh_format, "Output format: auto | ply | ply-ascii | obj")->capture_default_str();
    add_reconstruct_options(rc, ro);

    EvaluateOptions eo;
    auto* ev = app.add_subcommand("evaluate", "Measure a mesh against ground truth, or a method on a scan by hold-out");
    ev->footer(
        "Examples:\n"
        "  lidarsurf evaluate mesh.ply gt.bin --origin 0,0,0 --max-range 50 --json metrics.json\n"
        "  lidarsurf evaluate mesh.ply scene.obj          (a ground-truth mesh is sampled)\n"
        "  lidarsurf evaluate --holdout 0.5 000000.bin --seed 7 --method imls\n"
        "With --holdout the scan is split at random, one part is reconstructed with the reconstruct\n"
        "options and the held-out part is the ground truth (docs/evaluation.md).\n");
    ev->add_option("inputs", eo.inputs, "MESH GT, or SCAN with --holdout")->required()->expected(1, 2);
    ev->add_option("--holdout", eo.holdout, "Hold out this fraction of SCAN as ground truth, in (0, 1)");
    ev->add_option("--seed", eo.seed, "Seed of the hold-out split and of the surface sampling")->capture_default_str();
    ev->add_option("--max-range", eo.eval.max_range, "Evaluate only within this range of --origin (0 = all)")->capture_default_str();
    ev->add_option("--threshold", eo.eval.threshold, "Precision/recall/F-score threshold, metres")->capture_default_str();
    ev->add_option("--delta", eo.eval.delta, "Report the share of vertices within delta of GT (Fig. 6b)")->capture_default_str();
    ev->add_option("--sample-spacing", eo.eval.sample_spacing, "Mean spacing of the points sampled on the mesh, metres")->capture_default_str();
    ev->add_option("--gt-spacing", eo.gt_spacing, "Sample spacing of a ground-truth mesh, metres")->capture_default_str();
    ev->add_option("--gt-format", eo.gt_format, "Ground-truth format: auto | bin | ply | pcd | xyz")->capture_default_str();
    ev->add_option("--gt-bin-fields", eo.gt_bin_fields, "float32 values per point in a .bin ground truth")->capture_default_str();
    ev->add_option("--json", eo.json, "Also write the metrics as JSON to this file");
    ev->add_option("--mesh-out", eo.mesh_out, "With --holdout: write the reconstructed mesh here");
    add_reconstruct_options(ev, ro);

    std::string scene = "demo", sim_out, sim_gt;
    std::uint64_t seed = 1;
    auto* sc = app.add_subcommand("simulate", "Simulate a lidar scan of a built-in analytic scene");
    sc->add_option("--scene", scene, "Scene: demo")->capture_default_str();
    sc->add_option("-o,--output", sim_out, "Output scan (.bin KITTI layout or .ply)")->required();
    sc->add_option("--gt", sim_gt, "Also write the ground truth: a co-located noise-free 316-beam scan");
    sc->add_option("--seed", seed, "Noise seed")->capture_default_str();

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    try {
        if (*rc) return run_reconstruct(input, output, mesh_format, ro);
        if (*ev) return run_evaluate(eo, ro);
        if (*sc) return run_simulate(scene, sim_out, sim_gt, seed);
    } catch (const Error& e) {
        std::fprintf(stderr, "lidarsurf: error: %s\n", e.what());
        return exit_code(e);
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "lidarsurf: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "lidarsurf: internal error: %s\n", e.what());
        return 1;
    }
    return 1;
}
