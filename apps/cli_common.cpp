// Helpers shared by the lidarsurf subcommands.
#include "cli_common.hpp"
#include "lidarsurf/core/simd.hpp"

#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <fstream>
#include <sstream>

#include "lidarsurf/core/setting.hpp"
#include "lidarsurf/core/stopwatch.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/core/format_value.hpp"

namespace fs = std::filesystem;

namespace lidarsurf::cli {

Eigen::Vector3d parse_vec3(const std::string& text, const char* what) {
    const std::string shown = text.substr(0, 80);
    std::vector<std::string> items;
    std::stringstream ss(text);
    for (std::string item; std::getline(ss, item, ',');) items.push_back(item);
    if (!text.empty() && text.back() == ',') items.emplace_back();  // "1,2,3," has a fourth, empty value
    if (items.size() != 3)
        throw InvalidArgument(std::string(what) + " must be three numbers x,y,z (got " + format_value(items.size()) + " values in '" + shown + "')");
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) {
        try {
            std::size_t used = 0;
            v[i] = std::stod(items[static_cast<std::size_t>(i)], &used);
            if (used != items[static_cast<std::size_t>(i)].size()) throw std::invalid_argument(items[static_cast<std::size_t>(i)]);
        } catch (const std::exception&) {
            throw InvalidArgument(std::string(what) + " must be three numbers x,y,z (got '" + shown + "')");
        }
    }
    if (!v.allFinite()) throw InvalidArgument(std::string(what) + " must be three finite numbers x,y,z (got '" + shown + "')");
    return v;
}

// 2: the user's arguments; 3: the data; 4: the file system; 5: over the memory budget.
int exit_code(const Error& e) {
    if (dynamic_cast<const ResourceLimit*>(&e)) return 5;
    if (dynamic_cast<const InvalidArgument*>(&e)) return 2;
    if (dynamic_cast<const FormatError*>(&e) || dynamic_cast<const InvalidInput*>(&e)) return 3;
    if (dynamic_cast<const IoError*>(&e)) return 4;
    return 1;
}


namespace {

// The options of the settings of Component's table (core/setting.hpp) that `pick` accepts,
// filling `c`: each under the name of its field in kebab-case, with its earlier spelling as a
// hidden alias (not in --help). Returns the options added, aliases included.
template <typename Component, typename Pick>
std::vector<CLI::Option*> setting_options(CLI::App* app, ReconstructionConfig& c, Pick&& pick) {
    std::vector<CLI::Option*> out;
    Component::for_each_setting([&](const Setting& s, auto member) {
        if (!pick(s)) return;
        auto& value = c.*member;
        out.push_back(app->add_option(s.option(), value, s.help)->capture_default_str());
        if (*s.alias) out.push_back(app->add_option(s.alias, value, "alias of " + s.option())->group(""));
    });
    return out;
}
constexpr auto every = [](const Setting&) { return true; };

}  // namespace

std::vector<CLI::Option*> add_config_options(CLI::App* app, ReconstructionConfig& c, bool with_constant_level) {
    // The paper's parameters, then the guards, the surface's and carving's (--literal excludes them).
    setting_options<SurfaceConfig>(app, c, [&](const Setting& s) { return !s.guard() && (with_constant_level || std::string_view(s.name) != "k"); });
    std::vector<CLI::Option*> guards = setting_options<SurfaceConfig>(app, c, [](const Setting& s) { return s.guard(); });
    for (CLI::Option* o : setting_options<CarvingConfig>(app, c, every)) guards.push_back(o);
    return guards;
}

void add_run_options(CLI::App* app, ReconstructionConfig& c) { setting_options<RunConfig>(app, c, every); }

void add_live_mesh_options(CLI::App* app, ReconstructionConfig& c) { setting_options<LiveMeshConfig>(app, c, every); }

nlohmann::json config_json(const ReconstructionConfig& c) {
    nlohmann::json j = {{"mode", std::string(to_string(c.mode))}};
    ReconstructionConfig::for_each_setting([&](const Setting& s, auto member) { j[s.name] = c.*member; });
    return j;
}

void add_reconstruct_options(CLI::App* app, ReconstructOptions& o) {
    ReconstructionConfig& c = o.config;
    app->add_option("--method", o.method,
                    "default (lidarsurf: the paper's AN+GC with its guards) | paper (the paper as written, --mode selects "
                    "the variant; = --literal) | imls (the paper's baseline)")
        ->capture_default_str();
    const std::vector<CLI::Option*> guards = add_config_options(app, c, true);
    app->add_option("--mode", o.mode, "an+gc | an | cn+gc | cn (Sec. IV-B)")->capture_default_str();
    app->add_option("--origin", o.origin, "Sensor position x,y,z (orients the normals, Eq. 2)")->capture_default_str();
    auto* literal = app->add_flag("--literal", o.literal,
                                  "The paper as written (= --method paper): no planarity or thickness guard, no slab fallback, no "
                                  "truncation, every defined cube, no snapping");
    for (auto* opt : guards) opt->excludes(literal);
    add_run_options(app, c);
    app->add_option("--simd", o.simd, "Vector instructions of the fast path: sse2 | avx2 | avx512 (default: the widest this CPU has; "
                                      "every level gives the same mesh, bit for bit)");
    app->add_option("--format", o.format, "Input format: auto | bin | ply | pcd | xyz")->capture_default_str();
    app->add_option("--bin-fields", o.bin_fields, "float32 values per point in .bin input (KITTI 4, nuScenes 5)")->capture_default_str();
    app->add_option("--intensity-field", o.intensity_field,
                    "Which float32 of a .bin record is the intensity (KITTI and nuScenes 3; -1: none, the mesh gets no intensity)")
        ->capture_default_str();
    auto given = [](bool& flag) { return [&flag](const std::string&) { flag = true; }; };
    app->add_option("--imls-radius", o.imls.radius, "IMLS support radius r in metres (default alpha * k_max)")->each(given(o.imls_radius));
    app->add_option("--imls-k", o.imls.normal_k, "IMLS neighbours for the normals (default N_min)")->each(given(o.imls_k));
    app->add_option("--imls-h", o.imls.bandwidth, "IMLS Gaussian bandwidth h in metres (default r / 3)")->each(given(o.imls_h));
    app->add_option("--imls-truncation", o.imls.truncation_voxels, "IMLS truncation in voxels (default 0 = none, as the paper)")
        ->each(given(o.imls_truncation));
}


void add_recording_options(CLI::App* app, RecordingFlags& o) {
    app->add_option("--topic", o.topic, "A bag's topic of the scans (default: its only PointCloud2 topic, else its Ouster lidar packets)");
    app->add_option("--metadata", o.metadata, "An Ouster sensor's metadata JSON or a Velodyne calibration YAML (the ROS driver's) (default: "
                                              "beside the pcap as X.json or X.yaml, or the bag's metadata topic; a VLP-16, VLP-32C or "
                                              "HDL-32E needs none)");
    app->add_option("--returns", o.returns, "Dual returns (Ouster dual profiles, Velodyne dual mode): first | both")->capture_default_str();
}

RecordingOptions recording_options(const RecordingFlags& o) {
    RecordingOptions r;
    r.topic = o.topic;
    r.metadata = o.metadata;
    r.returns = parse_ouster_returns(o.returns);
    return r;
}

void add_pose_options(CLI::App* app, PoseFlags& o) {
    app->add_option("--pose-topic", o.pose_topic,
                    "A bag's topic of the sensor's poses (nav_msgs/Odometry, geometry_msgs/PoseStamped or PoseWithCovarianceStamped), "
                    "chained through /tf_static to the scans' frame (default: /tf)");
    app->add_option("--fixed-frame", o.fixed_frame, "The world frame of a bag's poses (default: the pose topic's frame; with /tf, odom if "
                                                    "the tree has it, else map)");
    app->add_option("--sensor-frame", o.sensor_frame, "The frame of the scans' points in the bag's tf tree (default: their frame_id)");
}

RecordedPosesOptions recorded_poses_options(const PoseFlags& o) {
    RecordedPosesOptions r;
    r.pose_topic = o.pose_topic;
    r.fixed_frame = o.fixed_frame;
    r.sensor_frame = o.sensor_frame;
    return r;
}

Method resolve_method(const ReconstructOptions& o) {
    Method m;
    m.config = o.config;
    m.config.mode = parse_mode(o.mode);
    if (o.method != "default" && o.method != "paper" && o.method != "imls")
        throw InvalidArgument("unknown method '" + o.method + "' (expected default, paper or imls)");
    if (o.literal || o.method == "paper") m.config.make_paper_literal();
    m.config.validate();
    m.imls = o.method == "imls";
    m.sensor = parse_vec3(o.origin, "--origin");
    m.read.format = parse_point_format(o.format);
    m.read.bin_fields = o.bin_fields;
    m.read.intensity_field = o.intensity_field;
    m.read.max_bytes = static_cast<std::size_t>(m.config.max_memory_mb * 1048576.0);  // the input alone must fit the budget
    if (!o.simd.empty()) set_simd_level(simd_level_from_string(o.simd.c_str()));
    m.imls_config = ImlsConfig::matching(m.config, m.config.threads);
    if (o.imls_radius) {
        m.imls_config.radius = o.imls.radius;
        m.imls_config.bandwidth = o.imls.radius / 3.0;
    }
    if (o.imls_k) m.imls_config.normal_k = o.imls.normal_k;
    if (o.imls_h) m.imls_config.bandwidth = o.imls.bandwidth;
    if (o.imls_truncation) m.imls_config.truncation_voxels = o.imls.truncation_voxels;
    if (m.imls) m.imls_config.validate();  // checked where IMLS runs: a paper run does not fail on IMLS's limits
    return m;
}

std::string method_name(const Method& m) { return m.imls ? "imls" : "mode " + std::string(to_string(m.config.mode)); }

// Runs the chosen method; `summary` receives one line of counts and times.
namespace {

Mesh require_triangles(Mesh mesh, const Method& m, const std::string& summary) {
    if (mesh.empty())
        throw InvalidInput("the reconstruction produced no triangle (" + summary + "); the cloud may be too sparse for n_min=" +
                           format_value(m.config.n_min) + " at voxel size " + format_value(m.config.voxel_size));
    return mesh;
}

}  // namespace

Mesh run_method(const Method& m, const PointCloud& cloud, std::string& summary) {
    return require_triangles(reconstruct_with(m, cloud, m.sensor, &summary), m, summary);
}

Mesh run_method(const Method& m, PointCloud&& cloud, std::string& summary) {
    return require_triangles(reconstruct_with(m, std::move(cloud), m.sensor, &summary), m, summary);
}

std::FILE* report_stream(const fs::path& output) {
    struct stat out {}, std_out {};
    const bool same = ::stat(output.c_str(), &out) == 0 && ::fstat(STDOUT_FILENO, &std_out) == 0 && out.st_dev == std_out.st_dev &&
                      out.st_ino == std_out.st_ino;
    return same ? stderr : stdout;
}

double ms_since(std::chrono::steady_clock::time_point t0) { return 1e3 * seconds_since(t0); }

void write_text(const std::string& path, const std::string& text) {
    AtomicFile file(path);
    file.stream() << text;
    file.commit();
}

void write_json(const std::string& path, const nlohmann::json& j) { write_text(path, j.dump(1) + "\n"); }


std::string extension_of(const fs::path& path) {
    std::string ext = path.extension().string();
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return ext;
}

std::string read_text_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path.string() + ": cannot open for reading");
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw IoError(path.string() + ": read error");
    return ss.str();
}

double resident_mib() {
    long pages = 0, resident = 0;
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        std::fclose(f);
    }
    return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
}
double peak_resident_mib() {
    // Linux's VmHWM (kB), which reset_peak_resident() can reset; the process's whole peak elsewhere.
    std::ifstream f("/proc/self/status");
    for (std::string line; std::getline(f, line);)
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_maxrss) / 1024.0;
}
void reset_peak_resident() {
    std::ofstream f("/proc/self/clear_refs");  // 5: the peak becomes the resident memory now
    if (f) f << "5";
}

}  // namespace lidarsurf::cli
