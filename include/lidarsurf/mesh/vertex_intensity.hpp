#pragma once
// Intensity on the mesh: each vertex takes the mean intensity of the returns in the neighbourhood
// that placed it. Marching cubes gives a vertex the level and confidence of the nearer lattice
// vertex of its edge; its intensity is the mean over that vertex's H^{k'} (Sec. III-B1), the
// voxels whose statistics gave the plane it lies on (docs/method.md, "Intensity").
#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

/// Sets mesh.intensity from `grid` (the grid the mesh was extracted from, with intensity): for
/// each vertex, the point-weighted mean intensity of H^k(v), v the lattice vertex nearest it
/// and k its level (mesh.levels, at least 1; 1 without levels). Where H^k holds no return with
/// an intensity (a bridged vertex between scan rings), the smallest larger box H^j(v) that does,
/// j up to `reach` (SurfaceConfig::max_reach(), the farthest the vertex's value could come
/// from); NaN when none does. Leaves the mesh as it is when the grid keeps no intensity. In parallel.
void attach_intensity(Mesh& mesh, const VoxelGrid& grid, int reach);

}  // namespace lidarsurf
