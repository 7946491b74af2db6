// `fuse --tile-size`: the map in tiles (tiles/tiles.hpp). A first pass reads every scan once for
// its reach (where it was seen from, how far its returns go); a second one reads each scan again,
// once, for every tile it reaches (fuse_tiles): a tile is fused from its first scan to its last,
// then meshed and its mesh appended to the output (MeshStreamWriter), the seams welded
// (SeamWelder). Memory holds the tiles open at once, never the map.
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
    std::size_t points = 0, voxels = 0, carved = 0;
    double insert_s = 0, carve_s = 0, tsdf_s = 0, mesh_s = 0, write_s = 0;
    Progress progress("fuse", "tiles", plan.tiles().size(), o.quiet);
    std::size_t done = 0;
    const TileDone append = [&](const TileKey& key, Mesh&& part, const ReconstructionSummary& s) {
        const auto t1 = std::chrono::steady_clock::now();
        writer.append(part, welder.weld(key, part, writer.vertices()));
        write_s += ms_since(t1) / 1e3;
        points += s.points_read - s.points_dropped;
        voxels += s.voxels;
        carved += s.carved_voxels;
        insert_s += s.seconds_insert, carve_s += s.seconds_carve, tsdf_s += s.seconds_tsdf, mesh_s += s.seconds_mesh;
        per_tile.push_back({{"x", key.x},
                            {"y", key.y},
                            {"scans", plan.scans_of(key)},
                            {"voxels", s.voxels},
                            {"triangles", part.triangles.size()},
                            {"ms", 1e3 * s.seconds_total()},
                            {"memory_estimate_mib", static_cast<double>(s.memory_estimate) / 1048576.0},
                            {"resident_mib", resident_mib()}});
        progress.update(++done, std::to_string(writer.triangles()) + " triangles");
    };
    TilePassStats pass;
    nlohmann::json per_group = nlohmann::json::array();
    for (const std::vector<TileKey>& group : plan.groups()) {
        const auto g0 = std::chrono::steady_clock::now();
        const double written_before = write_s;
        const TilePassStats p = fuse_tiles(plan, group, read_scan, append);
        pass.add(p);
        nlohmann::json keys = nlohmann::json::array();
        for (const TileKey& k : group) keys.push_back({k.x, k.y});
        // What a Dask task of this group does: its pass, without the writing into the one output.
        per_group.push_back({{"tiles", keys}, {"scans_read", p.scans_read}, {"seconds", ms_since(g0) / 1e3 - (write_s - written_before)}});
    }
    progress.finish(std::to_string(writer.triangles()) + " triangles");
    require_fused_triangles(writer.triangles());
    const auto t2 = std::chrono::steady_clock::now();
    writer.commit();
    write_s += ms_since(t2) / 1e3;
    const double total_s = ms_since(start) / 1e3;
    std::fprintf(report,
                 "%s: %zu frames fused in %zu tiles of %g m (%s, poses from %s); mesh %llu vertices %llu triangles; "
                 "plan %.1f s, tiles %.1f s (read %.1f, range images %.1f, insert %.1f, carving %.1f, tsdf %.1f, mesh %.1f), write %.1f s; "
                 "memory estimate %.0f MiB (largest group, %zu tiles at once), peak resident %.0f MiB -> %s\n",
                 in.name().c_str(), in.scans.size(), plan.tiles().size(), o.tiles.tile_size, method_name(m).c_str(), in.layout().c_str(),
                 static_cast<unsigned long long>(writer.vertices()), static_cast<unsigned long long>(writer.triangles()), plan_s,
                 total_s - plan_s - write_s, pass.seconds_read, pass.seconds_image, insert_s, carve_s, tsdf_s, mesh_s, write_s,
                 static_cast<double>(pass.memory_estimate) / 1048576.0, pass.most_open, peak_resident_mib(), o.output.c_str());
    if (!o.json.empty()) {
        nlohmann::json j = fuse_report_head(in, m);
        j.update({{"tile_size", o.tiles.tile_size},
                  {"tile_halo_cubes", o.tiles.halo_cubes},
                  {"tile_group", o.tiles.group},
                  {"ray_reach_m", plan.ray_reach()},
                  {"tiles", plan.tiles().size()},
                  {"tiles_at_once", pass.most_open},
                  {"scans_read", pass.scans_read},
                  {"points_integrated", points},
                  {"voxels", voxels},
                  {"carved_voxels", carved},
                  {"memory_estimate_mib", static_cast<double>(pass.memory_estimate) / 1048576.0},
                  {"seam_vertices", welder.size()},
                  {"mesh_vertices", writer.vertices()},
                  {"mesh_triangles", writer.triangles()},
                  {"seconds",
                   {{"plan", plan_s}, {"read", pass.seconds_read}, {"range_images", pass.seconds_image}, {"insert", insert_s}, {"carve", carve_s}, {"tsdf", tsdf_s}, {"mesh", mesh_s}, {"write", write_s}, {"total", total_s}}},
                  {"peak_resident_mib", peak_resident_mib()},
                  {"per_tile", per_tile},
                  {"per_group", per_group}});
        write_json(o.json, j);
    }
    return 0;
}

}  // namespace lidarsurf::cli
