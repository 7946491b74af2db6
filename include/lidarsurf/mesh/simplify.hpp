#pragma once
// Simplification of an extracted mesh: triangles merged wherever the surface stays about within a
// distance of the full mesh (meshoptimizer's quadric edge collapse, meshopt_simplify).
#include <cstddef>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

/// Collapses edges of `mesh` while meshoptimizer's quadric error, converted from metres with
/// meshopt_simplifyScale, stays within a share of `max_error` (src/mesh/simplify.cpp): the
/// surface then stays about within max_error of the full mesh (an estimate, not a guaranteed
/// bound: docs/method.md, "Simplification"). Vertices on
/// a border (an edge of one triangle: the mesh's outline, its holes, a tile's seam) are neither
/// moved nor removed, so the outline stays and no seam between tiles opens. What is kept is a subset of the vertices,
/// unmoved, with their attributes (normals, levels, confidence), in their order; triangles keep
/// their orientation. max_error <= 0 leaves the mesh as it is. Returns the triangles removed.
std::size_t simplify_mesh(Mesh& mesh, double max_error);

}  // namespace lidarsurf
