#include "lidarsurf/io/point_writer.hpp"

#include <algorithm>
#include <cctype>
#include <cstring>

#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_writer.hpp"

namespace lidarsurf {

void write_points(const PointCloud& cloud, const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".ply") {
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
