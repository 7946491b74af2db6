#pragma once
// Binary glTF 2.0 (.glb) for the web, game engines and simulators. The file holds one mesh in a
// two-node scene:
//   - the root node turns the lidar's z-up frame into glTF's y-up one (a rotation of -90 degrees
//     about x), so the map stands upright in three.js, Blender, Unity or Unreal;
//   - its child carries the mesh, translated by the map's origin (whole metres, kept as double in
//     the JSON), with positions as float offsets from it: a map in UTM coordinates keeps its
//     millimetres. Its translation and positions together are the mesh's world coordinates.
// Vertex attributes: POSITION, NORMAL, and the reconstruction's own as glTF application-specific
// attributes: _CONFIDENCE (float, the Eq. (3) value), _INTENSITY (float, the returns' mean
// intensity in the sensor's unit; -1 where the PLY has NaN, as glTF refuses NaN) when the mesh has
// one, and _LEVEL (unsigned byte, k'). Triangles are
// uint32 indices, counter-clockwise from the front; the material is grey and double-sided.
//
// With Draco (KHR_draco_mesh_compression, Debian's libdraco) each primitive is one Draco
// bitstream: positions quantized to 1 mm, normals to 10 bits, confidence to 10 bits and intensity
// to 12 bits over their ranges, levels exact. A mesh written part by part (MeshStreamWriter) gets one primitive a part,
// so a seam's vertices are repeated in each part that uses them; the triangles are the same.
#include <ostream>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

/// Writes `mesh` as binary glTF, Draco-compressed if `draco`. Throws InvalidInput for a mesh past
/// glTF's 4 GiB or 2^32 vertices, IoError.
void write_glb(const Mesh& mesh, std::ostream& out, bool draco = false);

}  // namespace lidarsurf
