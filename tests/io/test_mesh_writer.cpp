#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

Mesh tetrahedron(double offset = 0) {
    Mesh m;
    m.vertices = {{offset, 0, 0}, {offset + 1, 0, 0}, {offset, 1, 0}, {offset, 0, 1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    m.normals = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.levels = {1, 2, 3, 5};
    m.confidence = {0.5f, 1.0f, 2.0f, 4.0f};
    return m;
}

std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

TEST(MeshWriter, RoundTripsEveryFormat) {
    const test::TempDir dir("mesh");
    for (double offset : {0.0, 5e5}) {  // far from the origin the PLY switches to double
        const Mesh m = tetrahedron(offset);
        for (const auto& [file, fmt] : {std::pair{"a.ply", MeshFormat::PlyBinary}, {"b.ply", MeshFormat::PlyAscii}, {"c.obj", MeshFormat::Obj}}) {
            write_mesh(m, dir / file, fmt);
            const Mesh r = read_mesh(dir / file);
            ASSERT_EQ(r.vertices.size(), m.vertices.size()) << file;
            ASSERT_EQ(r.triangles, m.triangles) << file;
            for (std::size_t i = 0; i < m.vertices.size(); ++i) EXPECT_LT((r.vertices[i] - m.vertices[i]).norm(), 1e-6) << file;
            if (fmt != MeshFormat::Obj) {  // a PLY reads back k' and the confidence too
                EXPECT_EQ(r.levels, m.levels) << file;
                EXPECT_EQ(r.confidence, m.confidence) << file;
            }
        }
    }
    // The PLY keeps k' and confidence for colouring.
    const std::string header = slurp(dir / "b.ply");
    EXPECT_NE(header.find("property uchar level"), std::string::npos);
    EXPECT_NE(header.find("property float confidence"), std::string::npos);
}

TEST(MeshWriter, FailureLeavesPreviousOutputIntact) {
    const test::TempDir dir("atomic");
    const auto out = dir / "mesh.ply";
    write_mesh(tetrahedron(), out);
    const std::string before = slurp(out);
    Mesh bad = tetrahedron();
    bad.triangles.push_back({0, 1, 99});  // invalid index: refused before anything is written
    EXPECT_THROW(write_mesh(bad, out), InvalidInput);
    EXPECT_EQ(slurp(out), before);
    EXPECT_THROW(write_mesh(tetrahedron(), dir / "missing" / "mesh.ply"), IoError);
    EXPECT_THROW(write_mesh(tetrahedron(), dir), IoError);  // a directory
    std::size_t files = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
    EXPECT_EQ(files, 1u);  // no temporary left behind
}

}  // namespace

TEST(MeshReader, MalformedObjAndPlyFacesAreFormatErrors) {
    const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    // A face index of 1e300 was an out-of-range double -> long long conversion (UB) before the
    // check; found reviewing the parser for fuzz_mesh_reader.
    EXPECT_THROW(parse_mesh(v3 + "f 1e300 1 2\n", MeshFormat::Obj, "huge"), FormatError);
    EXPECT_THROW(parse_mesh(v3 + "f 1 2 4\n", MeshFormat::Obj, "range"), FormatError);
    EXPECT_THROW(parse_mesh(v3 + "f 1 2.5 3\n", MeshFormat::Obj, "fraction"), FormatError);
    EXPECT_EQ(parse_mesh(v3 + "f -3 -2 -1\n", MeshFormat::Obj, "relative").triangles.size(), 1u);
    const std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    EXPECT_EQ(parse_mesh(ply + "3 0 1 2\n", MeshFormat::PlyBinary, "ok").triangles.size(), 1u);
    EXPECT_THROW(parse_mesh(ply + "3 0 1 3\n", MeshFormat::PlyBinary, "range"), FormatError);
    EXPECT_THROW(parse_mesh(ply + "3 0 1 -1\n", MeshFormat::PlyBinary, "negative"), FormatError);
}
