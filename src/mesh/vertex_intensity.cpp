#include "lidarsurf/mesh/vertex_intensity.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <tbb/parallel_for.h>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {

void attach_intensity(Mesh& mesh, const VoxelGrid& grid, int reach) {
    if (!grid.has_intensity()) return;
    if (!mesh.levels.empty() && mesh.levels.size() != mesh.vertices.size())
        throw InvalidArgument("attach_intensity: the mesh's levels do not match its vertices");
    reach = std::max(reach, 1);
    const double alpha = grid.voxel_size();
    const Eigen::Vector3d origin = grid.origin();
    mesh.intensity.resize(mesh.vertices.size());
    const VoxelKey one = VoxelKey::Ones();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.vertices.size(), 1024), [&](const auto& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            // The nearer lattice vertex of the vertex's edge (within rounding for a vertex snapped to its plane).
            const VoxelKey v = ((mesh.vertices[i] - origin) / alpha).array().round().cast<int>();
            // H^k(v); where it holds no return, the next larger box, up to the reach.
            std::optional<double> mean;
            for (int k = std::clamp(mesh.levels.empty() ? 1 : static_cast<int>(mesh.levels[i]), 1, reach); !mean && k <= reach; ++k)
                mean = grid.mean_intensity(v - VoxelKey::Constant(k), v + VoxelKey::Constant(k) - one);
            mesh.intensity[i] = mean ? static_cast<float>(*mean) : std::numeric_limits<float>::quiet_NaN();
        }
    });
}

}  // namespace lidarsurf
