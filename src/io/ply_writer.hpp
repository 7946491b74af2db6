#pragma once
// Internal: the PLY writer's pieces (header, vertex records, face records), shared by write_ply
// (one mesh) and MeshStreamWriter (a mesh written part by part).
#include <array>
#include <cstdint>
#include <functional>
#include <ostream>
#include <span>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf::detail {

struct PlyLayout {
    bool binary = true;      ///< binary_little_endian, else ascii
    bool dbl = false;        ///< coordinates as double
    bool normals = false, levels = false, confidence = false, intensity = false;
    /// The layout of `mesh`'s attributes.
    static PlyLayout of(const Mesh& mesh, bool binary, bool dbl);
    bool operator==(const PlyLayout&) const = default;
};

void write_ply_header(std::ostream& out, const PlyLayout& layout, std::uint64_t vertices, std::uint64_t faces);
/// The vertex records of `mesh`, but those whose `existing` entry is >= 0 (empty: all).
void write_ply_vertices(std::ostream& out, const PlyLayout& layout, const Mesh& mesh, std::span<const std::int64_t> existing);
/// The face records, each index through `index` (none: as is). Throws InvalidInput past 2^31 - 1.
void write_ply_faces(std::ostream& out, const PlyLayout& layout, std::span<const std::array<std::uint32_t, 3>> triangles,
                     const std::function<std::uint64_t(std::uint32_t)>& index);

}  // namespace lidarsurf::detail
