#pragma once
// The subcommands, one *_command.cpp each: each adds itself to the app and runs from its options.
// Errors are thrown as lidarsurf exceptions; main() maps them to exit codes.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/recorded_drive.hpp"
#include "lidarsurf/map/empty_rays.hpp"
#include "lidarsurf/tiles/tiles.hpp"
#include "lidarsurf/eval/map_metrics.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/eval/ring_holdout.hpp"

namespace lidarsurf::cli {

struct ReconstructCommandOptions {
    std::string input, output, mesh_format = "auto";
    ReconstructOptions reconstruct;
    RecordingFlags recording;
    int scan = 0;  // the scan of a recording
    double time = -1;  // or the scan nearest this many seconds after its first (-1: by --scan)
};
CLI::App* add_reconstruct_command(CLI::App& app, ReconstructCommandOptions& o);
int run_reconstruct(const ReconstructCommandOptions& o);

struct InfoOptions {
    std::string input;
    RecordingFlags recording;
    PoseFlags recorded_poses;
    std::string json, save_poses;
};
CLI::App* add_info_command(CLI::App& app, InfoOptions& o);
int run_info(const InfoOptions& o);

struct EvaluateOptions {
    std::vector<std::string> inputs;
    std::string json, mesh_out, gt_format = "auto";
    int gt_bin_fields = 4;
    double holdout = 0, gt_spacing = 0.02;
    bool holdout_rings = false;
    std::string ring_field = "auto";
    std::uint64_t seed = 1;
    EvaluationConfig eval;
    RingHoldoutConfig rings;
    bool max_range_given = false;
    std::string ring_option;  // --ring-field or --range-bin when given: they need --holdout-rings
    bool json_given = false, mesh_out_given = false;  // an option given with an empty name is an error
    ReconstructOptions reconstruct;  // the method of --holdout and --holdout-rings; --origin, --threads
};
CLI::App* add_evaluate_command(CLI::App& app, EvaluateOptions& o);
int run_evaluate(EvaluateOptions o);

struct SimulateOptions {
    std::string scene = "town", sensor = "hdl64", output, gt, from, to;
    bool gt_given = false;  // --gt given, even with an empty name (an error)
    bool quiet = false;     // no progress report
    int frames = 100, gt_beams = 316, moving_cars = 3, pedestrians = 0, cyclists = 0, leaving_cars = 0, parking_cars = 0, dark_cars = 0;
    double length = 240.0, speed = 8.0, weave = 0.0, sweep_seconds = 0.0;
    std::uint64_t seed = 1;
};
CLI::App* add_simulate_command(CLI::App& app, SimulateOptions& o);
int run_simulate(const SimulateOptions& o);

struct RenderOptions {
    std::string input, output, colour = "height", eye, target;
    int width = 1280, height = 720;
    double fov = 55.0;
};
CLI::App* add_render_command(CLI::App& app, RenderOptions& o);
int run_render(const RenderOptions& o);

struct BenchmarkOptions {
    std::string dir, out, methods, peers;
    int frames = 0, stride = 1;
    bool no_plots = false, ablation = false, quiet = false;
    double max_range = 0;
    ReconstructionConfig config;  // alpha, tau, N_min, guards, threads; the rows set mode and k
};
CLI::App* add_benchmark_command(CLI::App& app, BenchmarkOptions& o);
int run_benchmark(const BenchmarkOptions& o);

struct BenchOptions {
    std::vector<std::string> scans;
    std::string json;
    bool json_given = false;  // --json given, even with an empty name (an error)
    int repeat = 7, slow_repeat = 3, frames = 3;
    bool no_reference = false, no_imls = false, no_scaling = false;
    ReconstructOptions reconstruct;  // the configuration timed (paper defaults)
    std::string allocator;           // how main() set the allocator (AllocatorTuning::describe())
};
CLI::App* add_bench_command(CLI::App& app, BenchOptions& o);
int run_bench(const BenchOptions& o);

struct FuseOptions {
    std::vector<std::string> dirs;  // one drive, or several whose poses share a world frame
    std::string output, mesh_format = "auto", calib, poses, json;
    int first = 0, frames = 0, step = 1, remesh_every = 0;
    bool quiet = false;  // no progress report
    bool live = false;   // keep the live mesh, updated after every scan
    double live_budget_ms = 30;
    int live_check_every = 0;  // compare the live mesh with the exact one every this many scans (0: never)
    int serve = -1;            // --serve PORT: the live view on this port (-1: none; 0: a free one)
    std::string bind = "127.0.0.1";
    double rate = 0;           // scans a second (0: as fast as it goes)
    TileConfig tiles{0.0};     // tile_size 0: the map whole, in memory
    ReconstructOptions reconstruct;  // the method and its configuration (paper defaults)
    RecordingFlags recording;        // a recording's topic, metadata and returns
    PoseFlags recorded_poses;        // without --poses: a bag's /tf or pose topic
    std::string times;               // KITTI poses' times.txt, for a recording
    int deskew = 1;                  // de-skew a recording's scans when they have per-point times
};
CLI::App* add_fuse_command(CLI::App& app, FuseOptions& o);
int run_fuse(const FuseOptions& o);

/// The drives `fuse` reads, resolved and checked: their scans one drive after the other.
struct FuseInput {
    struct Drive {
        KittiSequence seq;
        SequencePoses where;
        std::vector<Eigen::Isometry3d> poses;
        std::shared_ptr<RecordedDrive> recording;  // a recording's drive: scans read from it, in order
        std::optional<BeamPattern> pattern;         // a simulated drive's sensor (sensor.json): its rays that returned nothing
    };
    struct Scan {
        std::size_t drive = 0, frame = 0;
    };
    std::vector<Drive> drives;
    std::vector<Scan> scans;
    MeshFormat format = MeshFormat::Auto;

    const Eigen::Isometry3d& pose(std::size_t n) const { return drives[scans[n].drive].poses[scans[n].frame]; }
    /// Scan n in the world frame; `no_return`, when given, receives the directions (world) of its
    /// rays that returned nothing, from the recording or the drive's sensor pattern (empty when
    /// neither says).
    PointCloud read(std::size_t n, const PointReadOptions& options, std::vector<Eigen::Vector3f>* no_return = nullptr) const;
    /// "000042", or "2:000042" (drive 2) with several drives.
    std::string label(std::size_t n) const;
    /// The drives' directories, and where their poses came from, for reports.
    std::string name() const;
    std::string layout() const;
};
/// Reads and checks the drives of `o` (poses, frame ranges), their files' roles included.
FuseInput read_fuse_input(const FuseOptions& o);
/// fuse --tile-size: the map in tiles, one after the other, the mesh written tile by tile.
int run_fuse_tiles(const FuseOptions& o, const Method& m, const FuseInput& in);
/// What both ways of `fuse` open their JSON report with: the drives, their poses, the method and
/// its settings ("config"), the frame count.
nlohmann::json fuse_report_head(const FuseInput& in, const Method& m);
struct MapBenchmarkOptions {
    std::string dir, out, vdbfusion, fuse_options, fuse_input;
    std::string rows = "default,no-carving,paper";
    int frames = 0, gt_stride = 5, threads = 0;
    bool quiet = false;
    MapEvaluationConfig eval;
};
CLI::App* add_map_benchmark_command(CLI::App& app, MapBenchmarkOptions& o);
int run_map_benchmark(const MapBenchmarkOptions& o);

struct ViewOptions {
    std::string input, output, points, colour = "height", title;
    int max_points = 200000;
    double tau = 0.2;  ///< the mesh's tau: the confidence colouring marks the vertices below it (inferred surface)
    int points_scan = 0;       ///< --points of a recording: its scan
    RecordingFlags recording;  ///< --points of a recording: how it is read
};
CLI::App* add_view_command(CLI::App& app, ViewOptions& o);
int run_view(const ViewOptions& o);

}  // namespace lidarsurf::cli
