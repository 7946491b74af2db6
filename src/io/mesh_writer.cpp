#include "lidarsurf/io/mesh_writer.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <string>
#include <vector>

#include "byte_reader.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "ply_format.hpp"

namespace lidarsurf {

MeshFormat parse_mesh_format(std::string_view name) {
    const std::string s = detail::lower(name);
    if (s == "auto") return MeshFormat::Auto;
    if (s == "ply" || s == "ply-binary") return MeshFormat::PlyBinary;
    if (s == "ply-ascii") return MeshFormat::PlyAscii;
    if (s == "obj") return MeshFormat::Obj;
    throw InvalidArgument("unknown mesh format '" + std::string(name) + "' (expected ply, ply-ascii or obj)");
}

namespace {

// Appends v's bytes at `at` (PLY binary_little_endian; the supported targets are little endian).
template <typename T>
char* put(char* at, T v) {
    std::memcpy(at, &v, sizeof(T));
    return at + sizeof(T);
}

// Float32 keeps ~1e-3 m at 1e4 m; beyond that, vertices are written as double.
bool needs_double(const Mesh& mesh) {
    for (const auto& v : mesh.vertices)
        if (v.cwiseAbs().maxCoeff() > 1e4) return true;
    return false;
}

}  // namespace

void write_ply(const Mesh& mesh, std::ostream& out, bool binary) {
    mesh.check();
    const bool dbl = needs_double(mesh);
    const bool has_n = !mesh.normals.empty(), has_k = !mesh.levels.empty(), has_c = !mesh.confidence.empty();
    out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
        << "comment lidarsurf mesh; level = neighbourhood level k', confidence = Eq. (3) value\n"
        << "element vertex " << mesh.vertices.size() << "\n";
    const char* t = dbl ? "double" : "float";
    out << "property " << t << " x\nproperty " << t << " y\nproperty " << t << " z\n";
    if (has_n) out << "property float nx\nproperty float ny\nproperty float nz\n";
    if (has_k) out << "property uchar level\n";
    if (has_c) out << "property float confidence\n";
    out << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    if (binary) {
        // The body is laid out in 1 MiB pieces, each written at once: a stream write per value cost
        // ~12 ms per KITTI frame (about 1 M calls), more than marching cubes, and a buffer of the
        // whole body doubled the mesh's memory at the end of a run.
        const std::size_t vertex_bytes = 3 * (dbl ? sizeof(double) : sizeof(float)) + (has_n ? 3 * sizeof(float) : 0) +
                                         (has_k ? sizeof(std::uint8_t) : 0) + (has_c ? sizeof(float) : 0);
        constexpr std::size_t kFaceBytes = sizeof(std::uint8_t) + 3 * sizeof(std::int32_t);
        constexpr std::size_t kPiece = std::size_t{1} << 20;
        std::vector<char> piece(kPiece);
        char* at = piece.data();
        const auto room_for = [&](std::size_t bytes) {
            if (static_cast<std::size_t>(at - piece.data()) + bytes <= piece.size()) return;
            out.write(piece.data(), at - piece.data());
            at = piece.data();
        };
        for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
            room_for(vertex_bytes);
            const auto& v = mesh.vertices[i];
            for (int a = 0; a < 3; ++a) at = dbl ? put<double>(at, v[a]) : put<float>(at, static_cast<float>(v[a]));
            if (has_n) for (int a = 0; a < 3; ++a) at = put<float>(at, mesh.normals[i][a]);
            if (has_k) at = put<std::uint8_t>(at, mesh.levels[i]);
            if (has_c) at = put<float>(at, mesh.confidence[i]);
        }
        for (const auto& tri : mesh.triangles) {
            room_for(kFaceBytes);
            at = put<std::uint8_t>(at, 3);
            for (auto i : tri) at = put<std::int32_t>(at, static_cast<std::int32_t>(i));
        }
        out.write(piece.data(), at - piece.data());
        return;
    }
    out << std::setprecision(dbl ? 15 : 9);
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const auto& v = mesh.vertices[i];
        out << v.x() << ' ' << v.y() << ' ' << v.z();
        if (has_n) out << ' ' << mesh.normals[i].x() << ' ' << mesh.normals[i].y() << ' ' << mesh.normals[i].z();
        if (has_k) out << ' ' << static_cast<int>(mesh.levels[i]);
        if (has_c) out << ' ' << mesh.confidence[i];
        out << '\n';
    }
    for (const auto& tri : mesh.triangles) out << "3 " << tri[0] << ' ' << tri[1] << ' ' << tri[2] << '\n';
}

void write_obj(const Mesh& mesh, std::ostream& out) {
    mesh.check();
    out << "# lidarsurf mesh\n" << std::setprecision(needs_double(mesh) ? 15 : 9);
    for (const auto& v : mesh.vertices) out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
    for (const auto& n : mesh.normals) out << "vn " << n.x() << ' ' << n.y() << ' ' << n.z() << '\n';
    const bool has_n = !mesh.normals.empty();
    for (const auto& t : mesh.triangles) {
        out << 'f';
        for (auto i : t) {
            out << ' ' << i + 1;
            if (has_n) out << "//" << i + 1;
        }
        out << '\n';
    }
}

MeshFormat mesh_format_for(const std::filesystem::path& path, MeshFormat format) {
    if (format != MeshFormat::Auto) return format;
    const std::string ext = detail::lower(path.extension().string());
    if (ext == ".ply") return MeshFormat::PlyBinary;
    if (ext == ".obj") return MeshFormat::Obj;
    throw InvalidArgument(path.string() + ": unknown mesh extension '" + ext +
                          "' (lidarsurf writes .ply and .obj; name the format with --mesh-format ply|ply-ascii|obj)");
}

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, MeshFormat format) {
    AtomicFile file(path);  // first: a directory or an unwritable place is the file system's error
    format = mesh_format_for(path, format);  // the stream writers check the mesh; a throw removes the temporary
    if (format == MeshFormat::Obj) write_obj(mesh, file.stream());
    else write_ply(mesh, file.stream(), format == MeshFormat::PlyBinary);
    file.commit();
}

Mesh read_mesh(const std::filesystem::path& path) {
    const std::string name = path.string();
    const bool obj = detail::lower(path.extension().string()) == ".obj";
    return parse_mesh(detail::read_file(name), obj ? MeshFormat::Obj : MeshFormat::PlyBinary, name);
}

Mesh parse_mesh(std::string_view data, MeshFormat format, const std::string& name) {
    Mesh mesh;
    if (format != MeshFormat::Obj) {
        auto content = detail::parse_ply(data, name, true);
        mesh.vertices = std::move(content.vertices);
        mesh.triangles = std::move(content.triangles);
        if (content.levels.size() == mesh.vertices.size()) mesh.levels = std::move(content.levels);
        if (content.confidence.size() == mesh.vertices.size()) mesh.confidence = std::move(content.confidence);
        return mesh;
    }
    std::string_view rest = data;
    std::size_t line_no = 0;
    while (!rest.empty()) {
        const std::string_view line = detail::next_line(rest);
        ++line_no;
        detail::Tokens tk(line);
        std::string_view word, tok;
        if (!tk.next(word)) continue;
        if (word == "v") {
            Eigen::Vector3d p;
            for (int a = 0; a < 3; ++a)
                if (!tk.next(tok) || !detail::parse_double(tok, p[a])) throw FormatError(name + ": line " + std::to_string(line_no) + ": bad vertex");
            mesh.vertices.push_back(p);
        } else if (word == "f") {
            std::vector<std::uint32_t> idx;
            while (tk.next(tok)) {
                double v;
                if (!detail::parse_double(tok.substr(0, tok.find('/')), v) || v == 0 || v != std::floor(v) || std::fabs(v) > 4e9)
                    throw FormatError(name + ": line " + std::to_string(line_no) + ": bad face index");
                const double i = v > 0 ? v - 1 : static_cast<double>(mesh.vertices.size()) + v;
                if (i < 0 || i >= static_cast<double>(mesh.vertices.size())) throw FormatError(name + ": line " + std::to_string(line_no) + ": face index out of range");
                idx.push_back(static_cast<std::uint32_t>(i));
            }
            for (std::size_t j = 1; j + 1 < idx.size(); ++j) mesh.triangles.push_back({idx[0], idx[j], idx[j + 1]});
        }
    }
    if (mesh.vertices.empty()) throw FormatError(name + ": OBJ file has no vertices");
    return mesh;
}

}  // namespace lidarsurf
