// `fuse --tile-size`: the map in tiles (tiles/tiles.hpp), one after the other. A first pass reads
// every scan once for its reach (where it was seen from, how far its returns go); then each tile
// reads the scans that reach it, is fused and meshed alone, and its mesh is appended to the
// output (MeshStreamWriter), the seams welded (SeamWelder). Memory holds one tile's grid and mesh,
// never the map's.
#include <algorithm>
#include <chrono>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "progress.hpp"
#include "lidarsurf/io/mesh_stream.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/tiles/tile_writer.hpp"

namespace lidarsurf::cli {

int run_fuse_tiles(const FuseOptions& o, const Method& m, const FuseInput& in) {
    std::FILE* const report = report_stream(o.output);
    const auto start = std::chrono::steady_clock::now();
    // Scan n of the fusion (frame in.frames[n]) in the world frame, and where it was seen from.
    // and the directions of its rays that returned nothing (when carving takes them).
    const bool empty_rays = m.config.carve && m.config.carve_empty_range > 0;
    const auto read_scan = [&](std::size_t n, std::vector<Eigen::Vector3f>& no_return) {
        return in.read(n, m.read, empty_rays ? &no_return : nullptr);  // NaN stays NaN: no tile keeps it
    };
    std::vector<ScanReach> reach;
    reach.reserve(in.scans.size());
    {
        Progress progress("fuse: plan", "frames", in.scans.size(), o.quiet);
        std::vector<Eigen::Vector3f> no_return;
        for (std::size_t n = 0; n < in.scans.size(); ++n) {
            no_return.clear();
            const PointCloud cloud = read_scan(n, no_return);
            reach.push_back(scan_reach(cloud.points, in.pose(n) * m.sensor, !no_return.empty()));
            progress.update(n + 1);
        }
        progress.finish();
    }
    const TilePlan plan(std::move(reach), m.config, o.tiles);
    const double plan_s = ms_since(start) / 1e3;

    MeshStreamWriter writer(o.output, in.format, needs_double_coordinates(plan.bounds()));
    SeamWelder welder(plan);
    nlohmann::json per_tile = nlohmann::json::array();
    std::size_t points = 0, voxels = 0, carved = 0, estimate = 0;
    double insert_s = 0, carve_s = 0, tsdf_s = 0, mesh_s = 0, write_s = 0;
    Progress progress("fuse", "tiles", plan.tiles().size(), o.quiet);
    for (std::size_t t = 0; t < plan.tiles().size(); ++t) {
        const TileKey& key = plan.tiles()[t];
        const auto t0 = std::chrono::steady_clock::now();
        ReconstructionSummary s;
        const Mesh part = fuse_tile(plan, key, read_scan, &s);
        const double fuse_ms = ms_since(t0);
        const auto t1 = std::chrono::steady_clock::now();
        writer.append(part, welder.weld(key, part, writer.vertices()));
        write_s += ms_since(t1) / 1e3;
        points += s.points_read - s.points_dropped;
        voxels += s.voxels;
        carved += s.carved_voxels;
        estimate = std::max(estimate, s.memory_estimate);
        insert_s += s.seconds_insert, carve_s += s.seconds_carve, tsdf_s += s.seconds_tsdf, mesh_s += s.seconds_mesh;
        per_tile.push_back({{"x", key.x},
                            {"y", key.y},
                            {"scans", plan.scans_of(key)},
                            {"voxels", s.voxels},
                            {"triangles", part.triangles.size()},
                            {"ms", fuse_ms},
                            {"memory_estimate_mib", static_cast<double>(s.memory_estimate) / 1048576.0},
                            {"resident_mib", resident_mib()}});
        progress.update(t + 1, std::to_string(writer.triangles()) + " triangles");
    }
    progress.finish(std::to_string(writer.triangles()) + " triangles");
    require_fused_triangles(writer.triangles());
    const auto t2 = std::chrono::steady_clock::now();
    writer.commit();
    write_s += ms_since(t2) / 1e3;
    const double total_s = ms_since(start) / 1e3;
    std::fprintf(report,
                 "%s: %zu frames fused in %zu tiles of %g m (%s, poses from %s); mesh %llu vertices %llu triangles; "
                 "plan %.1f s, tiles %.1f s (insert %.1f, carving %.1f, tsdf %.1f, mesh %.1f), write %.1f s; memory estimate %.0f MiB (largest tile), peak resident %.0f MiB -> %s\n",
                 in.name().c_str(), in.scans.size(), plan.tiles().size(), o.tiles.tile_size, method_name(m).c_str(), in.layout().c_str(),
                 static_cast<unsigned long long>(writer.vertices()), static_cast<unsigned long long>(writer.triangles()), plan_s,
                 total_s - plan_s - write_s, insert_s, carve_s, tsdf_s, mesh_s, write_s, static_cast<double>(estimate) / 1048576.0,
                 peak_resident_mib(), o.output.c_str());
    if (!o.json.empty()) {
        nlohmann::json j = fuse_report_head(in, m);
        j.update({{"tile_size", o.tiles.tile_size},
                  {"tile_halo_cubes", o.tiles.halo_cubes},
                  {"ray_reach_m", plan.ray_reach()},
                  {"tiles", plan.tiles().size()},
                  {"points_integrated", points},
                  {"voxels", voxels},
                  {"carved_voxels", carved},
                  {"memory_estimate_mib", static_cast<double>(estimate) / 1048576.0},
                  {"seam_vertices", welder.size()},
                  {"mesh_vertices", writer.vertices()},
                  {"mesh_triangles", writer.triangles()},
                  {"seconds",
                   {{"plan", plan_s}, {"insert", insert_s}, {"carve", carve_s}, {"tsdf", tsdf_s}, {"mesh", mesh_s}, {"write", write_s}, {"total", total_s}}},
                  {"peak_resident_mib", peak_resident_mib()},
                  {"per_tile", per_tile}});
        write_json(o.json, j);
    }
    return 0;
}

}  // namespace lidarsurf::cli
