#include "lidarsurf/tiles/tile_writer.hpp"

#include <algorithm>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/mesh_stream.hpp"

namespace lidarsurf {

void require_fused_triangles(std::uint64_t triangles) {
    if (triangles == 0) throw InvalidInput("the fused sequence gives an empty mesh");
}

bool needs_double_coordinates(const Eigen::AlignedBox3d& b) {
    // Float coordinates keep ~1e-3 m up to 1e4 m (write_mesh's rule), with a margin for the mesh.
    return b.min().cwiseAbs().maxCoeff() > 1e4 - 100 || b.max().cwiseAbs().maxCoeff() > 1e4 - 100;
}

ReconstructionSummary mesh_in_tiles(Reconstructor& rec, const TilePlan& plan, const std::function<void(const TileKey&, const Mesh&)>& part) {
    ReconstructionSummary total = rec.summary();
    total.candidate_vertices = total.reused_vertices = total.defined_vertices = 0;
    total.seconds_tsdf = total.seconds_mesh = 0;
    for (const TileKey& key : plan.tiles()) {
        const Mesh mesh = mesh_tile(rec, plan, key);
        if (mesh.triangles.empty()) continue;
        const ReconstructionSummary& s = rec.summary();  // the tile's extraction
        total.candidate_vertices += s.candidate_vertices, total.reused_vertices += s.reused_vertices;
        total.defined_vertices += s.defined_vertices;
        total.seconds_tsdf += s.seconds_tsdf, total.seconds_mesh += s.seconds_mesh;
        total.memory_estimate = std::max(total.memory_estimate, s.memory_estimate);
        part(key, mesh);
    }
    return total;
}

ReconstructionSummary write_in_tiles(Reconstructor& rec, const TilePlan& plan, const std::string& output, MeshFormat format, Mesh* whole) {
    MeshStreamWriter writer(output, format, needs_double_coordinates(plan.bounds()));
    SeamWelder welder(plan);
    ReconstructionSummary total = mesh_in_tiles(rec, plan, [&](const TileKey& key, const Mesh& part) {
        writer.append(part, welder.weld(key, part, writer.vertices()));
        if (whole) whole->append(part);
    });
    require_fused_triangles(writer.triangles());
    writer.commit();
    total.mesh_vertices = writer.vertices();
    total.mesh_triangles = writer.triangles();
    return total;
}

}  // namespace lidarsurf
