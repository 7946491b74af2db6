// lidarsurf bench: end-to-end speed (read -> voxel statistics -> TSDF -> marching cubes) per stage,
// as medians over repeated runs, with peak memory, throughput, the ratios to the reference path and
// to IMLS, and the scaling with input size and threads. Without scans it simulates
// HDL-64 frames of the procedural town (the size scaling: one frame at 4 azimuth resolutions);
// with scans, the size scaling subsamples the first one (every 4th and every 2nd point).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>
#include <thread>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "allocator_tuning.hpp"
#include "commands.hpp"
#include "file_roles.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/point_writer.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/simulator.hpp"

#ifndef LIDARSURF_SOURCE_DIR
#define LIDARSURF_SOURCE_DIR ""
#endif

namespace fs = std::filesystem;

namespace lidarsurf::cli {
namespace {

// A row's peak resident memory is its own: the memory an earlier row freed is given back first
// (the allocator keeps some for reuse, apps/allocator_tuning.hpp), then the peak is reset.
void reset_peak_rss() {
    release_free_memory();
    reset_peak_resident();
}

// The fields of the first CPU in /proc/cpuinfo ("model name" -> "AMD EPYC", ...).
std::map<std::string, std::string> cpuinfo() {
    std::map<std::string, std::string> fields;
    std::ifstream f("/proc/cpuinfo");
    std::string line;
    while (std::getline(f, line) && !line.empty()) {  // a blank line ends the first CPU's block
        const auto colon = line.find(':');
        if (colon == std::string::npos || colon == 0) continue;
        const std::string key = line.substr(0, line.find_last_not_of(" \t", colon - 1) + 1);
        const auto start = line.find_first_not_of(' ', colon + 1);
        fields.emplace(key, start == std::string::npos ? "" : line.substr(start));
    }
    return fields;
}
std::string first_line(const std::string& path) {
    std::ifstream f(path);
    std::string line;
    std::getline(f, line);
    return line;
}

// The machine's CPU time so far (/proc/stat, all CPUs, in clock ticks): all of it, and the part
// stolen by the hypervisor (time this VM's CPUs were runnable but ran another guest).
struct CpuTimes {
    double total = 0, steal = 0;
};
CpuTimes cpu_times() {
    std::istringstream in(first_line("/proc/stat"));  // cpu user nice system idle iowait irq softirq steal ...
    std::string label;
    in >> label;
    CpuTimes t;
    double v;
    for (int i = 0; in >> v; ++i) {
        if (i < 8) t.total += v;  // guest time is already counted in user
        if (i == 7) t.steal = v;
    }
    return t;
}

// What the times depend on, for comparing runs across machines: the CPU (model, family/model, the
// clock now), the unified caches of CPU 0, and the CPU pressure (PSI "some" avg60: the share of
// time a runnable task of this machine waited for a CPU; in a VM it does not see other guests).
std::string machine_description() {
    auto cpu = cpuinfo();
    std::ostringstream out;
    out << (cpu["model name"].empty() ? "unknown CPU" : cpu["model name"]);
    if (!cpu["cpu family"].empty()) out << " (family " << cpu["cpu family"] << " model " << cpu["model"] << ")";
    const double mhz = std::strtod(cpu["cpu MHz"].c_str(), nullptr);  // 0 when absent or unreadable
    if (mhz > 0) out << ", " << std::lround(mhz) << " MHz";
    for (int i = 0; i < 8; ++i) {
        const std::string dir = "/sys/devices/system/cpu/cpu0/cache/index" + std::to_string(i) + "/";
        if (first_line(dir + "type") != "Unified") continue;
        out << ", L" << first_line(dir + "level") << " " << first_line(dir + "size");
    }
    const std::string psi = first_line("/proc/pressure/cpu");  // some avg10=.. avg60=.. avg300=.. total=..
    const auto at = psi.find("avg60=");
    if (at != std::string::npos) out << "; CPU pressure (PSI) " << psi.substr(at + 6, psi.find(' ', at) - at - 6) << " %";
    return out.str();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

enum class Path { Fast, Reference, Imls };
const char* path_name(Path p) { return p == Path::Fast ? "fast" : (p == Path::Reference ? "reference" : "imls"); }

// One row of the table: stage times of `repeat` runs on one scan.
struct Row {
    std::string scan, path;
    std::size_t points = 0, triangles = 0;
    int threads = 0, repeat = 0;
    // Per-stage times (ms) of every run. IMLS: insert = normals, tsdf = implicit function.
    std::vector<double> read, insert, tsdf, mesh, total;
    // The TSDF stage by phase (ms per run, in SeededTiming::named() order; fast path with the
    // seeded surface only, else empty).
    std::array<std::vector<double>, SeededTiming::kPhases> phases;
    double peak_rss = -1;
    double warmup_total = -1;  // the untimed first run's total (ms; fast path), -1 without one

    double median_total() const { return median(total); }
    double min_total() const { return *std::min_element(total.begin(), total.end()); }
};

// A scan to time, and how to read it: the scans a user passes are read with the command's format
// options, the bench's own inputs (simulated frames, the KITTI frames beside the source tree,
// subsampled copies) as the KITTI .bin files they are.
struct Input {
    fs::path path;
    std::string label;
    PointReadOptions read;
};

// Fast-path rows start with one run left out of the statistics: reset_peak_rss() has just given
// the freed memory back, so a row's first run faults its memory in again (54-96 ms, median 64,
// against 45-63, median 50, for the next runs of a KITTI frame),
// a cost a process pays once, not per frame. The reference path and IMLS (~1 s a run) keep every
// run.
Row run_row(const Input& in, Path path, const Method& method, int threads, int repeat) {
    Row row;
    row.scan = in.label;
    row.path = path_name(path);
    row.threads = threads;
    row.repeat = repeat;
    reset_peak_rss();
    const int warmup = path == Path::Fast ? 1 : 0;
    for (int r = -warmup; r < repeat; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        const PointCloud cloud = read_points(in.path, in.read);
        const double read_ms = ms_since(t0);
        double insert = 0, tsdf = 0, mesh_ms = 0;
        Mesh mesh;
        if (path == Path::Imls) {
            ImlsConfig ic = method.imls_config;
            ic.threads = threads;
            ImlsSummary s;
            mesh = reconstruct_imls(cloud, method.sensor, ic, &s);
            insert = 1e3 * s.seconds_normals;
            tsdf = 1e3 * s.seconds_field;
            mesh_ms = 1e3 * s.seconds_mesh;
        } else {
            ReconstructionConfig c = method.config;
            c.threads = threads;
            Reconstructor rec(c, method.sensor);
            rec.integrate(cloud);
            mesh = rec.extract_mesh(path == Path::Fast ? Evaluation::Fast : Evaluation::Reference);
            insert = 1e3 * rec.summary().seconds_insert;
            tsdf = 1e3 * rec.summary().seconds_tsdf;
            mesh_ms = 1e3 * rec.summary().seconds_mesh;
            if (path == Path::Fast && c.seeded_surface && r >= 0) {
                const auto named = rec.summary().tsdf_phases.named();
                for (std::size_t i = 0; i < named.size(); ++i) row.phases[i].push_back(1e3 * named[i].second);
            }
        }
        if (r < 0) {
            row.warmup_total = read_ms + insert + tsdf + mesh_ms;
            continue;
        }
        row.points = cloud.points.size();
        row.triangles = mesh.triangles.size();
        row.read.push_back(read_ms);
        row.insert.push_back(insert);
        row.tsdf.push_back(tsdf);
        row.mesh.push_back(mesh_ms);
        row.total.push_back(read_ms + insert + tsdf + mesh_ms);
    }
    row.peak_rss = peak_resident_mib();
    return row;
}

// Incremental re-meshing: `scan` split into `sectors` azimuth sectors around the
// sensor (as a spinning lidar delivers its packets), each integrated and followed by an
// extraction. Row "fast": a new Reconstructor per sector on everything so far (no reuse); row
// "reuse": one Reconstructor for the revolution, whose extractions redo only what the new
// sector can reach. Times are the sums over the revolution's sectors; the final meshes are
// compared (they must be the same).
std::vector<Row> run_sector_rows(const Input& in, const Method& method, int threads, int repeat, int sectors) {
    const PointCloud cloud = read_points(in.path, in.read);
    std::vector<PointCloud> parts(static_cast<std::size_t>(sectors));
    for (const Eigen::Vector3d& p : cloud.points) {
        const Eigen::Vector3d d = p - method.sensor;
        const double azimuth = std::atan2(d.y(), d.x()) + M_PI;  // [0, 2 pi]
        const int s = std::clamp(static_cast<int>(azimuth / (2 * M_PI) * sectors), 0, sectors - 1);
        parts[static_cast<std::size_t>(s)].points.push_back(p);
    }
    ReconstructionConfig c = method.config;
    c.threads = threads;
    const std::string label = std::to_string(sectors) + " sectors";
    std::vector<Row> rows(2);
    Mesh last[2];
    for (int reuse = 0; reuse < 2; ++reuse) {
        Row& row = rows[static_cast<std::size_t>(reuse)];
        row.scan = label;
        row.path = reuse ? "reuse" : "fast";
        row.threads = threads;
        row.repeat = repeat;
        row.points = cloud.points.size();
        reset_peak_rss();
        for (int r = 0; r < repeat; ++r) {
            double insert = 0, tsdf = 0, mesh_ms = 0;
            std::optional<Reconstructor> rec;
            PointCloud so_far;
            for (const PointCloud& part : parts) {
                if (reuse) {
                    if (!rec) rec.emplace(c, method.sensor);
                    rec->integrate(part);
                } else {
                    so_far.points.insert(so_far.points.end(), part.points.begin(), part.points.end());
                    rec.emplace(c, method.sensor);
                    rec->integrate(so_far);
                }
                if (part.points.empty()) continue;
                last[reuse] = rec->extract_mesh();
                insert += 1e3 * rec->summary().seconds_insert;  // reuse: cumulative over the integrations
                tsdf += 1e3 * rec->summary().seconds_tsdf;
                mesh_ms += 1e3 * rec->summary().seconds_mesh;
            }
            if (reuse) insert = 1e3 * rec->summary().seconds_insert;
            row.triangles = last[reuse].triangles.size();
            row.read.push_back(0);
            row.insert.push_back(insert);
            row.tsdf.push_back(tsdf);
            row.mesh.push_back(mesh_ms);
            row.total.push_back(insert + tsdf + mesh_ms);
        }
        row.peak_rss = peak_resident_mib();
    }
    if (last[0].vertices != last[1].vertices || last[0].triangles != last[1].triangles)
        throw Error("bench: the incremental re-mesh differs from the mesh of one extraction (a bug; please report it)");
    return rows;
}

std::string format_rows(const std::vector<Row>& rows, bool ratios) {
    std::ostringstream out;
    char buf[320];
    std::snprintf(buf, sizeof buf, "%-16s %8s %-9s %3s %7s %7s %8s %7s %9s %9s %7s %8s%s\n", "scan", "points", "path", "thr",
                  "read", "insert", "tsdf", "mesh", "total", "min", "Mpts/s", "peakMiB", ratios ? "  x fast" : "");
    out << buf;
    const Row* fast = nullptr;  // the fast-path row of the current scan (rows come grouped by scan, fast first)
    for (const Row& r : rows) {
        if (r.path == "fast") fast = &r;
        const double t = r.median_total();
        std::snprintf(buf, sizeof buf, "%-16s %8zu %-9s %3d %7.1f %7.1f %8.1f %7.1f %9.1f %9.1f %7.2f %8.0f", r.scan.c_str(),
                      r.points, r.path.c_str(), r.threads, median(r.read), median(r.insert), median(r.tsdf), median(r.mesh), t,
                      r.min_total(), 1e-3 * static_cast<double>(r.points) / t, r.peak_rss);
        out << buf;
        if (ratios && fast && fast->scan == r.scan) {
            std::snprintf(buf, sizeof buf, " %8.2f", t / fast->median_total());
            out << buf;
        }
        out << "\n";
    }
    return out.str();
}

// The TSDF stage of `rows` (which have phases): medians per phase, and the stage's median.
std::string format_phases(const std::vector<Row>& rows) {
    std::ostringstream out;
    char buf[320];
    constexpr std::array<int, SeededTiming::kPhases> width{7, 9, 11, 7, 7};  // each phase's column
    std::snprintf(buf, sizeof buf, "%-16s %3s", "scan", "thr");
    out << buf;
    for (std::size_t i = 0; i < width.size(); ++i) {
        std::string name = SeededTiming{}.named()[i].first;
        std::replace(name.begin(), name.end(), '_', ' ');
        std::snprintf(buf, sizeof buf, " %*s", width[i], name.c_str());
        out << buf;
    }
    out << "     tsdf\n";
    for (const Row& r : rows) {
        std::snprintf(buf, sizeof buf, "%-16s %3d", r.scan.c_str(), r.threads);
        out << buf;
        for (std::size_t i = 0; i < width.size(); ++i) {
            std::snprintf(buf, sizeof buf, " %*.1f", width[i], median(r.phases[i]));
            out << buf;
        }
        std::snprintf(buf, sizeof buf, " %8.1f\n", median(r.tsdf));
        out << buf;
    }
    return out.str();
}

nlohmann::json to_json(const Row& r) {
    nlohmann::json j = {{"scan", r.scan},           {"path", r.path},           {"points", r.points},
            {"threads", r.threads},     {"repeat", r.repeat},       {"triangles", r.triangles},
            {"read_ms", median(r.read)}, {"insert_ms", median(r.insert)}, {"tsdf_ms", median(r.tsdf)},
            {"mesh_ms", median(r.mesh)}, {"total_ms", r.median_total()},  {"total_min_ms", r.min_total()},
            {"peak_rss_mib", r.peak_rss}, {"total_runs_ms", r.total}};
    if (r.warmup_total >= 0) j["warmup_total_ms"] = r.warmup_total;
    if (!r.phases[0].empty()) {
        nlohmann::json phases;
        for (std::size_t i = 0; i < r.phases.size(); ++i) phases[SeededTiming{}.named()[i].first] = median(r.phases[i]);
        j["tsdf_phases_ms"] = phases;
    }
    return j;
}

// The scans of the table (`frames`) and of the size scaling (`sizes`, smallest first), whose third
// is a full HDL-64 frame: the one the thread-scaling and sector rows use.
struct Inputs {
    std::vector<Input> frames, sizes;
};
constexpr std::size_t kFullSize = 2;

// Simulated town frames (sensor frame, KITTI .bin) in `dir`: `frames` frames spread over a
// 100-frame drive, and the middle frame at 4 azimuth resolutions for the size scaling.
Inputs simulate_inputs(const fs::path& dir, int frames) {
    Inputs in;
    sim::SceneConfig scene;  // town, seed 1: the benchmark sequence of docs/benchmarks.md
    const sim::World world = sim::make_world(scene);
    sim::SimulatorConfig sc;
    sc.gt_beams = 0;
    const sim::Simulator simulator(world, sc);
    for (int i = 0; i < frames; ++i) {
        const std::size_t index = static_cast<std::size_t>((i + 1) * 100 / (frames + 1));
        char name[64];
        std::snprintf(name, sizeof name, "town_%03zu.bin", index);
        write_points(simulator.frame(index).scan, dir / name);
        in.frames.push_back({dir / name, std::string("town ") + std::to_string(index), {}});
    }
    // Same scene and beams, azimuth step 0.72 / 0.36 / 0.18 / 0.09 deg: ~30k / 60k / 120k / 240k points.
    for (double step : {0.72, 0.36, 0.18, 0.09}) {
        sim::SimulatorConfig s2 = sc;
        s2.sensor.azimuth_step_deg = step;
        const sim::Simulator sized(world, s2);
        char name[64];
        std::snprintf(name, sizeof name, "town_050_az%.2f.bin", step);
        write_points(sized.frame(50).scan, dir / name);
        char label[64];
        std::snprintf(label, sizeof label, "az %.2f deg", step);
        in.sizes.push_back({dir / name, label, {}});
    }
    return in;
}

// The size scaling on the user's scans: every 4th and every 2nd point of the first (KITTI .bin
// copies in `dir`), then the scan itself, which the thread-scaling and sector rows use.
void add_subsampled_sizes(Inputs& in, const fs::path& dir) {
    const Input& scan = in.frames.front();
    const PointCloud cloud = read_points(scan.path, scan.read);
    for (const std::size_t step : {4, 2}) {
        PointCloud part;
        for (std::size_t i = 0; i < cloud.points.size(); i += step) part.points.push_back(cloud.points[i]);
        const fs::path path = dir / ("every" + std::to_string(step) + ".bin");
        write_points(part, path);
        in.sizes.push_back({path, scan.label + " 1/" + std::to_string(step), {}});
    }
    in.sizes.push_back(scan);
}

}  // namespace

CLI::App* add_bench_command(CLI::App& app, BenchOptions& o) {
    CLI::App* b = app.add_subcommand("bench", "End-to-end speed per stage: fast path vs reference vs IMLS, size and thread scaling");
    b->add_option("scans", o.scans, "Scans to time (default: simulated HDL-64 town frames, and the real KITTI frames of ../shared/data/kitti beside the source tree when present); the size scaling then subsamples the first");
    b->add_option("--repeat", o.repeat, "Runs per row for the fast path (median reported)")->capture_default_str();
    b->add_option("--slow-repeat", o.slow_repeat, "Runs per row for the reference path and IMLS")->capture_default_str();
    b->add_option("--frames", o.frames, "Simulated frames when no scan is given")->capture_default_str();
    b->add_flag("--no-reference", o.no_reference, "Skip the reference path");
    b->add_flag("--no-imls", o.no_imls, "Skip IMLS");
    b->add_flag("--no-scaling", o.no_scaling, "Skip the size and thread scaling tables and the incremental re-meshing table");
    b->add_option("--json", o.json, "Also write every row (all run times) as JSON")->each([&o](const std::string&) { o.json_given = true; });
    add_reconstruct_options(b, o.reconstruct);
    b->footer("Example:\n  lidarsurf bench                      # simulated town frames\n"
              "  lidarsurf bench ../shared/data/kitti/*.bin --repeat 11");
    return b;
}

int run_bench(const BenchOptions& o) {
    if (o.repeat < 1 || o.repeat > 1000) throw InvalidArgument("--repeat must be in [1, 1000]");
    if (o.slow_repeat < 1 || o.slow_repeat > 1000) throw InvalidArgument("--slow-repeat must be in [1, 1000]");
    if (o.frames < 1 || o.frames > 100) throw InvalidArgument("--frames must be in [1, 100]");
    const Method method = resolve_method(o.reconstruct);
    const int threads = method.config.threads;  // 0 = all cores
    if (!o.no_imls && !method.imls) {
        try {
            method.imls_config.validate();
        } catch (const InvalidArgument& e) {
            throw InvalidArgument(std::string("the IMLS rows: ") + e.what() + " (or skip them with --no-imls)");
        }
    }
    FileRoles files;
    for (const std::string& s : o.scans) files.input(s);
    if (o.json_given) files.output(o.json, "--json");
    files.check();

    Inputs in;
    // Scratch files (simulated and subsampled scans): removed at the end, on an error or a signal.
    const AtomicDirectory scratch(fs::temp_directory_path() / "lidarsurf-bench");
    const fs::path& tmp = scratch.path();
    if (o.scans.empty()) {
        const ReconstructOptions defaults;
        if (o.reconstruct.format != defaults.format || o.reconstruct.bin_fields != defaults.bin_fields)
            throw InvalidArgument("--format and --bin-fields describe the scans you pass; without scans, bench reads its own "
                                  "(simulated town frames and the KITTI frames beside the source tree)");
        std::fprintf(stderr, "bench: simulating %d town frames and 4 resolutions in %s\n", o.frames, tmp.c_str());
        in = simulate_inputs(tmp, o.frames);
        const std::size_t simulated = in.frames.size();
        // The real KITTI frames beside the source tree (../shared/data/kitti, see its README), when
        // present: the simulated town is an easier scene than a real street (docs/benchmarks.md).
        const fs::path kitti = fs::path(LIDARSURF_SOURCE_DIR) / ".." / "shared" / "data" / "kitti";
        std::error_code ec;
        for (std::size_t i = 0; !std::string(LIDARSURF_SOURCE_DIR).empty(); ++i) {
            const std::string name = KittiSequence::frame_name(i);
            const fs::path scan = kitti / (name + ".bin");
            if (!fs::is_regular_file(scan, ec)) break;
            in.frames.push_back({scan, "kitti " + name, {}});
        }
        if (in.frames.size() > simulated)
            std::fprintf(stderr, "bench: and %zu real KITTI frames from %s\n", in.frames.size() - simulated, kitti.c_str());
    } else {
        for (const std::string& s : o.scans) {
            if (!fs::is_regular_file(s)) throw IoError("cannot read '" + s + "': not a file");
            in.frames.push_back({s, fs::path(s).filename().string(), method.read});
        }
    }
    {
        const CpuTimes start = cpu_times();
        std::vector<Row> rows, size_rows, thread_rows, sector_rows;
        std::string sector_scan;  // the label of the scan the incremental table splits
        for (const Input& scan : in.frames) {
            std::fprintf(stderr, "bench: %s\n", scan.label.c_str());
            rows.push_back(run_row(scan, Path::Fast, method, threads, o.repeat));
            if (!o.no_reference) rows.push_back(run_row(scan, Path::Reference, method, threads, o.slow_repeat));
            if (!o.no_imls) rows.push_back(run_row(scan, Path::Imls, method, threads, o.slow_repeat));
        }
        if (!o.no_scaling) {
            if (in.sizes.empty()) {  // the user's scans
                add_subsampled_sizes(in, tmp);
            }
            for (const Input& scan : in.sizes) size_rows.push_back(run_row(scan, Path::Fast, method, threads, o.repeat));
            const Input& mid = in.sizes[kFullSize];
            for (int t : {1, 2}) thread_rows.push_back(run_row(mid, Path::Fast, method, t, o.repeat));
            if (method.config.seeded_surface) {
                std::fprintf(stderr, "bench: %s in sectors\n", mid.label.c_str());
                sector_rows = run_sector_rows(mid, method, threads, o.slow_repeat, 10);
                sector_scan = mid.label;
            }
        }

        std::printf("lidarsurf bench: mode %s, alpha %.3g m, tau %.3g, N_min %d, k_max %d; times in ms, median of %d runs "
                    "after one untimed (reference and IMLS: %d, none untimed), min = fastest run; %u hardware threads\n",
                    std::string(to_string(method.config.mode)).c_str(), method.config.voxel_size, method.config.tau,
                    method.config.n_min, method.config.k_max, o.repeat, o.slow_repeat, std::thread::hardware_concurrency());
        // The share of the machine's CPU time the hypervisor stole during the run: on a shared host
        // another tenant's load shows there (and not in the PSI above), and inflates every time.
        const CpuTimes end = cpu_times();
        const double steal = end.total > start.total ? 100.0 * (end.steal - start.steal) / (end.total - start.total) : 0.0;
        char steal_text[64];
        std::snprintf(steal_text, sizeof steal_text, "; CPU time stolen by the hypervisor during the run %.1f %%", steal);
        // How the allocator was set (apps/allocator_tuning.hpp): huge pages are worth a few percent
        // of a frame, so the table says which.
        const std::string machine = machine_description() + steal_text + "; SIMD " + to_string(simd_level()) +
                                    (o.allocator.empty() ? "" : "; " + o.allocator);
        std::printf("machine: %s\n", machine.c_str());
        std::printf("total = read + insert + tsdf + mesh (IMLS: insert = normals, tsdf = implicit function)\n\n");
        std::fputs(format_rows(rows, true).c_str(), stdout);
        std::vector<Row> phased;  // the fast rows, and the thread-scaling ones
        for (const std::vector<Row>* group : {&rows, &thread_rows})
            for (const Row& r : *group)
                if (!r.phases[0].empty()) phased.push_back(r);
        if (!phased.empty()) {
            std::printf("\nthe fast path's tsdf by phase (medians, ms): setup = packing and seeds; seed wave and later waves\n"
                        "= their parallel parts; serial = between the waves; field = ordering the defined vertices and sorting the cubes:\n");
            std::fputs(format_phases(phased).c_str(), stdout);
        }
        if (!size_rows.empty()) {
            std::printf("\nscaling with input size (fast path):\n");
            std::fputs(format_rows(size_rows, false).c_str(), stdout);
            std::printf("\nscaling with threads (fast path):\n");
            std::fputs(format_rows(thread_rows, false).c_str(), stdout);
            const double s = thread_rows[0].median_total() / thread_rows[1].median_total();
            std::printf("speed-up 1 -> 2 threads: %.2fx\n", s);
        }
        if (!sector_rows.empty()) {
            std::printf("\nincremental re-meshing, %s delivered in 10 azimuth sectors, a mesh after each (sums over the\n"
                        "revolution; fast = a new reconstruction of all sectors so far each time, reuse = one Reconstructor\n"
                        "that re-evaluates only what the new sector reaches; the same final mesh):\n",
                        sector_scan.c_str());
            std::fputs(format_rows(sector_rows, true).c_str(), stdout);
        }
        if (o.json_given) {
            nlohmann::json j;
            j["machine"] = machine;
            for (const char* key : {"rows", "sizes", "threads", "sectors"}) j[key] = nlohmann::json::array();
            for (const Row& r : sector_rows) j["sectors"].push_back(to_json(r));
            for (const Row& r : rows) j["rows"].push_back(to_json(r));
            for (const Row& r : size_rows) j["sizes"].push_back(to_json(r));
            for (const Row& r : thread_rows) j["threads"].push_back(to_json(r));
            write_text(o.json, j.dump(2) + "\n");
        }
    }
    return 0;
}

}  // namespace lidarsurf::cli
