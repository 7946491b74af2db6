#pragma once
// Renders a mesh to an image: one Embree ray per pixel from a perspective camera, Lambert shading
// with a key light and a head light, coloured by height, by the adaptive level k' or by intensity
// (a grey ramp over the 2nd-98th percentiles of the vertices' intensity; pale blue where a
// triangle has none).
#include <optional>
#include <string_view>

#include <Eigen/Core>

#include "lidarsurf/viz/png_writer.hpp"
#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf::viz {

enum class Colouring { Height, Level, Grey, Intensity };
Colouring parse_colouring(std::string_view name);  ///< height | level | grey | intensity

struct RenderConfig {
    int width = 1280, height = 720;
    std::optional<Eigen::Vector3d> eye;     ///< camera position (default: chosen from the mesh)
    std::optional<Eigen::Vector3d> target;  ///< point looked at (default: the mesh's median vertex)
    double fov_deg = 55.0;                  ///< horizontal field of view
    Colouring colouring = Colouring::Height;

    void validate() const;
};

/// Throws InvalidInput for a mesh without triangles; Colouring::Level needs mesh.levels,
/// Colouring::Intensity mesh.intensity.
Image render(const Mesh& mesh, const RenderConfig& config);

}  // namespace lidarsurf::viz
