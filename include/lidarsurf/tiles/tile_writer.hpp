#pragma once
// One map fused whole, meshed and written tile by tile (tiles.hpp's mesh_tile): the triangles of
// Reconstructor::extract_mesh(), appended to the output as each tile comes, the seams welded
// (SeamWelder), so that the whole mesh is never held. What `fuse` writes its map with.
#include <cstdint>
#include <functional>
#include <string>

#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/tiles/tiles.hpp"

namespace lidarsurf {

/// The side of the tiles a map fused whole is written in (metres).
inline constexpr double kWriteTileSize = 64.0;

/// Meshes `rec`'s map tile by tile (plan.tiles(), in order) and calls `part(tile, mesh)` for each
/// tile with a triangle. Returns rec's summary with the tiles' counts and times summed (mesh
/// counts left for the caller).
ReconstructionSummary mesh_in_tiles(Reconstructor& rec, const TilePlan& plan, const std::function<void(const TileKey&, const Mesh&)>& part);

/// mesh_in_tiles() into `output` (`format` as write_mesh's), the seams welded: the file holds the
/// triangles and vertices of rec.extract_mesh(). `whole`, when given, also gets every tile's mesh
/// (seams not welded: for a viewer). Returns the summary with the file's counts. Throws
/// InvalidInput for an empty mesh (nothing written), IoError.
ReconstructionSummary write_in_tiles(Reconstructor& rec, const TilePlan& plan, const std::string& output, MeshFormat format,
                                     Mesh* whole = nullptr);

/// Throws InvalidInput ("the fused sequence gives an empty mesh") when a fused map's mesh has
/// no triangle: nothing is written.
void require_fused_triangles(std::uint64_t triangles);

/// Whether a map within `bounds` needs double coordinates in its file (write_mesh's rule: a
/// coordinate past 1e4 m), decided before the first tile is written.
bool needs_double_coordinates(const Eigen::AlignedBox3d& bounds);

}  // namespace lidarsurf
