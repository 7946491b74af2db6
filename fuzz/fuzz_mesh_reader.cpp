// libFuzzer harness for the mesh reader (ground-truth scenes, evaluate, render): PLY with faces
// and OBJ, chosen by the first byte. Every triangle returned refers to an existing vertex.
#include "fuzz_common.hpp"
#include "lidarsurf/io/mesh_writer.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const MeshFormat format = (data[0] & 1) ? MeshFormat::Obj : MeshFormat::PlyBinary;
    fuzz::expect_typed([&] {
        const Mesh mesh = parse_mesh(fuzz::as_view(data + 1, size - 1), format, "fuzz.mesh");
        for (const auto& t : mesh.triangles)
            for (auto i : t) fuzz::require(i < mesh.vertices.size(), "face index out of range");
        fuzz::require(mesh.levels.empty() || mesh.levels.size() == mesh.vertices.size(), "levels size");
    });
    return 0;
}
