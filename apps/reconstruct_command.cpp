// lidarsurf reconstruct: one scan -> one mesh, by the method and settings of the reconstruct
// options (cli_common.hpp).
#include <chrono>
#include <cstdio>

#include "commands.hpp"
#include "file_roles.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/io/recording.hpp"

namespace lidarsurf::cli {

CLI::App* add_reconstruct_command(CLI::App& app, ReconstructCommandOptions& o) {
    auto* rc = app.add_subcommand("reconstruct", "Reconstruct a triangle mesh from one lidar scan");
    rc->footer(
        "Examples:\n"
        "  lidarsurf reconstruct 000000.bin -o mesh.ply\n"
        "  lidarsurf reconstruct scan.pcd -o mesh.obj --mode cn --k 3 --origin 0,0,1.73\n"
        "  lidarsurf reconstruct sweep.bin --bin-fields 5 -o mesh.ply --voxel-size 0.1 --threads 2\n"
        "  lidarsurf reconstruct 000000.bin -o imls.ply --method imls\n"
        "  lidarsurf reconstruct OS-1-64.pcap --scan 3 -o mesh.ply      (metadata: OS-1-64.json beside it)\n"
        "  lidarsurf reconstruct drive.bag --topic /points --scan 100 -o mesh.ply\n"
        "  lidarsurf reconstruct drive.mcap --time 12.5 -o mesh.ply     (the scan 12.5 s after the first)\n");
    rc->add_option("input", o.input, "Input point cloud (.bin KITTI, .ply, .pcd, .xyz/.csv/.txt) or recording (.pcap, ROS 1 .bag, ROS 2 bag: directory, .db3, .mcap)")->required();
    auto* scan = rc->add_option("--scan,--message", o.scan, "The scan of a recording to mesh, from 0 (lidarsurf info counts them)")
                     ->capture_default_str()->check(CLI::NonNegativeNumber);
    rc->add_option("--time", o.time, "Or the scan of a recording whose stamp is nearest T seconds after its first scan's")
        ->check(CLI::NonNegativeNumber)->excludes(scan);
    add_recording_options(rc, o.recording);
    rc->add_option("-o,--output", o.output, "Output mesh (.ply binary by default, .obj)")->required();
    rc->add_option("--mesh-format", o.mesh_format, "Output format: auto | ply | ply-ascii | obj | glb | glb-draco (binary glTF, Draco-compressed)")->capture_default_str();
    add_reconstruct_options(rc, o.reconstruct);
    return rc;
}

int run_reconstruct(const ReconstructCommandOptions& o) {
    const std::string& input = o.input;
    const std::string& output = o.output;
    Method m = resolve_method(o.reconstruct);
    FileRoles files;
    files.input(input);
    files.output(output, "-o");
    files.check();
    const MeshFormat mesh_format = mesh_format_for(output, parse_mesh_format(o.mesh_format));  // .stl: exit 2 now

    auto t0 = std::chrono::steady_clock::now();
    PointCloud cloud;
    std::string from = input;
    if (is_recording(input)) {
        RecordedScan scan = o.time >= 0 ? read_recorded_scan_at(input, o.time, recording_options(o.recording))
                                         : read_recorded_scan(input, static_cast<std::size_t>(o.scan), recording_options(o.recording));
        if (o.reconstruct.origin == ReconstructOptions{}.origin) m.sensor = scan.origin;  // the rays start at the sensor's lidar
        cloud = std::move(scan.cloud);
        from += " scan " + std::to_string(scan.index);
        if (o.time >= 0) from += " (" + std::to_string(o.time) + " s asked for)";
    } else {
        cloud = read_points(input, m.read);
    }
    const double read_ms = ms_since(t0);
    std::string summary;
    const Mesh mesh = run_method(m, std::move(cloud), summary);
    t0 = std::chrono::steady_clock::now();
    write_mesh(mesh, output, mesh_format);
    std::fprintf(report_stream(output), "%s: %s; %s; read %.1f ms, write %.1f ms -> %s\n", from.c_str(), method_name(m).c_str(), summary.c_str(), read_ms,
                ms_since(t0), output.c_str());
    return 0;
}

}  // namespace lidarsurf::cli
