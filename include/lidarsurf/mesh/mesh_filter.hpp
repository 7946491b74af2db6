#pragma once
// Clean-up of an extracted mesh: connected pieces below a size are dropped.
#include <cstddef>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

/// Removes every connected piece (triangles joined through shared vertices) with fewer than
/// `min_triangles` triangles, then the vertices no triangle uses; vertex attributes follow their
/// vertices and the order of what is kept is unchanged. Returns the number of triangles removed.
std::size_t remove_small_components(Mesh& mesh, std::size_t min_triangles);

}  // namespace lidarsurf
