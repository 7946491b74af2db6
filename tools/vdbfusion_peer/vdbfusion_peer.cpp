// A peer for the map benchmark: VDBFusion (Vizzo et al., Sensors 2022), the TSDF fusion in OpenVDB
// that lidar users run today to mesh a drive from posed scans. Fuses a sequence the way its KITTI
// pipeline does (world-frame points, the sensor's position as the ray origin, constant weights),
// then extracts its marching-cubes mesh. Writes the mesh and a report with the keys `lidarsurf map-benchmark`
// reads from `lidarsurf fuse --json` (seconds.insert, per_frame[].integrate_ms).
// With --single-scans, every frame is meshed alone in the sensor frame instead (the single-scan
// peer of `lidarsurf benchmark --peers`): OUT is then a directory that receives NNNNNN.ply per
// frame and times.txt ("frame seconds" lines, integration and extraction).
// Built only by make map-peers (OpenVDB stays out of the default build and of make test).
//
// Usage: lidarsurf_vdbfusion_peer SEQ OUT.ply --json REPORT.json [--frames N] [--voxel-size 0.1]
//        [--sdf-trunc 0.3] [--space-carving 0|1] [--min-weight 5]
//        lidarsurf_vdbfusion_peer SEQ OUT_DIR --single-scans [--frames N] [same options]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <openvdb/openvdb.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "vdbfusion/VDBVolume.h"

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

const std::function<float(float)> constant_weight = [](float) { return 1.0f; };

// The finite points of scan `frame` moved by `pose` (read_world_scan keeps NaN as NaN; VDBFusion
// would trace a ray to it).
std::vector<Eigen::Vector3d> finite_points(const lidarsurf::KittiSequence& seq, std::size_t frame, const Eigen::Isometry3d& pose) {
    const lidarsurf::PointCloud cloud = lidarsurf::read_world_scan(seq, frame, pose);
    std::vector<Eigen::Vector3d> points;
    points.reserve(cloud.points.size());
    for (const Eigen::Vector3d& p : cloud.points)
        if (p.allFinite()) points.push_back(p);
    return points;
}

lidarsurf::Mesh extract(const vdbfusion::VDBVolume& volume, float min_weight) {
    const auto [vertices, triangles] = volume.ExtractTriangleMesh(true, min_weight);
    lidarsurf::Mesh mesh;
    mesh.vertices = vertices;
    mesh.triangles.reserve(triangles.size());
    for (const Eigen::Vector3i& t : triangles)
        mesh.triangles.push_back({static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
    return mesh;
}

// Each frame alone, in the sensor frame (the sensor at the origin), as a user meshing one scan
// with VDBFusion would: OUT_DIR/NNNNNN.ply and OUT_DIR/times.txt. A frame that gives no triangle
// has no mesh file (the benchmark scores it as an empty mesh).
void mesh_single_scans(const lidarsurf::KittiSequence& seq, std::size_t n, const std::filesystem::path& out, float voxel_size,
                       float sdf_trunc, bool space_carving, float min_weight) {
    std::filesystem::create_directories(out);
    std::ostringstream times;
    for (std::size_t i = 0; i < n; ++i) {
        const std::vector<Eigen::Vector3d> points = finite_points(seq, i, Eigen::Isometry3d::Identity());
        const auto t0 = std::chrono::steady_clock::now();
        vdbfusion::VDBVolume volume(voxel_size, sdf_trunc, space_carving);
        volume.Integrate(points, Eigen::Vector3d(Eigen::Vector3d::Zero()), constant_weight);
        const lidarsurf::Mesh mesh = extract(volume, min_weight);
        times << i << " " << ms_since(t0) / 1e3 << "\n";
        const std::filesystem::path file = out / (lidarsurf::KittiSequence::frame_name(i) + ".ply");
        if (!mesh.triangles.empty())
            lidarsurf::write_mesh(mesh, file);
        else
            std::filesystem::remove(file);  // no mesh left from an earlier run: the frame scores empty
        std::fprintf(stderr, "vdbfusion: frame %zu/%zu, %zu triangles\n", i + 1, n, mesh.triangles.size());
    }
    lidarsurf::AtomicFile file(out / "times.txt");
    file.stream() << times.str();
    file.commit();
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"VDBFusion on a lidarsurf sequence (peer of lidarsurf map-benchmark)"};
    std::string dir, out, json;
    int frames = 0;
    // VDBFusion's own KITTI settings (examples/python/config/kitti.yaml upstream).
    float voxel_size = 0.1f, sdf_trunc = 0.3f, min_weight = 5.0f;
    int space_carving = 0;
    bool single_scans = false;
    app.add_option("SEQ", dir, "Sequence directory (velodyne/, poses.txt)")->required();
    app.add_option("OUT", out, "Output mesh (.ply), or with --single-scans the output directory")->required();
    app.add_option("--json", json, "Report: seconds by stage and per frame (required without --single-scans)");
    app.add_flag("--single-scans", single_scans, "Mesh every frame alone in the sensor frame: OUT/NNNNNN.ply and OUT/times.txt");
    app.add_option("--frames", frames, "Fuse the first N frames (0: all)");
    app.add_option("--voxel-size", voxel_size, "Voxel size, metres");
    app.add_option("--sdf-trunc", sdf_trunc, "Truncation distance, metres");
    app.add_option("--space-carving", space_carving, "1: integrate free space along every ray");
    app.add_option("--min-weight", min_weight, "Skip cubes with a corner of lower weight when meshing");
    CLI11_PARSE(app, argc, argv);
    try {
        openvdb::initialize();
        const lidarsurf::KittiSequence seq{dir};
        std::size_t n = seq.frame_count();
        if (frames > 0) n = std::min(n, static_cast<std::size_t>(frames));
        if (single_scans) {
            mesh_single_scans(seq, n, out, voxel_size, sdf_trunc, space_carving != 0, min_weight);
            return 0;
        }
        if (json.empty()) throw lidarsurf::InvalidArgument("--json is required (a fused map's report)");
        const std::vector<Eigen::Isometry3d> poses = lidarsurf::read_poses(seq.poses());
        if (poses.size() < n) throw lidarsurf::InvalidInput(seq.poses().string() + ": fewer poses than scans");

        vdbfusion::VDBVolume volume(voxel_size, sdf_trunc, space_carving != 0);
        double integrate_s = 0;
        nlohmann::json per_frame = nlohmann::json::array();
        for (std::size_t i = 0; i < n; ++i) {
            const std::vector<Eigen::Vector3d> world = finite_points(seq, i, poses[i]);
            const auto t0 = std::chrono::steady_clock::now();
            const Eigen::Vector3d origin = poses[i].translation();
            volume.Integrate(world, origin, constant_weight);
            const double ms = ms_since(t0);
            integrate_s += ms / 1e3;
            per_frame.push_back({{"frame", i}, {"integrate_ms", ms}});
            if ((i + 1) % 20 == 0 || i + 1 == n) std::fprintf(stderr, "vdbfusion: %zu/%zu frames\n", i + 1, n);
        }
        const auto t0 = std::chrono::steady_clock::now();
        lidarsurf::Mesh mesh = extract(volume, min_weight);
        const double extract_s = ms_since(t0) / 1e3;
        if (mesh.triangles.empty()) throw lidarsurf::InvalidInput("VDBFusion gave an empty mesh");
        lidarsurf::write_mesh(mesh, out);
        const nlohmann::json j = {{"sequence", dir},
                                  {"method", "vdbfusion"},
                                  {"voxel_size", voxel_size},
                                  {"sdf_trunc", sdf_trunc},
                                  {"space_carving", space_carving != 0},
                                  {"min_weight", min_weight},
                                  {"frames", n},
                                  {"mesh_triangles", mesh.triangles.size()},
                                  {"seconds", {{"insert", integrate_s}, {"last_mesh", extract_s}}},
                                  {"per_frame", per_frame}};
        lidarsurf::AtomicFile report(json);
        report.stream() << j.dump(1) << "\n";
        report.commit();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "lidarsurf_vdbfusion_peer: %s\n", e.what());
        return 1;
    }
    return 0;
}
