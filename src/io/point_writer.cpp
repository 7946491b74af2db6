#include "lidarsurf/io/point_writer.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>

#include "byte_reader.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_writer.hpp"

namespace lidarsurf {

bool is_point_extension(const std::filesystem::path& path) {
    const std::string ext = detail::lower(path.extension().string());
    return ext == ".bin" || ext == ".ply" || ext == ".pcd" || ext == ".xyz" || ext == ".txt" || ext == ".csv";
}

void write_points(const PointCloud& cloud, const std::filesystem::path& path) {
    const std::string ext = detail::lower(path.extension().string());
    if (!is_point_extension(path))
        throw InvalidArgument(path.string() + ": unknown point-file extension '" + ext + "' (lidarsurf writes .bin, .ply, .pcd, .xyz, .txt, .csv)");
    if (ext == ".ply") {
        Mesh m;
        m.vertices = cloud.points;
        write_mesh(m, path, MeshFormat::PlyBinary);
        return;
    }
    AtomicFile file(path);
    std::ostream& out = file.stream();
    if (ext == ".xyz" || ext == ".txt" || ext == ".csv") {
        char line[96];
        const char* format = ext == ".csv" ? "%.17g,%.17g,%.17g\n" : "%.17g %.17g %.17g\n";
        if (ext == ".csv") out << "x,y,z\n";
        for (const auto& p : cloud.points) {
            const int n = std::snprintf(line, sizeof line, format, p.x(), p.y(), p.z());
            out.write(line, n);
        }
    } else if (ext == ".pcd") {
        out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH "
            << cloud.points.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << cloud.points.size() << "\nDATA binary\n";
        for (const auto& p : cloud.points) {
            const float rec[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
            out.write(reinterpret_cast<const char*>(rec), sizeof(rec));
        }
    } else {
        const bool intensity = cloud.intensities.size() == cloud.points.size();
        for (std::size_t i = 0; i < cloud.points.size(); ++i) {
            const Eigen::Vector3d& p = cloud.points[i];
            const float rec[4] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), intensity ? cloud.intensities[i] : 0.0f};
            out.write(reinterpret_cast<const char*>(rec), sizeof(rec));
        }
    }
    file.commit();
}

}  // namespace lidarsurf
