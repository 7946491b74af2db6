#pragma once
// A triangle-mesh world for the simulator and the renderer: ray casting with Embree 3 (Debian's
// libembree-dev). The mesh is copied into Embree's single-precision buffers, so hits are exact to
// float precision (about 1e-5 m at 100 m). A mesh with a per-vertex `intensity` gives each triangle
// the reflectivity of its first vertex (the procedural worlds' materials, sim/procedural_scene.hpp).
#include <limits>
#include <memory>

#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/sim/ray_scene.hpp"

namespace lidarsurf::sim {

struct RayHit {
    double range = 0;              ///< distance along the unit direction
    std::uint32_t triangle = 0;    ///< index into the mesh's triangles
    Eigen::Vector3d normal;        ///< unit geometric normal of that triangle (its winding)
    float reflectivity = std::numeric_limits<float>::quiet_NaN();  ///< that triangle's; NaN when the mesh has none
};

class MeshScene final : public RayScene {
public:
    /// Builds the acceleration structure. Throws InvalidInput on an empty or non-finite mesh.
    explicit MeshScene(const Mesh& mesh);
    ~MeshScene() override;
    MeshScene(MeshScene&&) noexcept;
    MeshScene& operator=(MeshScene&&) noexcept;
    MeshScene(const MeshScene&) = delete;
    MeshScene& operator=(const MeshScene&) = delete;

    std::optional<RayReturn> first_return(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                          double max_range) const override;
    /// As first_return, with the triangle hit and its normal.
    std::optional<RayHit> cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range) const;
    /// True if something blocks the open segment from `from` to `to`.
    bool occluded(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const;

    std::size_t triangle_count() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace lidarsurf::sim
