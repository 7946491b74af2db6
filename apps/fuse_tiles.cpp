// The map in squares (map/tiles.hpp). `fuse --tile-size`: one tile after the other. A first pass
// reads every scan once for its reach (where it was seen from, how far its returns go); then each
// tile reads the scans that reach it, is fused and meshed alone, and its mesh is appended to the
// output (MeshStreamWriter), the seams welded (SeamWelder). Memory holds one tile's grid and mesh,
// never the map's. Plain `fuse` writes its one map the same way, square by square
// (write_by_squares), so that the whole mesh is never held either.
#include <chrono>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "progress.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_stream.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/pipeline.hpp"

namespace lidarsurf::cli {

namespace {

// Float coordinates keep ~1e-3 m up to 1e4 m (write_mesh's rule), decided before the header.
bool double_coordinates(const TilePlan& plan) {
    const Eigen::AlignedBox3d& b = plan.bounds();
    return b.min().cwiseAbs().maxCoeff() > 1e4 - 100 || b.max().cwiseAbs().maxCoeff() > 1e4 - 100;
}

}  // namespace

ReconstructionSummary write_by_squares(Reconstructor& rec, const TilePlan& plan, const std::string& output, MeshFormat format, Mesh* whole) {
    MeshStreamWriter writer(output, format, double_coordinates(plan));
    SeamWelder welder(plan);
    ReconstructionSummary total = rec.summary();
    total.candidate_vertices = total.reused_vertices = total.defined_vertices = 0;
    total.seconds_tsdf = total.seconds_mesh = 0;
    for (const TileKey& key : plan.tiles()) {
        const Mesh part = mesh_tile(rec, plan, key);
        if (part.triangles.empty()) continue;
        const ReconstructionSummary& s = rec.summary();  // the square's extraction
        total.candidate_vertices += s.candidate_vertices, total.reused_vertices += s.reused_vertices;
        total.defined_vertices += s.defined_vertices;
        total.seconds_tsdf += s.seconds_tsdf, total.seconds_mesh += s.seconds_mesh;
        total.memory_estimate = std::max(total.memory_estimate, s.memory_estimate);
        writer.append(part, welder.weld(key, part, writer.vertices()));
        if (whole) whole->append(part);
    }
    if (writer.triangles() == 0) throw InvalidInput("the fused sequence gives an empty mesh");
    writer.commit();
    total.mesh_vertices = writer.vertices();
    total.mesh_triangles = writer.triangles();
    return total;
}

int run_fuse_tiles(const FuseOptions& o, const Method& m, const FuseInput& in) {
    std::FILE* const report = report_stream(o.output);
    const auto start = std::chrono::steady_clock::now();
    // Scan n of the fusion (frame in.frames[n]) in the world frame, and where it was seen from.
    const auto read_scan = [&](std::size_t n) { return in.read(n, m.read).points; };  // NaN stays NaN: no tile keeps it
    std::vector<ScanReach> reach;
    reach.reserve(in.scans.size());
    {
        Progress progress("fuse: plan", "frames", in.scans.size(), o.quiet);
        for (std::size_t n = 0; n < in.scans.size(); ++n) {
            reach.push_back(scan_reach(read_scan(n), in.pose(n) * m.sensor));
            progress.update(n + 1);
        }
        progress.finish();
    }
    const TilePlan plan(std::move(reach), m.config, o.tiles);
    const double plan_s = ms_since(start) / 1e3;

    MeshStreamWriter writer(o.output, in.format, double_coordinates(plan));
    SeamWelder welder(plan);
    nlohmann::json per_tile = nlohmann::json::array();
    std::size_t points = 0, voxels = 0, carved = 0;
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
        insert_s += s.seconds_insert, carve_s += s.seconds_carve, tsdf_s += s.seconds_tsdf, mesh_s += s.seconds_mesh;
        per_tile.push_back({{"x", key.x},
                            {"y", key.y},
                            {"scans", plan.scans_of(key)},
                            {"voxels", s.voxels},
                            {"triangles", part.triangles.size()},
                            {"ms", fuse_ms},
                            {"resident_mib", resident_mib()}});
        progress.update(t + 1, std::to_string(writer.triangles()) + " triangles");
    }
    progress.finish(std::to_string(writer.triangles()) + " triangles");
    if (writer.triangles() == 0) throw InvalidInput("the fused sequence gives an empty mesh");
    const auto t2 = std::chrono::steady_clock::now();
    writer.commit();
    write_s += ms_since(t2) / 1e3;
    const double total_s = ms_since(start) / 1e3;
    std::fprintf(report,
                 "%s: %zu frames fused in %zu tiles of %g m (%s, poses from %s); mesh %llu vertices %llu triangles; "
                 "plan %.1f s, tiles %.1f s (insert %.1f, carving %.1f, tsdf %.1f, mesh %.1f), write %.1f s; peak resident %.0f MiB -> %s\n",
                 in.name().c_str(), in.scans.size(), plan.tiles().size(), o.tiles.tile_size, method_name(m).c_str(), in.layout().c_str(),
                 static_cast<unsigned long long>(writer.vertices()), static_cast<unsigned long long>(writer.triangles()), plan_s,
                 total_s - plan_s - write_s, insert_s, carve_s, tsdf_s, mesh_s, write_s, peak_resident_mib(), o.output.c_str());
    if (!o.json.empty()) {
        nlohmann::json j = {{"sequence", in.name()},
                            {"poses", in.layout()},
                            {"method", method_name(m)},
                            {"carve", m.config.carve},
                            {"frames", in.scans.size()},
                            {"tile_size", o.tiles.tile_size},
                            {"tile_halo_cubes", o.tiles.halo_cubes},
                            {"ray_reach_m", plan.ray_reach()},
                            {"tiles", plan.tiles().size()},
                            {"points_integrated", points},
                            {"voxels", voxels},
                            {"carved_voxels", carved},
                            {"seam_vertices", welder.size()},
                            {"mesh_vertices", writer.vertices()},
                            {"mesh_triangles", writer.triangles()},
                            {"seconds",
                             {{"plan", plan_s},
                              {"insert", insert_s},
                              {"carve", carve_s},
                              {"tsdf", tsdf_s},
                              {"mesh", mesh_s},
                              {"write", write_s},
                              {"total", total_s}}},
                            {"peak_resident_mib", peak_resident_mib()},
                            {"per_tile", per_tile}};
        AtomicFile out(o.json);
        out.stream() << j.dump(1) << "\n";
        out.commit();
    }
    return 0;
}

}  // namespace lidarsurf::cli
