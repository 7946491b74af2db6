#pragma once
// Internal: PLY parsing shared by the point reader and the mesh reader.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace lidarsurf::detail {

struct PlyContent {
    std::vector<Eigen::Vector3d> vertices;
    std::vector<std::array<std::uint32_t, 3>> triangles;  ///< polygons fanned into triangles
    std::vector<std::uint8_t> levels;                     ///< the vertex property `level` (k'), when present
    std::vector<float> confidence;                        ///< the vertex property `confidence` (Eq. 3), when present
    /// the vertex property `intensity` (or `reflectance`, `scalar_intensity`), when present
    std::vector<float> intensity;
};

/// Parses a PLY buffer; faces are read only when `want_faces`.
PlyContent parse_ply(std::string_view data, const std::string& name, bool want_faces);

}  // namespace lidarsurf::detail
