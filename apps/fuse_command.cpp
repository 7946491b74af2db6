// lidarsurf fuse: a sequence in the KITTI odometry layout (velodyne/NNNNNN.bin and poses.txt, as
// `lidarsurf simulate` writes it) fused into one mesh in the world frame. Each scan is moved by its
// pose and integrated with the position it was seen from, so each part of the surface is oriented
// toward the sensor positions that saw it (docs/method.md, "Sequences"); with --remesh-every the
// mesh is extracted along the way, each extraction redoing only what the new scans reach.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <thread>


#include <nlohmann/json.hpp>

#include "allocator_tuning.hpp"
#include "commands.hpp"
#include "file_roles.hpp"
#include "interrupt.hpp"
#include "progress.hpp"
#include "viewer_page.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/tiles/tile_writer.hpp"
#include "lidarsurf/eval/live_staleness.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/viz/live_server.hpp"

namespace fs = std::filesystem;

namespace lidarsurf::cli {

CLI::App* add_fuse_command(CLI::App& app, FuseOptions& o) {
    CLI::App* f = app.add_subcommand("fuse", "Fuse a sequence of scans with poses (KITTI odometry layout) into one mesh");
    f->add_option("dirs", o.dirs,
                  "Sequence directory: velodyne/000000.bin, ... with poses.txt (sensor-to-world lidar poses, as simulate "
                  "writes), or KITTI's dataset/sequences/NN (poses from dataset/poses/NN.txt and the sequence's calib.txt), "
                  "or a recording (.pcap, ROS 1 .bag, ROS 2 bag) with --poses, its sensor's timestamped trajectory (a bag's own "
                  "/tf or --pose-topic when --poses is not given). "
                  "Several: drives whose poses share one world frame, fused one after the other into one map")
        ->required();
    f->add_option("-o,--output", o.output, "Output mesh (.ply binary by default, .obj), in the world frame")->required();
    f->add_option("--mesh-format", o.mesh_format, "Output format: auto | ply | ply-ascii | obj | glb | glb-draco (binary glTF, Draco-compressed)")->capture_default_str();
    f->add_option("--poses", o.poses,
                  "Pose file (KITTI format, one 3x4 sensor-to-world pose a line), e.g. from your odometry; the lidar's "
                  "unless --calib is given");
    add_recording_options(f, o.recording);
    add_pose_options(f, o.recorded_poses);
    f->add_option("--times", o.times, "A recording's trajectory given as KITTI poses (--poses): their times.txt (seconds, one a line)");
    f->add_option("--deskew", o.deskew, "De-skew a recording's scans with the trajectory, when they have per-point times (0: off)")
        ->capture_default_str();
    f->add_option("--first", o.first, "First frame (of each drive)")->capture_default_str();
    f->add_option("--frames", o.frames, "Frames to fuse of each drive (0 = to the last)")->capture_default_str();
    f->add_option("--step", o.step, "Use every step-th frame")->capture_default_str();
    f->add_option("--calib", o.calib,
                  "KITTI calib.txt: the poses are the left camera's (KITTI's published ones); its Tr: line converts them "
                  "to the lidar's (found in the sequence directory when the poses come from dataset/poses/)");
    f->add_option("--remesh-every", o.remesh_every,
                  "Also extract the mesh after every this many fused frames, printing its time (0 = only at the end)")
        ->capture_default_str();
    f->add_flag("--live", o.live,
                "Keep a live mesh, updated after every scan nearest the sensor first within --live-budget-ms (the "
                "output is still the exact mesh; --json reports update_ms, delta_triangles, live_triangles per frame)");
    f->add_option("--live-budget-ms", o.live_budget_ms, "Time for the live mesh's update after each scan (ms; 0 = everything due)")
        ->capture_default_str();
    f->add_option("--live-check-every", o.live_check_every,
                  "With --live: every this many scans, extract the exact mesh and measure the live mesh against it within "
                  "30 m of the sensor (the share of its area farther than 5 cm; slow: the exact extraction)")
        ->capture_default_str();
    add_live_mesh_options(f, o.reconstruct.config);
    f->add_option("--serve", o.serve,
                  "Watch the map grow in a browser: serve the live view at http://127.0.0.1:PORT/ (implies --live; 0: a free "
                  "port, printed). After the drive the final map stays served until Ctrl-C")
        ->type_name("PORT");
    f->add_option("--bind", o.bind, "With --serve: the address to listen on (e.g. 0.0.0.0 for every interface; the view is open to anyone "
                                    "who reaches it)")
        ->type_name("ADDR")
        ->capture_default_str();
    f->add_option("--rate", o.rate, "Replay the scans at this many a second (0: as fast as they fuse), e.g. 10 for a recorded drive")
        ->type_name("HZ")
        ->capture_default_str();
    f->add_option("--tile-size", o.tiles.tile_size,
                  "Fuse the map in square tiles of this side (metres, e.g. 100), a group of tiles after the other: memory follows "
                  "a group, not the map, and the mesh, written tile by tile, is the one fused whole (docs/method.md, \"Tiles\"); 0: whole")
        ->type_name("METRES")
        ->capture_default_str();
    f->add_option("--tile-halo-cubes", o.tiles.halo_cubes, "With --tile-size: the surface search of a tile reaches this many cubes beyond it")
        ->capture_default_str();
    f->add_option("--tile-group", o.tiles.group,
                  "With --tile-size: tiles fused in one pass over the scans, squares of this many tiles a side (each scan read "
                  "once per group; memory holds a group)")
        ->capture_default_str();
    f->add_option("--json", o.json, "Also write a report: times by stage, and per frame (per tile with --tile-size) the time, voxels and resident memory");
    f->add_flag("-q,--quiet", o.quiet, "No progress report on stderr");
    add_reconstruct_options(f, o.reconstruct);
    f->footer("--origin is the sensor's position in the scan frame (0,0,0 for KITTI's velodyne frame).\n"
              "Poses map the scan frame to the world; with KITTI's published (camera) poses the world is\n"
              "frame 0's velodyne frame. Moving objects are carved away (--carve 0 keeps them).\n\n"
              "Examples:\n  lidarsurf simulate --frames 20 -o town && lidarsurf fuse town -o town.ply --remesh-every 1\n"
              "  lidarsurf fuse dataset/sequences/00 -o kitti00.ply --frames 200\n"
              "  lidarsurf fuse drive --poses drive_poses.txt -o drive.ply\n"
              "  lidarsurf fuse monday tuesday -o street.ply          (two drives of one street, one world frame)\n"
              "  lidarsurf fuse kitti00 -o kitti00.ply --tile-size 100                (flat memory on a drive of any length)\n"
              "  lidarsurf fuse town -o town.ply --serve 8080 --rate 10          (then open http://127.0.0.1:8080/)\n"
              "  lidarsurf fuse drive.pcap --poses drive_tum.txt -o drive.ply     (a recording with the sensor's trajectory)\n"
              "  lidarsurf fuse drive.bag -o drive.ply --fixed-frame map           (poses from the bag's /tf)");
    return f;
}

std::string FuseInput::label(std::size_t n) const {
    const std::string frame = KittiSequence::frame_name(scans[n].frame);
    return drives.size() > 1 ? std::to_string(scans[n].drive + 1) + ":" + frame : frame;
}

PointCloud FuseInput::read(std::size_t n, const PointReadOptions& options, std::vector<Eigen::Vector3f>* no_return) const {
    const Drive& d = drives[scans[n].drive];
    if (d.recording) return d.recording->world_scan(scans[n].frame, no_return);
    PointCloud cloud = read_points(d.seq.scan(scans[n].frame), options);
    if (no_return) *no_return = d.pattern ? empty_rays(*d.pattern, cloud.points, pose(n).linear()) : std::vector<Eigen::Vector3f>{};
    for (Eigen::Vector3d& p : cloud.points) p = pose(n) * p;  // NaN stays NaN
    return cloud;
}

std::string FuseInput::name() const {
    std::string out;
    for (const Drive& d : drives) out += (out.empty() ? "" : " + ") + d.seq.dir.string();
    return out;
}

std::string FuseInput::layout() const {
    std::string out;
    for (const Drive& d : drives) out += (out.empty() ? "" : ", ") + d.where.layout;
    return out;
}

namespace {

// A recording's drive: its scans within the trajectory of --poses (TUM, or KITTI with --times), or
// else of the bag's /tf or --pose-topic.
FuseInput::Drive read_recorded_drive(const FuseOptions& o, const std::string& path, FileRoles& files) {
    if (!o.calib.empty()) throw InvalidArgument("--calib converts KITTI's camera poses of a sequence directory, not a recording's trajectory");
    const auto& rp = o.recorded_poses;
    const bool from_bag = o.poses.empty();
    if (!from_bag && !(rp.pose_topic.empty() && rp.fixed_frame.empty() && rp.sensor_frame.empty()))
        throw InvalidArgument("--poses gives the trajectory: --pose-topic, --fixed-frame and --sensor-frame choose a bag's own instead");
    if (from_bag && !has_recorded_poses(path))
        throw InvalidArgument(path + ": a recording needs the sensor's trajectory to be fused, and this one holds no /tf or pose topic: "
                              "--poses FILE (TUM: t x y z qx qy qz qw, as odometries such as KISS-ICP write; or KITTI poses with "
                              "--times times.txt)");
    RecordedDriveOptions ro;
    ro.recording = recording_options(o.recording);
    ro.deskew = o.deskew != 0;
    std::string source = "--poses";
    Trajectory trajectory;
    if (from_bag) {
        RecordedPoses poses = read_recorded_poses(path, recorded_poses_options(rp), ro.recording);
        source = poses.source + " (" + poses.fixed_frame + " -> " + poses.sensor_frame + ")";
        trajectory = std::move(poses.trajectory);
    } else {
        trajectory = read_trajectory(o.poses, o.times);
    }
    auto drive = std::make_shared<RecordedDrive>(path, std::move(trajectory), ro);
    files.input(path);
    if (!from_bag) files.input(o.poses);
    if (!o.times.empty()) files.input(o.times);
    FuseInput::Drive d{KittiSequence{path}, {}, {}, drive, std::nullopt};
    d.where.poses = from_bag ? path : o.poses;
    d.where.layout = source + " (" + std::to_string(drive->size()) + " of " + std::to_string(drive->recorded()) + " scans within its span" +
                     (drive->deskews() ? ", de-skewed" : "") + ")";
    for (std::size_t k = 0; k < drive->size(); ++k) d.poses.push_back(drive->pose(k));
    return d;
}

}  // namespace

FuseInput read_fuse_input(const FuseOptions& o) {
    if (o.dirs.size() > 1 && !o.poses.empty())
        throw InvalidArgument("--poses names the poses of one drive: with several drives, put each one's in its poses.txt");
    FuseInput in;
    FileRoles files;
    for (const std::string& dir : o.dirs) {
        if (is_recording(dir)) {
            in.drives.push_back(read_recorded_drive(o, dir, files));
            const std::size_t available = in.drives.back().poses.size();
            for (std::size_t i : select_frames(available, o.first, o.frames, o.step, dir)) in.scans.push_back({in.drives.size() - 1, i});
            continue;
        }
        FuseInput::Drive d{KittiSequence{dir}, {}, {}, {}, std::nullopt};
        const std::size_t available = d.seq.frame_count();  // IoError when there is no velodyne/
        d.where = find_sequence_poses(d.seq.dir, o.poses, o.calib);
        d.poses = read_sequence_poses(d.where);
        if (d.poses.size() < available)
            throw InvalidInput(d.where.poses.string() + ": " + std::to_string(d.poses.size()) + " poses for " + std::to_string(available) + " scans");
        for (std::size_t i : select_frames(available, o.first, o.frames, o.step, dir)) in.scans.push_back({in.drives.size(), i});
        d.pattern = sim::drive_pattern(d.seq.sensor());  // a simulated drive: its sensor says which rays returned nothing
        if (d.pattern) files.input(d.seq.sensor());
        files.input_sequence(d.seq.dir);
        files.input(d.where.poses);
        if (!d.where.calib.empty()) files.input(d.where.calib);
        in.drives.push_back(std::move(d));
    }
    files.output(o.output, "-o");
    if (!o.json.empty()) files.output(o.json, "--json");
    files.check();
    return in;
}

nlohmann::json fuse_report_head(const FuseInput& in, const Method& m) {
    return {{"sequence", in.name()}, {"poses", in.layout()}, {"method", method_name(m)}, {"carve", m.config.carve},
            {"config", config_json(m.config)}, {"frames", in.scans.size()}};
}

namespace {

// The live mesh's staleness (docs/method.md, "Live mesh"): within 30 m of the sensor, 5 cm.
constexpr double kStalenessRadius = 30.0, kStalenessTolerance = 0.05;

// Step 1: fuse's options, checked before any file is read.
struct FuseChecked {
    Method method;
    bool serve = false, live = false;
    MeshFormat requested = MeshFormat::Auto;
};
FuseChecked check_fuse_options(const FuseOptions& o) {
    if (o.remesh_every < 0) throw InvalidArgument("--remesh-every must be >= 0");
    if (!std::isfinite(o.live_budget_ms) || o.live_budget_ms < 0 || o.live_check_every < 0)
        throw InvalidArgument("--live-budget-ms and --live-check-every must be >= 0");
    if (!o.live && o.live_check_every > 0) throw InvalidArgument("--live-check-every measures the live mesh: add --live");
    if (o.serve < -1 || o.serve > 65535) throw InvalidArgument("--serve takes a port in [0, 65535] (0: a free one)");
    if (!std::isfinite(o.rate) || o.rate < 0) throw InvalidArgument("--rate must be >= 0 scans a second");
    FuseChecked c;
    c.serve = o.serve >= 0;
    c.live = o.live || c.serve;
    if (!c.serve && o.bind != "127.0.0.1") throw InvalidArgument("--bind is the live view's address: add --serve PORT");
    if (c.serve) require_viewer();
    c.method = resolve_method(o.reconstruct);
    const Method& m = c.method;
    if (m.imls) throw InvalidArgument("fuse: the method must be default or paper (IMLS meshes one scan)");
    if (c.live) LiveMesh::check(m.config.surface(), m.config.live());  // before any scan is read
    if (o.tiles.tile_size != 0) {
        if (c.live || o.remesh_every > 0) throw InvalidArgument("--tile-size meshes each tile once, at its end: not with --live, --serve or --remesh-every");
        o.tiles.validate();
        TilePlan::check(m.config);
    }
    c.requested = parse_mesh_format(o.mesh_format);
    return c;
}

// The map fused whole: the live view's server (listening before the first scan), then one step
// per scan (read, integrate, the live mesh and its stream, the exact mesh when asked), then the
// mesh written and the report.
class WholeMapFusion {
public:
    WholeMapFusion(const FuseOptions& o, const FuseChecked& c, const FuseInput& in)
        : o_(o), m_(c.method), in_(in), live_(c.live), rec_(m_.config, in.pose(0) * m_.sensor), report_(report_stream(o.output)) {
        if (c.serve) start_server();
    }

    // Step 2: scan n.
    void scan(std::size_t n) {
        const std::size_t count = in_.scans.size();
        auto t0 = std::chrono::steady_clock::now();
        const PointCloud cloud = in_.read(n, m_.read, m_.config.carve && m_.config.carve_empty_range > 0 ? &no_return_ : nullptr);  // NaN stays NaN: integrate drops it
        const Eigen::Isometry3d& pose = in_.pose(n);
        read_ms_ += ms_since(t0);
        if (by_tiles()) reaches_.push_back(scan_reach(cloud.points, pose * m_.sensor, !no_return_.empty()));
        const double before = rec_.summary().seconds_insert + rec_.summary().seconds_carve;
        const auto t_update = std::chrono::steady_clock::now();
        rec_.integrate(cloud.points, pose * m_.sensor, no_return_, cloud.intensities);
        nlohmann::json row = {{"frame", in_.scans[n].frame},
                              {"drive", in_.scans[n].drive},
                              {"integrate_ms", 1e3 * (rec_.summary().seconds_insert + rec_.summary().seconds_carve - before)},
                              {"voxels", rec_.summary().voxels}};
        // The exact mesh along the way: for --remesh-every, and for the live mesh's check (one
        // extraction when both fall on this scan).
        auto falls_here = [&](int every) { return every > 0 && ((n + 1) % static_cast<std::size_t>(every) == 0 || n + 1 == count); };
        const bool remesh = falls_here(o_.remesh_every), check = live_ && falls_here(o_.live_check_every);
        if (live_) update_live(n, pose, t_update, row);
        fresh_ = remesh || check;
        if (fresh_) mesh_ = rec_.extract_mesh();
        if (check) {
            const Staleness st = measure_staleness(rec_.live_mesh(), mesh_, pose * m_.sensor, kStalenessRadius, kStalenessTolerance);
            stale_shares_.push_back(st.share());
            row["staleness"] = {{"share", st.share()},
                                {"live_area_m2", st.live_area},
                                {"stale_area_m2", st.stale_area},
                                {"exact_area_m2", st.exact_area},
                                {"covered_share", st.covered_share()}};
        }
        if (remesh) {
            const ReconstructionSummary& s = rec_.summary();
            row["remesh_ms"] = 1e3 * (s.seconds_tsdf + s.seconds_mesh);
            std::fprintf(report_, "frame %s: %zu voxels, vertices evaluated %zu (reused %zu), mesh %zu triangles; tsdf %.1f ms, mesh %.1f ms\n",
                         in_.label(n).c_str(), s.voxels, s.candidate_vertices, s.reused_vertices, s.mesh_triangles, 1e3 * s.seconds_tsdf,
                         1e3 * s.seconds_mesh);
            std::fflush(report_);
        }
        row["resident_mib"] = resident_mib();
        row["map_mib"] = static_cast<double>(rec_.map_bytes()) / 1048576.0;
        per_frame_.push_back(std::move(row));
    }

    // Step 3: the mesh, written whole or not at all.
    void write(MeshFormat format) {
        // The scans' scratch and the old copies of the map's grown arrays, freed but kept by the
        // allocator's tuning for the next scan, go back before the final mesh, whose peak is the run's.
        release_free_memory();
        const auto t0 = std::chrono::steady_clock::now();
        if (by_tiles()) {
            Mesh* const whole = server_ ? &mesh_ : nullptr;  // the live view's final map
            if (whole) *whole = Mesh{};
            summary_ = write_in_tiles(rec_, TilePlan(std::move(reaches_), m_.config, TileConfig{kWriteTileSize}), o_.output, format, whole);
        } else {
            if (!fresh_) mesh_ = rec_.extract_mesh();
            require_fused_triangles(mesh_.triangles.size());
            write_mesh(mesh_, o_.output, format);
            summary_ = rec_.summary();
        }
        write_ms_ = ms_since(t0) - 1e3 * (by_tiles() ? summary_.seconds_tsdf + summary_.seconds_mesh : 0.0);
    }

    // Step 4: the report line, and the JSON report (--json).
    void report() const {
        const ReconstructionSummary& s = summary_;
        std::fprintf(report_, "%s: %zu frames fused (%s, poses from %s); %s; read %.1f ms, write %.1f ms -> %s\n", in_.name().c_str(),
                     in_.scans.size(), method_name(m_).c_str(), in_.layout().c_str(), s.to_string().c_str(), read_ms_, write_ms_,
                     o_.output.c_str());
        if (o_.json.empty()) return;
        nlohmann::json j = fuse_report_head(in_, m_);
        j["points"] = s.points_read;
        j["voxels"] = s.voxels;
        j["carved_voxels"] = s.carved_voxels;
        j["mesh_vertices"] = s.mesh_vertices;
        j["mesh_triangles"] = s.mesh_triangles;
        j["seconds"] = {{"read", read_ms_ / 1e3},        {"insert", s.seconds_insert}, {"carve", s.seconds_carve},
                        {"last_tsdf", s.seconds_tsdf}, {"last_mesh", s.seconds_mesh},  {"write", write_ms_ / 1e3}};
        j["peak_resident_mib"] = peak_resident_mib();
        j["map_mib"] = static_cast<double>(rec_.map_bytes()) / 1048576.0;
        j["per_frame"] = per_frame_;
        if (live_) j["live"] = live_report();
        if (server_) {
            const LiveServer::Stats st = server_->stats();  // at the end of the drive, before the final map is sent
            j["serve"] = {{"port", server_->port()},       {"clients_now", st.clients}, {"clients_accepted", st.accepted},
                          {"clients_dropped", st.dropped}, {"messages", st.messages},  {"bytes", st.bytes},
                          {"wire_bytes", st.wire_bytes}};
        }
        write_json(o_.json, j);
    }

    // With --serve: the page keeps the final map (the exact mesh, block for block in place of the
    // live one) until Ctrl-C.
    void serve_until_interrupted() {
        if (!server_) return;
        const std::size_t count = in_.scans.size();
        server_->finish(split_into_blocks(mesh_, rec_.grid().origin(), m_.config.voxel_size), in_.pose(count - 1),
                        static_cast<std::uint32_t>(count));
        std::fprintf(stderr, "fuse: %s written; the final map is at %s until Ctrl-C\n", o_.output.c_str(), address_.c_str());
        finish_on_interrupt();
        wait_for_exit();
    }

    std::size_t voxels() const { return rec_.summary().voxels; }

private:
    // The output is meshed tile by tile and written as it goes (write_in_tiles), so that the whole
    // mesh is never held: every seeded-surface method without the whole map's component filter.
    bool by_tiles() const { return m_.config.seeded_surface && m_.config.min_component_triangles == 0; }

    // The live view: listening before the first scan (a port in use: exit 4 before any work).
    void start_server() {
        LiveServerConfig sc;
        sc.bind = o_.bind;
        sc.port = o_.serve;
        nlohmann::json data = {{"title", fs::path(in_.drives.front().seq.dir).filename().string() + " (live)"}, {"colour", "height"}, {"live", true}};
        server_ = std::make_unique<LiveServer>(sc, viewer_page(data));
        const bool v6 = o_.bind.find(':') != std::string::npos;
        address_ = "http://" + (v6 ? "[" + o_.bind + "]" : o_.bind) + ":" + std::to_string(server_->port()) + "/";
        std::fprintf(stderr, "fuse: the live view is at %s\n", address_.c_str());
    }

    // The live mesh after scan n (timed from `t_update`, the integration included), sent to the
    // live view's clients.
    void update_live(std::size_t n, const Eigen::Isometry3d& pose, std::chrono::steady_clock::time_point t_update, nlohmann::json& row) {
        MeshDelta delta = rec_.update_mesh(o_.live_budget_ms);
        const double update_ms = ms_since(t_update);
        update_times_.push_back(update_ms);
        row["update_ms"] = update_ms;
        row["live_ms"] = 1e3 * delta.seconds;
        row["delta_blocks"] = delta.changed.size() + delta.removed.size();
        row["delta_triangles"] = delta.triangles();
        row["meshed_blocks"] = delta.meshed_blocks;
        row["pending_blocks"] = delta.pending;
        row["live_triangles"] = rec_.live()->triangle_count();
        if (server_) {
            const auto t_serve = std::chrono::steady_clock::now();
            server_->publish(std::move(delta), pose, static_cast<std::uint32_t>(n + 1));
            row["serve_ms"] = ms_since(t_serve);
        }
    }

    nlohmann::json live_report() const {
        const DirectedError update = summarize(update_times_);
        nlohmann::json r = {{"budget_ms", o_.live_budget_ms},
                            {"growth", m_.config.live_growth},
                            {"range_m", m_.config.live_range},
                            {"reach_blocks", m_.config.live_reach_blocks},
                            {"halo_cubes", m_.config.live_halo_cubes},
                            {"update_ms_median", update.median},
                            {"update_ms_p90", update.p90},
                            {"update_ms_max", update.max}};
        if (!stale_shares_.empty()) {
            r["staleness_radius_m"] = kStalenessRadius;
            r["staleness_tolerance_m"] = kStalenessTolerance;
            const DirectedError stale = summarize(stale_shares_);
            r["staleness_median"] = stale.median;
            r["staleness_max"] = stale.max;
        }
        return r;
    }

    const FuseOptions& o_;
    const Method& m_;
    const FuseInput& in_;
    const bool live_;
    Reconstructor rec_;
    std::FILE* const report_;
    std::unique_ptr<LiveServer> server_;
    std::string address_;
    std::vector<ScanReach> reaches_;  // with by_tiles(): the plan of the final write
    Mesh mesh_;
    bool fresh_ = false;  // whether mesh_ holds every frame fused so far
    double read_ms_ = 0, write_ms_ = 0;
    std::vector<Eigen::Vector3f> no_return_;  // the scan's rays that returned nothing (world directions)
    nlohmann::json per_frame_ = nlohmann::json::array();
    std::vector<double> update_times_, stale_shares_;
    ReconstructionSummary summary_;
};

}  // namespace

int run_fuse(const FuseOptions& o) {
    FuseChecked checked = check_fuse_options(o);
    FuseInput in = read_fuse_input(o);
    // A recording says where its rays start (an Ouster's lidar origin), unless --origin does.
    if (in.drives.front().recording && o.reconstruct.origin == ReconstructOptions{}.origin) checked.method.sensor = in.drives.front().recording->origin();
    in.format = mesh_format_for(o.output, checked.requested);  // .stl: exit 2 now
    if (o.tiles.tile_size != 0) return run_fuse_tiles(o, checked.method, in);

    WholeMapFusion fusion(o, checked, in);
    const std::size_t count = in.scans.size();
    Progress progress("fuse", "frames", count, o.quiet);
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t n = 0; n < count; ++n) {
        if (o.rate > 0) std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                                  std::chrono::duration<double>(static_cast<double>(n) / o.rate)));
        fusion.scan(n);
        progress.update(n + 1, std::to_string(fusion.voxels()) + " voxels");
    }
    progress.finish(std::to_string(fusion.voxels()) + " voxels");
    fusion.write(in.format);
    fusion.report();
    fusion.serve_until_interrupted();
    return 0;
}

}  // namespace lidarsurf::cli
