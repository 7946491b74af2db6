#pragma once
// Internal: the binary glTF writer's pieces (vertex records, indices, Draco primitives, the JSON
// chunk, the container's header), shared by write_glb (one mesh) and MeshStreamWriter (a mesh
// written part by part). The layout is documented in lidarsurf/io/glb_writer.hpp.
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf::detail {

struct GlbLayout {
    bool normals = false, levels = false, confidence = false, intensity = false;
    /// The mesh node's translation: positions are float offsets from it (whole metres).
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    /// The layout of `mesh`'s attributes, its origin its first vertex rounded down to the metre.
    static GlbLayout of(const Mesh& mesh);
    /// Bytes per interleaved vertex record: position, normal, confidence, intensity, level (padded to 4).
    std::uint32_t stride() const;
};

/// A vertex's intensity as the file holds it: glTF refuses NaN, so a vertex without one is -1.
inline float glb_intensity(float v) { return v == v ? v : -1.0f; }

/// A vertex's position as the file holds it: its float offset from the origin.
inline Eigen::Vector3f offset_from(const Eigen::Vector3d& v, const Eigen::Vector3d& origin) { return (v - origin).cast<float>(); }

/// The bounds of the float positions written (glTF's accessor min and max must be theirs).
struct PositionBounds {
    Eigen::Vector3f min = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
    Eigen::Vector3f max = Eigen::Vector3f::Constant(-std::numeric_limits<float>::infinity());
    void add(const Eigen::Vector3f& p) { min = min.cwiseMin(p), max = max.cwiseMax(p); }
    void add(const PositionBounds& b) { min = min.cwiseMin(b.min), max = max.cwiseMax(b.max); }
};

/// The interleaved vertex records of `mesh`, but those whose `existing` entry is >= 0 (empty:
/// all); `bounds`, when given, grows by the positions written.
void write_glb_vertices(std::ostream& out, const GlbLayout& layout, const Mesh& mesh, std::span<const std::int64_t> existing,
                        PositionBounds* bounds);
/// The triangles' indices as uint32, each through `index` (none: as is). Throws InvalidInput past
/// 2^32 - 1.
void write_glb_indices(std::ostream& out, std::span<const std::array<std::uint32_t, 3>> triangles,
                       const std::function<std::uint64_t(std::uint32_t)>& index);

/// A primitive compressed by Draco (KHR_draco_mesh_compression).
struct DracoPrimitive {
    std::string bytes;  ///< the Draco bitstream (empty once written to a spill file)
    std::uint64_t length = 0, vertices = 0, triangles = 0;
    PositionBounds bounds;
    int position_id = -1, normal_id = -1, confidence_id = -1, intensity_id = -1, level_id = -1;  ///< Draco attribute ids
};
/// `mesh` (its attributes as `layout` has them) compressed: positions to 1 mm, normals to 10 bits,
/// confidence to 10 bits and intensity to 12 bits over their ranges, levels exact. Throws InvalidInput if Draco refuses.
DracoPrimitive draco_primitive(const Mesh& mesh, const GlbLayout& layout);

/// The JSON chunk of one plain primitive (vertex records then indices in the binary chunk).
std::string glb_json(const GlbLayout& layout, std::uint64_t vertices, std::uint64_t triangles, const PositionBounds& bounds);
/// The JSON chunk of Draco primitives, their bitstreams in order in the binary chunk, each padded
/// to 4 bytes.
std::string glb_json(const GlbLayout& layout, std::span<const DracoPrimitive> primitives);
/// Bytes the binary chunk holds for one plain primitive, and for Draco primitives.
std::uint64_t glb_binary_length(const GlbLayout& layout, std::uint64_t vertices, std::uint64_t triangles);
std::uint64_t glb_binary_length(std::span<const DracoPrimitive> primitives);
/// The 12-byte header, the JSON chunk, and the binary chunk's 8-byte header (its content follows).
/// Throws InvalidInput past glTF's 4 GiB.
void write_glb_header(std::ostream& out, const std::string& json, std::uint64_t binary_length);
/// Zero bytes padding `length` to a multiple of 4.
void write_glb_padding(std::ostream& out, std::uint64_t length);

}  // namespace lidarsurf::detail
