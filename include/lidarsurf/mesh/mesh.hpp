#pragma once
// Indexed triangle mesh with the per-vertex attributes of the reconstruction.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf {

struct Mesh {
    std::vector<Eigen::Vector3d> vertices;               ///< world coordinates, metres
    std::vector<std::array<std::uint32_t, 3>> triangles; ///< counter-clockwise seen from the front
    std::vector<Eigen::Vector3f> normals;                ///< optional, per vertex (empty or |vertices|)
    std::vector<std::uint8_t> levels;                    ///< optional, k' per vertex
    std::vector<float> confidence;                       ///< optional, Eq. (3) value per vertex
    /// optional, per vertex: the mean intensity of the returns in the neighbourhood of the
    /// vertex's nearer lattice vertex (mesh/vertex_intensity.hpp), in the sensor's unit; NaN
    /// where no return near it had one
    std::vector<float> intensity;

    bool empty() const { return triangles.empty(); }
    /// Throws InvalidInput if attribute sizes or triangle indices are inconsistent.
    void check() const;
    /// Area of triangle `i`, m^2 (half the norm of the edge cross product).
    double triangle_area(std::size_t i) const;
    /// Appends `part`: its vertices (with their attributes) after this mesh's, its triangles
    /// renumbered to them. Shared vertices are not merged.
    void append(const Mesh& part);
    /// Appends `part` welded onto this mesh: a vertex of `part` whose `existing` entry is >= 0 is
    /// this mesh's vertex of that index and is not appended again; the others are appended in
    /// order (the numbering of MeshStreamWriter::append and SeamWelder::weld).
    void append(const Mesh& part, std::span<const std::int64_t> existing);
    /// Replaces the triangles by `kept` (indices into this mesh's vertices), then drops the
    /// vertices no kept triangle uses; attributes follow their vertices, whose order is unchanged.
    void keep_triangles(std::vector<std::array<std::uint32_t, 3>> kept);
};

}  // namespace lidarsurf
