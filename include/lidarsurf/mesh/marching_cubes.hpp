#pragma once
// Marching cubes (Lorensen & Cline 1987) over the cubes of the lattice whose 8 corners are defined.
//
// Instead of the 256-case table, each cube's patch is built from its faces: on every face the
// sign changes are joined into oriented segments (face ambiguities resolved by the asymptotic
// decider, which depends only on that face's four values, so neighbouring cubes agree and the
// surface is closed), the segments are chained into loops, and each loop is fanned into
// triangles. Vertices are keyed by lattice edge, so shared vertices are welded. Triangles face
// the positive side of the field (the sensor side of the TSDF).
#include <span>
#include <vector>

#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"

namespace lidarsurf {

/// Where a vertex goes on a lattice edge whose ends have opposite signs.
enum class VertexPlacement {
    Interpolated,    ///< the zero of the linear interpolation (Lorensen & Cline)
    SnappedToPlane,  ///< that point moved onto the plane Pi^{k'} of the nearer end (docs/method.md)
};

/// Meshes every cube of `field` whose 8 corners are defined.
Mesh extract_mesh(const TsdfField& field, VertexPlacement placement = VertexPlacement::Interpolated);

/// Meshes only the given cubes (by minimum corner), in the given order.
Mesh extract_mesh(const TsdfField& field, const std::vector<VoxelKey>& cubes,
                  VertexPlacement placement = VertexPlacement::Interpolated);

/// Meshes the cubes in groups, one mesh each: group g is cubes[starts[g], starts[g + 1]) and its
/// mesh is the one extract_mesh(field, those cubes) gives (its vertices welded within the group).
/// In parallel over the groups.
std::vector<Mesh> extract_meshes(const TsdfField& field, const std::vector<VoxelKey>& cubes, std::span<const std::size_t> starts,
                                 VertexPlacement placement = VertexPlacement::Interpolated);

}  // namespace lidarsurf
