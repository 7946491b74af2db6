#include <gtest/gtest.h>

#include "lidarsurf/mesh/mesh_filter.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

// An n x n grid of unit quads (2 n^2 triangles, (n+1)^2 vertices) at height z, with attributes.
void add_grid(Mesh& m, int n, double z) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            m.vertices.emplace_back(i, j, z);
            m.normals.emplace_back(0.f, 0.f, 1.f);
            m.levels.push_back(static_cast<std::uint8_t>(n));
            m.confidence.push_back(static_cast<float>(z));
        }
    auto id = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
}

TEST(MeshFilter, SmallPiecesAreRemovedAndVerticesCompacted) {
    Mesh m;
    add_grid(m, 1, 5.0);   // 2 triangles
    add_grid(m, 10, 0.0);  // 200 triangles
    add_grid(m, 2, 9.0);   // 8 triangles
    m.vertices.emplace_back(100, 100, 100);  // unreferenced
    m.normals.emplace_back(0.f, 0.f, 1.f);
    m.levels.push_back(0);
    m.confidence.push_back(0.f);
    Mesh kept = m;
    EXPECT_EQ(remove_small_components(kept, 9), 10u);
    EXPECT_NO_THROW(kept.check());
    ASSERT_EQ(kept.triangles.size(), 200u);
    ASSERT_EQ(kept.vertices.size(), 121u);
    ASSERT_EQ(kept.levels.size(), 121u);
    ASSERT_EQ(kept.confidence.size(), 121u);
    ASSERT_EQ(kept.normals.size(), 121u);
    // The big grid, in its original order, with its attributes.
    for (std::size_t v = 0; v < 121; ++v) {
        EXPECT_EQ(kept.vertices[v], m.vertices[4 + v]);
        EXPECT_EQ(kept.levels[v], 10);
        EXPECT_EQ(kept.confidence[v], 0.f);
    }
    for (std::size_t t = 0; t < 200; ++t)
        for (int k = 0; k < 3; ++k) EXPECT_EQ(kept.vertices[kept.triangles[t][k]], m.vertices[m.triangles[2 + t][k]]);
    // A threshold the 8-triangle piece meets keeps it.
    Mesh two = m;
    EXPECT_EQ(remove_small_components(two, 8), 2u);
    EXPECT_EQ(two.triangles.size(), 208u);
}

TEST(MeshFilter, PiecesJoinedThroughOneVertexAreOnePiece) {
    Mesh m;
    m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    m.triangles = {{0, 1, 2}, {0, 3, 4}};  // two triangles sharing vertex 0 only
    EXPECT_EQ(remove_small_components(m, 2), 0u);
    EXPECT_EQ(remove_small_components(m, 3), 2u);
    EXPECT_TRUE(m.triangles.empty());
    EXPECT_TRUE(m.vertices.empty());
}

TEST(MeshFilter, ZeroOrOneKeepsEverything) {
    Mesh m;
    add_grid(m, 1, 0.0);
    for (std::size_t n : {0u, 1u}) {
        Mesh c = m;
        EXPECT_EQ(remove_small_components(c, n), 0u);
        EXPECT_EQ(c.vertices.size(), m.vertices.size());
        EXPECT_EQ(c.triangles, m.triangles);
    }
}

}  // namespace
