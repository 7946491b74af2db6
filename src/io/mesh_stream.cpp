#include "lidarsurf/io/mesh_stream.hpp"

#include <iomanip>
#include <vector>

#include "glb_format.hpp"
#include "lidarsurf/core/errors.hpp"
#include "ply_writer.hpp"

namespace lidarsurf {

struct MeshStreamWriter::Glb {
    detail::GlbLayout layout;
    detail::PositionBounds bounds;
    std::vector<detail::DracoPrimitive> draco;  // their bytes in vertex_records_
};

namespace {

bool is_glb(MeshFormat f) { return f == MeshFormat::Glb || f == MeshFormat::GlbDraco; }

}  // namespace

MeshStreamWriter::MeshStreamWriter(const std::filesystem::path& path, MeshFormat format, bool double_coordinates)
    : dbl_(double_coordinates) {
    out_ = std::make_unique<AtomicFile>(path);
    format_ = mesh_format_for(path, format);
    if (format_ == MeshFormat::Obj) {
        out_->stream() << "# lidarsurf mesh\n" << std::setprecision(dbl_ ? 15 : 9);
        return;
    }
    if (is_glb(format_)) glb_ = std::make_unique<Glb>();
    // Never committed: the directory goes with the writer, or with the process on a signal.
    const std::filesystem::path dir = out_->destination().parent_path();
    spill_ = std::make_unique<AtomicDirectory>((dir.empty() ? std::filesystem::path(".") : dir) / (out_->destination().filename().string() + ".parts"));
    vertex_records_.open(spill_->path() / "vertices", std::ios::binary);
    face_records_.open(spill_->path() / "faces", std::ios::binary);
    if (!vertex_records_ || !face_records_) throw IoError(spill_->path().string() + ": cannot write the mesh's records");
}

MeshStreamWriter::~MeshStreamWriter() = default;

void MeshStreamWriter::append(const Mesh& part, std::span<const std::int64_t> existing) {
    part.check();
    if (!existing.empty() && existing.size() != part.vertices.size())
        throw InvalidArgument("MeshStreamWriter: one `existing` entry per vertex of the part");
    if (part.triangles.empty()) return;
    const bool n = !part.normals.empty(), k = !part.levels.empty(), c = !part.confidence.empty(), g = !part.intensity.empty();
    if (!has_layout_) {
        has_layout_ = true, normals_ = n, levels_ = k, confidence_ = c, intensity_ = g;
        if (glb_) glb_->layout = detail::GlbLayout::of(part);
    } else if (n != normals_ || k != levels_ || c != confidence_ || g != intensity_) {
        throw InvalidArgument("MeshStreamWriter: a part with other vertex attributes than the first");
    }
    // The part's vertex i is written as index[i].
    std::vector<std::uint64_t> index(part.vertices.size());
    std::uint64_t next = vertices_;
    for (std::size_t i = 0; i < index.size(); ++i) {
        if (!existing.empty() && existing[i] >= 0) {
            if (static_cast<std::uint64_t>(existing[i]) >= vertices_) throw InvalidArgument("MeshStreamWriter: an existing vertex not written yet");
            index[i] = static_cast<std::uint64_t>(existing[i]);
        } else {
            index[i] = next++;
        }
    }
    if (format_ == MeshFormat::Obj) {
        std::ostream& out = out_->stream();
        for (std::size_t i = 0; i < index.size(); ++i) {
            if (index[i] < vertices_) continue;
            const auto& v = part.vertices[i];
            out << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
            if (normals_) out << "vn " << part.normals[i].x() << ' ' << part.normals[i].y() << ' ' << part.normals[i].z() << '\n';
        }
        for (const auto& t : part.triangles) {
            out << 'f';
            for (auto i : t) {
                out << ' ' << index[i] + 1;
                if (normals_) out << "//" << index[i] + 1;
            }
            out << '\n';
        }
    } else if (format_ == MeshFormat::GlbDraco) {
        detail::DracoPrimitive p = detail::draco_primitive(part, glb_->layout);
        vertex_records_.write(p.bytes.data(), static_cast<std::streamsize>(p.bytes.size()));
        detail::write_glb_padding(vertex_records_, p.length);
        p.bytes = {};
        glb_->draco.push_back(std::move(p));
    } else if (format_ == MeshFormat::Glb) {
        detail::write_glb_vertices(vertex_records_, glb_->layout, part, existing, &glb_->bounds);
        detail::write_glb_indices(face_records_, part.triangles, [&](std::uint32_t i) { return index[i]; });
    } else {
        const detail::PlyLayout l{format_ == MeshFormat::PlyBinary, dbl_, normals_, levels_, confidence_, intensity_};
        detail::write_ply_vertices(vertex_records_, l, part, existing);
        detail::write_ply_faces(face_records_, l, part.triangles, [&](std::uint32_t i) { return index[i]; });
    }
    if (spill_ && (!vertex_records_ || !face_records_)) throw IoError(spill_->path().string() + ": cannot write the mesh's records (disk full?)");
    vertices_ = next;
    triangles_ += part.triangles.size();
}

void MeshStreamWriter::commit() {
    if (format_ != MeshFormat::Obj) {
        vertex_records_.close();
        face_records_.close();
        if (!vertex_records_ || !face_records_) throw IoError(spill_->path().string() + ": cannot write the mesh's records (disk full?)");
        std::ostream& out = out_->stream();
        if (glb_ && triangles_ == 0) throw InvalidInput("glTF: the mesh has no triangle (a .glb's accessors need one)");
        if (format_ == MeshFormat::GlbDraco)
            detail::write_glb_header(out, detail::glb_json(glb_->layout, glb_->draco), detail::glb_binary_length(glb_->draco));
        else if (format_ == MeshFormat::Glb)
            detail::write_glb_header(out, detail::glb_json(glb_->layout, vertices_, triangles_, glb_->bounds),
                                     detail::glb_binary_length(glb_->layout, vertices_, triangles_));
        else
            detail::write_ply_header(out, {format_ == MeshFormat::PlyBinary, dbl_, normals_, levels_, confidence_, intensity_}, vertices_, triangles_);
        for (const char* name : {"vertices", "faces"}) {
            std::ifstream in(spill_->path() / name, std::ios::binary);
            if (!in) throw IoError((spill_->path() / name).string() + ": cannot read the mesh's records back");
            if (in.peek() != std::ifstream::traits_type::eof()) out << in.rdbuf();
        }
    }
    out_->commit();
    spill_.reset();  // the records go
}

}  // namespace lidarsurf
