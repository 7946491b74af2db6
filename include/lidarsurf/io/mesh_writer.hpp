#pragma once
// Mesh writers: PLY (binary little endian by default, ascii on request), OBJ, and binary glTF
// (glb_writer.hpp; Draco-compressed on request). The PLY keeps the per-vertex normal, level k'
// (uchar "level") and confidence (float "confidence"); the glTF keeps them as NORMAL, _LEVEL and
// _CONFIDENCE.
#include <filesystem>
#include <ostream>
#include <string>
#include <string_view>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

enum class MeshFormat { Auto, PlyBinary, PlyAscii, Obj, Glb, GlbDraco };

/// "auto", "ply", "ply-ascii", "obj", "glb", "glb-draco"; throws InvalidArgument otherwise.
MeshFormat parse_mesh_format(std::string_view name);

/// The format a mesh written to `path` gets: `format` itself unless Auto; Auto takes it from the
/// extension (".ply" binary PLY, ".obj" OBJ, ".glb" binary glTF, any case) and throws InvalidArgument for any other
/// extension (".stl" is not written as PLY in disguise).
MeshFormat mesh_format_for(const std::filesystem::path& path, MeshFormat format = MeshFormat::Auto);

/// Writes to `path` atomically (temporary + rename), in mesh_format_for(path, format).
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, MeshFormat format = MeshFormat::Auto);

/// Stream writers (no atomicity; used by write_mesh and tests).
void write_ply(const Mesh& mesh, std::ostream& out, bool binary);
void write_obj(const Mesh& mesh, std::ostream& out);

/// Reads a triangle mesh written as PLY (vertex x, y, z and a face list) or OBJ (v and f lines);
/// throws InvalidArgument for a .glb (written, not read).
Mesh read_mesh(const std::filesystem::path& path);
/// The same on an in-memory buffer: OBJ if `format` is Obj, else PLY (any PLY encoding). `name` is
/// for messages. Used by read_mesh and by the fuzzers.
Mesh parse_mesh(std::string_view data, MeshFormat format, const std::string& name);

}  // namespace lidarsurf
