#include "lidarsurf/io/mesh_writer.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <functional>
#include <iomanip>
#include <string>
#include <vector>

#include "byte_reader.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/glb_writer.hpp"
#include "ply_format.hpp"
#include "ply_writer.hpp"

namespace lidarsurf {

MeshFormat parse_mesh_format(std::string_view name) {
    const std::string s = detail::lower(name);
    if (s == "auto") return MeshFormat::Auto;
    if (s == "ply" || s == "ply-binary") return MeshFormat::PlyBinary;
    if (s == "ply-ascii") return MeshFormat::PlyAscii;
    if (s == "obj") return MeshFormat::Obj;
    if (s == "glb") return MeshFormat::Glb;
    if (s == "glb-draco") return MeshFormat::GlbDraco;
    throw InvalidArgument("unknown mesh format '" + std::string(name) + "' (expected ply, ply-ascii, obj, glb or glb-draco)");
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

namespace detail {

PlyLayout PlyLayout::of(const Mesh& mesh, bool binary, bool dbl) {
    return {binary, dbl, !mesh.normals.empty(), !mesh.levels.empty(), !mesh.confidence.empty(), !mesh.intensity.empty()};
}

void write_ply_header(std::ostream& out, const PlyLayout& l, std::uint64_t vertices, std::uint64_t faces) {
    out << "ply\nformat " << (l.binary ? "binary_little_endian" : "ascii") << " 1.0\n"
        << "comment lidarsurf mesh; level = neighbourhood level k', confidence = Eq. (3) value, intensity = the returns' mean\n"
        << "element vertex " << vertices << "\n";
    const char* t = l.dbl ? "double" : "float";
    out << "property " << t << " x\nproperty " << t << " y\nproperty " << t << " z\n";
    if (l.normals) out << "property float nx\nproperty float ny\nproperty float nz\n";
    if (l.levels) out << "property uchar level\n";
    if (l.confidence) out << "property float confidence\n";
    if (l.intensity) out << "property float intensity\n";
    out << "element face " << faces << "\nproperty list uchar int vertex_indices\nend_header\n";
}

// The body is laid out in 1 MiB pieces, each written at once: a stream write per value cost
// ~12 ms per KITTI frame (about 1 M calls), more than marching cubes, and a buffer of the
// whole body doubled the mesh's memory at the end of a run.
void write_ply_vertices(std::ostream& out, const PlyLayout& l, const Mesh& mesh, std::span<const std::int64_t> existing) {
    const auto written = [&](std::size_t i) { return !existing.empty() && existing[i] >= 0; };
    if (!l.binary) {
        out << std::setprecision(l.dbl ? 15 : 9);
        for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
            if (written(i)) continue;
            const auto& v = mesh.vertices[i];
            out << v.x() << ' ' << v.y() << ' ' << v.z();
            if (l.normals) out << ' ' << mesh.normals[i].x() << ' ' << mesh.normals[i].y() << ' ' << mesh.normals[i].z();
            if (l.levels) out << ' ' << static_cast<int>(mesh.levels[i]);
            if (l.confidence) out << ' ' << mesh.confidence[i];
            if (l.intensity) out << ' ' << mesh.intensity[i];
            out << '\n';
        }
        return;
    }
    const std::size_t vertex_bytes = 3 * (l.dbl ? sizeof(double) : sizeof(float)) + (l.normals ? 3 * sizeof(float) : 0) +
                                     (l.levels ? sizeof(std::uint8_t) : 0) + (l.confidence ? sizeof(float) : 0) + (l.intensity ? sizeof(float) : 0);
    constexpr std::size_t kPiece = std::size_t{1} << 20;
    std::vector<char> piece(kPiece);
    char* at = piece.data();
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        if (written(i)) continue;
        if (static_cast<std::size_t>(at - piece.data()) + vertex_bytes > piece.size()) out.write(piece.data(), at - piece.data()), at = piece.data();
        const auto& v = mesh.vertices[i];
        for (int a = 0; a < 3; ++a) at = l.dbl ? put<double>(at, v[a]) : put<float>(at, static_cast<float>(v[a]));
        if (l.normals) for (int a = 0; a < 3; ++a) at = put<float>(at, mesh.normals[i][a]);
        if (l.levels) at = put<std::uint8_t>(at, mesh.levels[i]);
        if (l.confidence) at = put<float>(at, mesh.confidence[i]);
        if (l.intensity) at = put<float>(at, mesh.intensity[i]);
    }
    out.write(piece.data(), at - piece.data());
}

void write_ply_faces(std::ostream& out, const PlyLayout& l, std::span<const std::array<std::uint32_t, 3>> triangles,
                     const std::function<std::uint64_t(std::uint32_t)>& index) {
    const auto checked = [&](std::uint32_t i) {
        const std::uint64_t g = index ? index(i) : i;
        if (g > static_cast<std::uint64_t>(INT32_MAX)) throw InvalidInput("PLY: more than 2^31 vertices");
        return static_cast<std::int32_t>(g);
    };
    if (!l.binary) {
        for (const auto& tri : triangles) out << "3 " << checked(tri[0]) << ' ' << checked(tri[1]) << ' ' << checked(tri[2]) << '\n';
        return;
    }
    constexpr std::size_t kFaceBytes = sizeof(std::uint8_t) + 3 * sizeof(std::int32_t);
    constexpr std::size_t kPiece = std::size_t{1} << 20;
    std::vector<char> piece(kPiece);
    char* at = piece.data();
    for (const auto& tri : triangles) {
        if (static_cast<std::size_t>(at - piece.data()) + kFaceBytes > piece.size()) out.write(piece.data(), at - piece.data()), at = piece.data();
        at = put<std::uint8_t>(at, 3);
        for (auto i : tri) at = put<std::int32_t>(at, checked(i));
    }
    out.write(piece.data(), at - piece.data());
}

}  // namespace detail

void write_ply(const Mesh& mesh, std::ostream& out, bool binary) {
    mesh.check();
    const detail::PlyLayout l = detail::PlyLayout::of(mesh, binary, needs_double(mesh));
    detail::write_ply_header(out, l, mesh.vertices.size(), mesh.triangles.size());
    detail::write_ply_vertices(out, l, mesh, {});
    detail::write_ply_faces(out, l, mesh.triangles, {});
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
    if (ext == ".glb") return MeshFormat::Glb;
    throw InvalidArgument(path.string() + ": unknown mesh extension '" + ext +
                          "' (lidarsurf writes .ply, .obj and .glb; name the format with --mesh-format ply|ply-ascii|obj|glb|glb-draco)");
}

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, MeshFormat format) {
    AtomicFile file(path);  // first: a directory or an unwritable place is the file system's error
    format = mesh_format_for(path, format);  // the stream writers check the mesh; a throw removes the temporary
    if (format == MeshFormat::Obj) write_obj(mesh, file.stream());
    else if (format == MeshFormat::Glb || format == MeshFormat::GlbDraco) write_glb(mesh, file.stream(), format == MeshFormat::GlbDraco);
    else write_ply(mesh, file.stream(), format == MeshFormat::PlyBinary);
    file.commit();
}

Mesh read_mesh(const std::filesystem::path& path) {
    const std::string name = path.string();
    const std::string ext = detail::lower(path.extension().string());
    if (ext == ".glb") throw InvalidArgument(name + ": lidarsurf writes glTF but reads meshes as PLY or OBJ");
    const bool obj = ext == ".obj";
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
        if (content.intensity.size() == mesh.vertices.size()) mesh.intensity = std::move(content.intensity);
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
