#pragma once
// Builds closed triangle meshes of simple solids (boxes, cylinders, ellipsoids, cones) and open
// height fields: the parts of the procedural scenes. Triangles are counter-clockwise seen from
// outside, so face normals point out of the solid. Each part can carry a reflectivity.
#include <functional>

#include <Eigen/Core>

#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf::sim {

class MeshBuilder {
public:
    /// Box centred at `centre` with half extents `half` (along its own axes), turned by `yaw`
    /// radians about +z.
    void box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half, double yaw = 0);
    /// Axis-aligned box from its two corners.
    void box_between(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
    /// Capped cylinder from `a` to `b` with the given radius, `segments` sides.
    void cylinder(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, int segments = 12);
    /// Capped cone: base disc at `base` (radius), apex at `apex`.
    void cone(const Eigen::Vector3d& base, const Eigen::Vector3d& apex, double radius, int segments = 12);
    /// Ellipsoid with semi-axes `radii` along x, y, z; `rings` latitude bands.
    void ellipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& radii, int rings = 8);
    /// Open height field z = height(x, y) over [x0, x1] x [y0, y1] with the given cell size,
    /// facing +z.
    void height_field(double x0, double x1, double y0, double y1, double cell,
                      const std::function<double(double, double)>& height);
    /// Appends another mesh: vertices, triangles and, once reflectivity is on, the other mesh's
    /// per-vertex intensity (the current reflectivity where it has none).
    void append(const Mesh& other);
    /// The reflectivity in [0, 1] of what is built from now on, kept as the mesh's per-vertex
    /// `intensity` (what MeshScene reports for a ray that hits it). Off until first set; the
    /// vertices built before then get kDefaultReflectivity. InvalidArgument outside [0, 1].
    void set_reflectivity(float reflectivity);
    static constexpr float kDefaultReflectivity = 0.2f;

    const Mesh& mesh() const { return mesh_; }
    Mesh take() { return std::move(mesh_); }

private:
    std::uint32_t vertex(const Eigen::Vector3d& p);
    void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c);
    void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d);  ///< a b c d counter-clockwise

    Mesh mesh_;
    bool reflective_ = false;
    float reflectivity_ = kDefaultReflectivity;
};

}  // namespace lidarsurf::sim
