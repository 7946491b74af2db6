#include "lidarsurf/io/point_writer.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "byte_reader.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_writer.hpp"

namespace lidarsurf {

void write_points(const PointCloud& cloud, const std::filesystem::path& path) {
    if (detail::lower(path.extension().string()) == ".ply") {
        Mesh m;
        m.vertices = cloud.points;
        write_mesh(m, path, MeshFormat::PlyBinary);
        return;
    }
    AtomicFile file(path);
    for (const auto& p : cloud.points) {
        const float rec[4] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), 0.0f};
        file.stream().write(reinterpret_cast<const char*>(rec), sizeof(rec));
    }
    file.commit();
}

}  // namespace lidarsurf
