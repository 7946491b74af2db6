// lidarsurf command-line tool. The only place where library exceptions become messages and
// exit codes: 0 success, 1 internal error, 2 bad arguments, 3 bad input data, 4 file system error.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

#include "lidarsurf/core/errors.hpp"
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

struct ReconstructOptions {
    std::string input, output, format = "auto", mesh_format = "auto", origin = "0,0,0", mode = "an+gc";
    int bin_fields = 4;
    bool k_given = false;
};

int run_reconstruct(const ReconstructOptions& o, ReconstructionConfig config) {
    config.mode = parse_mode(o.mode);
    config.validate();
    const Eigen::Vector3d sensor = parse_vec3(o.origin, "--origin");
    const MeshFormat mesh_format = parse_mesh_format(o.mesh_format);
    refuse_overwriting_input(o.input, o.output);
    PointReadOptions read;
    read.format = parse_point_format(o.format);
    read.bin_fields = o.bin_fields;

    const auto t0 = std::chrono::steady_clock::now();
    const PointCloud cloud = read_points(o.input, read);
    const double read_ms = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    Reconstructor rec(config, sensor);
    rec.integrate(cloud);
    const Mesh mesh = rec.extract_mesh();
    if (mesh.empty())
        throw InvalidInput("the reconstruction produced no triangle (" + rec.summary().to_string() +
                           "); the cloud may be too sparse for n_min=" + std::to_string(config.n_min) + " at voxel size " +
                           std::to_string(config.voxel_size));
    const auto t1 = std::chrono::steady_clock::now();
    write_mesh(mesh, o.output, mesh_format);
    const double write_ms = 1e3 * std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    std::printf("%s: mode %s; %s; read %.1f ms, write %.1f ms -> %s\n", o.input.c_str(), std::string(to_string(config.mode)).c_str(),
                rec.summary().to_string().c_str(), read_ms, write_ms, o.output.c_str());
    return 0;
}

int run_simulate(const std::string& scene, const std::string& output, std::uint64_t seed) {
    if (scene != "demo") throw InvalidArgument("unknown scene '" + scene + "' (available: demo)");
    const auto world = sim::AnalyticScene::demo();
    const PointCloud cloud = sim::simulate_scan(world, sim::SensorModel::hdl64(), Eigen::Vector3d::Zero(), seed);
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

    ReconstructionConfig config;  // paper defaults, defined once in ReconstructionConfig
    ReconstructOptions ro;
    auto* rc = app.add_subcommand("reconstruct", "Reconstruct a triangle mesh from one lidar scan");
    rc->footer(
        "Examples:\n"
        "  lidarsurf reconstruct 000000.bin -o mesh.ply\n"
        "  lidarsurf reconstruct scan.pcd -o mesh.obj --mode cn --k 3 --origin 0,0,1.73\n"
        "  lidarsurf reconstruct sweep.bin --bin-fields 5 -o mesh.ply --voxel 0.1 --threads 2\n");
    rc->add_option("input", ro.input, "Input point cloud (.bin KITTI, .ply, .pcd, .xyz/.csv/.txt)")->required();
    rc->add_option("-o,--output", ro.output, "Output mesh (.ply binary by default, .obj)")->required();
    rc->add_option("--voxel", config.voxel_size, "Voxel size alpha in metres")->capture_default_str();
    rc->add_option("--tau", config.tau, "Gaussian confidence threshold tau, Eq. (3)")->capture_default_str();
    rc->add_option("--nmin", config.n_min, "Minimum points N_min in a neighbourhood, Eq. (1)")->capture_default_str();
    rc->add_option("--kmax", config.k_max, "Largest neighbourhood level k_max (adaptive modes)")->capture_default_str();
    rc->add_option("--k", config.k, "Neighbourhood level k (constant modes cn, cn+gc)")->capture_default_str();
    rc->add_option("--mode", ro.mode, "an+gc | an | cn+gc | cn (Sec. IV-B)")->capture_default_str();
    rc->add_option("--origin", ro.origin, "Sensor position x,y,z (orients the normals, Eq. 2)")->capture_default_str();
    rc->add_option("--min-planarity", config.min_planarity, "Reject neighbourhoods with lambda2 < this * lambda1 (0 = paper-literal)")->capture_default_str();
    rc->add_option("--truncation", config.truncation_voxels, "TSDF truncation in voxels (0 = none)")->capture_default_str();
    rc->add_option("--threads", config.threads, "Worker threads (0 = all cores)")->capture_default_str();
    rc->add_option("--format", ro.format, "Input format: auto | bin | ply | pcd | xyz")->capture_default_str();
    rc->add_option("--bin-fields", ro.bin_fields, "float32 values per point in .bin input (KITTI 4, nuScenes 5)")->capture_default_str();
    rc->add_option("--mesh-format", ro.mesh_format, "Output format: auto | ply | ply-ascii | obj")->capture_default_str();

    std::string scene = "demo", sim_out;
    std::uint64_t seed = 1;
    auto* sc = app.add_subcommand("simulate", "Simulate a lidar scan of a built-in analytic scene");
    sc->add_option("--scene", scene, "Scene: demo")->capture_default_str();
    sc->add_option("-o,--output", sim_out, "Output scan (.bin KITTI layout or .ply)")->required();
    sc->add_option("--seed", seed, "Noise seed")->capture_default_str();

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    try {
        if (*rc) return run_reconstruct(ro, config);
        if (*sc) return run_simulate(scene, sim_out, seed);
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
