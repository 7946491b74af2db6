#pragma once
// A mesh written part by part (the tiles of a map, tiles/tiles.hpp): memory holds one part, never
// the whole mesh. The output appears whole at commit() or not at all, as write_mesh's: PLY's
// header counts come first, so its vertex and face records wait in a temporary directory beside
// the output until commit() writes the header and copies them behind it; OBJ goes straight to
// the output's temporary; binary glTF's JSON comes first too, so its records (or, with Draco, one
// compressed primitive a part) wait likewise.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>

#include "lidarsurf/io/atomic_file.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/mesh/mesh.hpp"

namespace lidarsurf {

class MeshStreamWriter {
public:
    /// `format` as write_mesh's (Auto: from the extension). `double_coordinates`: coordinates as
    /// double (PLY) or with 15 digits; decided before the first part because the header comes
    /// first (write_mesh's rule: when a coordinate can pass 1e4 m; glTF keeps its offsets from the
    /// first vertex, whatever this says). Throws IoError if the
    /// output's directory is not writable, InvalidArgument for an unknown extension.
    MeshStreamWriter(const std::filesystem::path& path, MeshFormat format, bool double_coordinates);
    ~MeshStreamWriter();
    MeshStreamWriter(const MeshStreamWriter&) = delete;
    MeshStreamWriter& operator=(const MeshStreamWriter&) = delete;

    /// Appends `part`. Its vertices whose `existing` entry is -1 are written, numbered from
    /// vertices() in order; one with an entry >= 0 is the vertex written earlier with that index
    /// (empty `existing`: every vertex is new). Every part with triangles must carry the same
    /// attributes as the first (InvalidArgument otherwise). Draco-compressed glTF takes each part
    /// whole as one primitive (glb_writer.hpp), its seam vertices repeated.
    void append(const Mesh& part, std::span<const std::int64_t> existing = {});

    std::uint64_t vertices() const { return vertices_; }
    std::uint64_t triangles() const { return triangles_; }

    /// Puts the whole mesh at the path. Throws IoError.
    void commit();

private:
    MeshFormat format_;
    bool dbl_;
    bool has_layout_ = false;
    bool normals_ = false, levels_ = false, confidence_ = false, intensity_ = false;
    std::uint64_t vertices_ = 0, triangles_ = 0;
    std::unique_ptr<AtomicFile> out_;
    std::unique_ptr<AtomicDirectory> spill_;  // PLY: the records until commit()
    std::ofstream vertex_records_, face_records_;  // glTF with Draco: the primitives in vertex_records_
    struct Glb;
    std::unique_ptr<Glb> glb_;  // glTF: the layout, bounds and primitives written so far
};

}  // namespace lidarsurf
