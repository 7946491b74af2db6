#pragma once
// Helpers shared by the lidarsurf subcommands (apps/ only; the library never prints or exits).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "lidarsurf/baselines/imls.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/io/recorded_poses.hpp"
#include "lidarsurf/io/recording.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/pipeline.hpp"

namespace lidarsurf::cli {

/// "x,y,z" -> vector; InvalidArgument naming `what` otherwise.
Eigen::Vector3d parse_vec3(const std::string& text, const char* what);
/// 2: the user's arguments; 3: the data; 4: the file system; 5: over the memory budget; 1: anything else.
int exit_code(const Error& e);

/// The ReconstructionConfig options, named as its fields in kebab-case (--voxel-size, --tau,
/// --n-min, --k-max, [--k,] the guards; the earlier spellings --voxel, --nmin, --kmax, --slab, ...
/// as hidden aliases), filling `c` whose values are the defaults shown. Returns the guard options
/// (the ones --literal excludes).
std::vector<CLI::Option*> add_config_options(CLI::App* app, ReconstructionConfig& c, bool with_constant_level);
/// --max-memory-mb and --threads (ReconstructionConfig's run settings, RunConfig).
void add_run_options(CLI::App* app, ReconstructionConfig& c);
/// --live-growth, --live-range, --live-reach-blocks, --live-halo-cubes (LiveMeshConfig).
void add_live_mesh_options(CLI::App* app, ReconstructionConfig& c);
/// Every setting of `c` by its field's name, and its mode: a JSON report's "config".
nlohmann::json config_json(const ReconstructionConfig& c);

/// Options shared by `reconstruct`, `evaluate --holdout`, `bench` and `fuse`.
struct ReconstructOptions {
    std::string format = "auto", origin = "0,0,0", mode = "an+gc", method = "default";
    std::string simd;  // empty: the widest this CPU has (core/simd.hpp)
    int bin_fields = 4;
    int intensity_field = PointReadOptions{}.intensity_field;  // -1: none
    ReconstructionConfig config;  // paper defaults, defined once in ReconstructionConfig
    ImlsConfig imls;              // only the fields given on the command line are used
    bool imls_radius = false, imls_k = false, imls_h = false, imls_truncation = false;
    bool literal = false;  // ReconstructionConfig::make_paper_literal()
};
void add_reconstruct_options(CLI::App* app, ReconstructOptions& o);

/// How a recording is read (`reconstruct`, `info`): --topic, --metadata, --returns.
struct RecordingFlags {
    std::string topic, metadata, returns = "first";
};
void add_recording_options(CLI::App* app, RecordingFlags& o);
RecordingOptions recording_options(const RecordingFlags& o);

/// Where a recording's poses come from (`fuse`, `info`): --pose-topic, --fixed-frame, --sensor-frame.
struct PoseFlags {
    std::string pose_topic, fixed_frame, sensor_frame;
};
void add_pose_options(CLI::App* app, PoseFlags& o);
RecordedPosesOptions recorded_poses_options(const PoseFlags& o);

/// The method and its settings, validated before any file is read.
struct Method : MethodConfig {
    Eigen::Vector3d sensor = Eigen::Vector3d::Zero();
    PointReadOptions read;
};
Method resolve_method(const ReconstructOptions& o);
std::string method_name(const Method& m);
/// Runs the chosen method; `summary` receives one line of counts and times. InvalidInput when
/// the reconstruction is empty.
Mesh run_method(const Method& m, const PointCloud& cloud, std::string& summary);
/// The same, freeing the cloud once it is integrated.
Mesh run_method(const Method& m, PointCloud&& cloud, std::string& summary);

/// Where a command's report goes: stderr when `output` is the standard output itself
/// (`-o /dev/stdout`), so the report does not end up inside the file written there; stdout otherwise.
std::FILE* report_stream(const std::filesystem::path& output);

double ms_since(std::chrono::steady_clock::time_point t0);
/// This process's resident memory now, and its peak since it started or since the last
/// reset_peak_resident() (MiB; Linux).
double resident_mib();
double peak_resident_mib();
void reset_peak_resident();
/// Lower-case extension with the dot (".ply"), "" when none.
std::string extension_of(const std::filesystem::path& path);
/// The whole file; IoError when it cannot be read.
std::string read_text_file(const std::filesystem::path& path);
/// Writes `text` to `path` atomically.
void write_text(const std::string& path, const std::string& text);
/// Writes a JSON report to `path` atomically (indented by one, a final newline).
void write_json(const std::string& path, const nlohmann::json& j);

}  // namespace lidarsurf::cli
