// lidarsurf simulate: a built-in or loaded scene scanned by a sensor along a drive, written in the
// KITTI odometry layout (or one scan to one file).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <Eigen/Geometry>

#include "commands.hpp"
#include "file_roles.hpp"
#include "progress.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_writer.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/simulator.hpp"

namespace fs = std::filesystem;

namespace lidarsurf::cli {
namespace {


sim::SensorModel load_sensor(const std::string& spec) {
    if (extension_of(spec) == ".json") return sim::SensorModel::from_json(read_text_file(spec));
    return sim::SensorModel::preset(spec);
}

// The message for a view that sees nothing: a scan with no point is no scan.
std::string no_return_message(const std::string& sensor) {
    return "the sensor (" + sensor + ") sees nothing from where it stands: no ray returns within its range; nothing was written";
}

void write_binary(const fs::path& path, const std::vector<float>& values) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float)));
    if (!out) throw IoError(path.string() + ": cannot write");
}

// With sweeps that take time: the frames' times (KITTI's times.txt, s from the drive's start) and
// the sensor's trajectory every 10 ms as TUM (t x y z qx qy qz qw) to the last sweep's end.
void write_sweep_times(const sim::Simulator& simulator, const std::vector<double>& frame_times, const fs::path& dir) {
    std::ostringstream times, tum;
    times << std::setprecision(17);
    tum << std::setprecision(17);
    for (double t : frame_times) times << t << "\n";
    const double end = (frame_times.empty() ? 0.0 : frame_times.back()) + simulator.config().sweep_seconds;
    for (int k = 0; k * 0.01 <= end + 0.01; ++k) {
        const Eigen::Isometry3d p = simulator.pose_at_time(k * 0.01);
        const Eigen::Quaterniond q(p.linear());
        tum << k * 0.01 << " " << p.translation().x() << " " << p.translation().y() << " " << p.translation().z() << " " << q.x() << " "
            << q.y() << " " << q.z() << " " << q.w() << "\n";
    }
    write_text((dir / "times.txt").string(), times.str());
    write_text((dir / "poses_tum.txt").string(), tum.str());
}

sim::World load_world(const SimulateOptions& o) {
    const std::string ext = extension_of(o.scene);
    if (ext == ".ply" || ext == ".obj") {
        sim::World w;
        w.static_mesh = read_mesh(o.scene);
        if (w.static_mesh.triangles.empty()) throw InvalidInput(o.scene + ": the scene mesh has no triangle");
        if (o.from.empty()) throw InvalidArgument("a mesh scene needs --from x,y,z (the ground point where the drive starts)");
        const Eigen::Vector3d from = parse_vec3(o.from, "--from");
        const Eigen::Vector3d to = o.to.empty() ? Eigen::Vector3d(from + Eigen::Vector3d(10, 0, 0)) : parse_vec3(o.to, "--to");
        if ((to - from).norm() < 1e-6) throw InvalidArgument("--to must differ from --from");
        w.path = {from, to};
        w.config.ego_speed = o.speed;
        return w;
    }
    sim::SceneConfig sc;
    sc.kind = sim::parse_scene_kind(o.scene);
    sc.seed = o.seed;
    sc.length = o.length;
    sc.moving_cars = o.moving_cars;
    sc.pedestrians = o.pedestrians;
    sc.cyclists = o.cyclists;
    sc.leaving_cars = o.leaving_cars;
    sc.parking_cars = o.parking_cars;
    sc.dark_cars = o.dark_cars;
    sc.ego_speed = o.speed;
    sc.weave = o.weave;
    return sim::make_world(sc);
}

// The files the command reads (a scene mesh, a sensor file) and writes, checked before any work.
void check_files(const SimulateOptions& o, bool single) {
    FileRoles files;
    const std::string scene_ext = extension_of(o.scene);
    if (scene_ext == ".ply" || scene_ext == ".obj") files.input(o.scene);
    if (extension_of(o.sensor) == ".json") files.input(o.sensor);
    if (single) {
        files.output(o.output, "-o");
        if (o.gt_given) {
            if (!o.gt.empty() && !is_point_extension(o.gt))
                throw InvalidArgument("--gt '" + o.gt + "': unknown point-file extension (lidarsurf writes .bin, .ply, .pcd, .xyz, .txt, .csv)");
            files.output(o.gt, "--gt");
        }
    } else {
        files.output_directory(o.output, "-o");
    }
    files.check();
}

int simulate_demo(const SimulateOptions& o) {
    if (!is_point_extension(o.output)) throw InvalidArgument("the demo scene writes one scan: give -o a point file (.bin, .ply, ...)");
    check_files(o, true);
    const auto world = sim::AnalyticScene::demo();
    const sim::SensorModel sensor = load_sensor(o.sensor);
    const PointCloud cloud = sim::simulate_scan(world, sensor, Eigen::Vector3d::Zero(), o.seed);
    if (cloud.points.empty()) throw InvalidInput(no_return_message(o.sensor));
    if (!o.gt.empty()) {
        const sim::SensorModel gts = sim::SensorModel::ground_truth_for(sensor, o.gt_beams > 0 ? o.gt_beams : 316);
        const PointCloud gt = sim::simulate_scan(world, gts, Eigen::Vector3d::Zero(), o.seed);
        write_points(gt, o.gt);
        std::printf("ground truth: %zu noise-free points (%zu beams) -> %s\n", gt.points.size(), gts.elevations_deg.size(), o.gt.c_str());
    }
    write_points(cloud, o.output);
    std::printf("simulated %zu points (scene demo, %s at 0,0,0, seed %llu) -> %s\n", cloud.points.size(), sensor.name.c_str(),
                static_cast<unsigned long long>(o.seed), o.output.c_str());
    return 0;
}

}  // namespace

CLI::App* add_simulate_command(CLI::App& app, SimulateOptions& o) {
    auto* sc = app.add_subcommand("simulate", "Simulate lidar scans of a scene along a drive (KITTI odometry layout)");
    sc->footer(
        "Examples:\n"
        "  lidarsurf simulate -o town_seq                      (100 HDL-64E frames of the town)\n"
        "  lidarsurf simulate --scene offroad --sensor vlp16 --frames 20 -o offroad_seq\n"
        "  lidarsurf simulate --frames 1 -o one.bin --gt one_gt.bin\n"
        "  lidarsurf simulate --scene my_scene.ply --from 0,0,0 --to 50,0,0 --sensor my_sensor.json -o seq\n"
        "  lidarsurf simulate --scene demo -o scan.bin --gt gt.bin   (the analytic test scene)\n"
        "A directory gets velodyne/NNNNNN.bin (sensor frame), gt/NNNNNN.bin (co-located noise-free\n"
        "ground-truth sensor), poses.txt (sensor-to-world, 3x4 row-major), scene.ply, objects/NNNNNN.ply\n"
        "(moving cars at each frame's time), sensor.json and, with --dark-cars, dark.ply (the surfaces that return no ray). A point file gets one scan (mid-drive).\n");
    sc->add_option("--scene", o.scene, "town | offroad | demo | a .ply/.obj scene mesh")->capture_default_str();
    sc->add_option("--sensor", o.sensor, "hdl64 | vlp16 | hdl32 | os1-128 | gt316 | a .json sensor file")->capture_default_str();
    sc->add_option("--frames", o.frames, "Frames, equi-sampled along the drive")->capture_default_str();
    sc->add_option("-o,--output", o.output, "Output directory (KITTI layout), or one point file")->required();
    sc->add_option("--gt", o.gt, "With a point-file output: also write its ground-truth scan here")->each([&o](const std::string&) {
        o.gt_given = true;
    });
    sc->add_option("--gt-beams", o.gt_beams, "Beams of the ground-truth sensor (0 = none)")->capture_default_str();
    sc->add_option("--seed", o.seed, "Scene and noise seed")->capture_default_str();
    sc->add_option("--length", o.length, "Street / track length in metres (town, offroad)")->capture_default_str();
    sc->add_option("--moving-cars", o.moving_cars, "Cars driving in the opposite lane (town)")->capture_default_str();
    sc->add_option("--pedestrians", o.pedestrians, "People walking the sidewalks (town)")->capture_default_str();
    sc->add_option("--cyclists", o.cyclists, "Cyclists riding beside the opposite lane (town)")->capture_default_str();
    sc->add_option("--leaving-cars", o.leaving_cars, "Cars parked at the curb that drive off mid-drive (town)")->capture_default_str();
    sc->add_option("--parking-cars", o.parking_cars, "Cars that drive in and park at the curb mid-drive (town)")->capture_default_str();
    sc->add_option("--dark-cars", o.dark_cars, "Cars parked all along whose hull is too dark to return a ray (town)")->capture_default_str();
    sc->add_option("--speed", o.speed, "Speed of the sensor rig along the drive, m/s (sets the frame times)")->capture_default_str();
    sc->add_option("--weave", o.weave, "Town: the drive weaves this many metres to either side of its lane (a 40 m sine; 0 = straight)")
        ->capture_default_str();
    sc->add_option("--sweep-seconds", o.sweep_seconds,
                   "The sensor turns once in this time while the rig moves (0: each frame at one instant); adds times/NNNNNN.bin "
                   "(float32 s after the frame's time per point), times.txt and poses_tum.txt (every 10 ms)")
        ->capture_default_str();
    sc->add_flag("-q,--quiet", o.quiet, "No progress report on stderr");
    sc->add_option("--from", o.from, "Mesh scene: ground point where the drive starts, x,y,z");
    sc->add_option("--to", o.to, "Mesh scene: ground point where it ends (default 10 m along +x)");
    return sc;
}

int run_simulate(const SimulateOptions& o) {
    if (o.scene == "demo") return simulate_demo(o);
    sim::SimulatorConfig cfg;
    cfg.frames = o.frames;
    cfg.sensor = load_sensor(o.sensor);
    cfg.gt_beams = o.gt_beams;
    cfg.seed = o.seed;
    cfg.sweep_seconds = o.sweep_seconds;
    const bool single = is_point_extension(o.output);
    if (single && o.sweep_seconds > 0) throw InvalidArgument("--sweep-seconds writes per-point times: give -o a directory");
    if (single) cfg.frames = 1;
    if (!single && !o.gt.empty()) throw InvalidArgument("--gt goes with a point-file output; a directory gets gt/ itself");
    if (single && o.gt.empty()) cfg.gt_beams = 0;
    cfg.validate();
    check_files(o, single);
    const sim::Simulator simulator(load_world(o), cfg);

    if (single) {
        const sim::SimulatedFrame f = simulator.frame(0);
        if (f.scan.points.empty()) throw InvalidInput(no_return_message(o.sensor));
        write_points(f.scan, o.output);
        if (!o.gt.empty()) write_points(f.ground_truth, o.gt);
        std::printf("simulated %zu points (scene %s, %s, mid-drive, sensor frame, seed %llu) -> %s%s%s\n", f.scan.points.size(),
                    o.scene.c_str(), cfg.sensor.name.c_str(), static_cast<unsigned long long>(o.seed), o.output.c_str(),
                    o.gt.empty() ? "" : ", ground truth -> ", o.gt.c_str());
        return 0;
    }
    // The sequence is written under a temporary directory and put in place whole at the end.
    AtomicDirectory out(o.output);
    const KittiSequence seq{out.path()};
    std::error_code ec;
    const bool sweeps = cfg.sweep_seconds > 0;
    for (const fs::path& d : {seq.dir / "velodyne", seq.dir / "gt", seq.dir / "objects", seq.dir / "times"}) {
        if (!sweeps && d.filename() == "times") continue;
        fs::create_directories(d, ec);
        if (ec) throw IoError(d.string() + ": cannot create the directory (" + ec.message() + ")");
    }
    // The scene a map of the drive should hold: what stands at its end (cars that left are not in
    // it, cars that parked are).
    write_mesh(simulator.world().standing_at(simulator.world().time_at(1.0)), seq.scene());
    write_text(seq.sensor().string(), cfg.sensor.to_json());
    // The surfaces that return no ray (--dark-cars), part of scene.ply too.
    if (!simulator.world().dark_mesh.triangles.empty()) write_mesh(simulator.world().dark_mesh, seq.dir / "dark.ply");
    std::vector<Eigen::Isometry3d> poses;
    std::vector<double> frame_times;
    std::size_t points = 0;
    Progress progress("simulate", "frames", simulator.frame_count(), o.quiet);
    for (std::size_t i = 0; i < simulator.frame_count(); ++i) {
        const sim::SimulatedFrame f = simulator.frame(i);
        write_points(f.scan, seq.scan(i));
        if (cfg.gt_beams > 0) write_points(f.ground_truth, seq.ground_truth(i));
        if (!f.movers.empty()) write_mesh(f.movers, seq.objects(i));
        if (sweeps) {
            write_binary(seq.dir / "times" / seq.scan(i).filename(), f.times);
            frame_times.push_back(f.time);
        }
        poses.push_back(f.pose);
        points += f.scan.points.size();
        progress.update(i + 1);
    }
    write_poses(poses, seq.poses());
    if (sweeps) write_sweep_times(simulator, frame_times, seq.dir);
    out.commit();
    progress.finish();
    std::printf("simulated %zu frames of scene %s with %s (%.0f points per frame, seed %llu, %zu scene triangles) -> %s\n",
                simulator.frame_count(), o.scene.c_str(), cfg.sensor.name.c_str(),
                static_cast<double>(points) / static_cast<double>(simulator.frame_count()), static_cast<unsigned long long>(o.seed),
                simulator.world().static_mesh.triangles.size(), o.output.c_str());
    return 0;
}

}  // namespace lidarsurf::cli
