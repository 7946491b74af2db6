#pragma once
// A client of the live stream for the tests: decodes the messages (viz/live_stream.hpp) into its
// own copy of the blocks, and compares blocks with what was published (the stream's quantized
// positions, its own vertex order).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "lidarsurf/viz/live_stream.hpp"
#include "lidarsurf/map/live_mesh.hpp"

namespace lidarsurf::test {

struct LiveClient {
    std::vector<MeshBlock> blocks;
    std::vector<live_stream::Message> headers_only;  // every message read, blocks dropped
    std::size_t trajectory = 0;
    bool final = false;

    void take(const std::string& bytes) {
        live_stream::Message m = live_stream::decode({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()});
        if (m.header.flags & live_stream::kReset) trajectory = 0;
        trajectory += m.trajectory.size();
        live_stream::apply(m, blocks);
        final = (m.header.flags & live_stream::kFinal) != 0;
        m.changed.clear();
        headers_only.push_back(std::move(m));
    }
};

/// How many triangles of `got` match no triangle of `sent` (each used once): the same corners in
/// the same cyclic order (orientation kept), each within `tolerance` metres, with the same level
/// and a confidence within `confidence_tolerance` (absolute). Vertex order
/// and numbering are free. Brute force within 1 cm cells of the centroids.
inline std::size_t unmatched_triangles(const Mesh& got, const Mesh& sent, double tolerance, double confidence_tolerance) {
    using Cell = std::tuple<long, long, long>;
    const auto centroid = [](const Mesh& m, std::size_t t) {
        return Eigen::Vector3d((m.vertices[m.triangles[t][0]] + m.vertices[m.triangles[t][1]] + m.vertices[m.triangles[t][2]]) / 3);
    };
    const auto cell = [](const Eigen::Vector3d& c) { return Cell{std::lround(std::floor(c.x() / 0.01)), std::lround(std::floor(c.y() / 0.01)), std::lround(std::floor(c.z() / 0.01))}; };
    std::map<Cell, std::vector<std::size_t>> grid;
    for (std::size_t t = 0; t < sent.triangles.size(); ++t) grid[cell(centroid(sent, t))].push_back(t);
    const auto corner_matches = [&](std::uint32_t a, std::uint32_t b) {
        if ((got.vertices[a] - sent.vertices[b]).cwiseAbs().maxCoeff() > tolerance) return false;
        if (!sent.levels.empty() && got.levels[a] != sent.levels[b]) return false;
        if (!sent.confidence.empty() && std::fabs(got.confidence[a] - sent.confidence[b]) > confidence_tolerance) return false;
        return true;
    };
    std::vector<bool> used(sent.triangles.size(), false);
    std::size_t missing = 0;
    for (std::size_t t = 0; t < got.triangles.size(); ++t) {
        const auto [cx, cy, cz] = cell(centroid(got, t));
        bool found = false;
        for (long dx = -1; dx <= 1 && !found; ++dx)
            for (long dy = -1; dy <= 1 && !found; ++dy)
                for (long dz = -1; dz <= 1 && !found; ++dz) {
                    const auto it = grid.find({cx + dx, cy + dy, cz + dz});
                    if (it == grid.end()) continue;
                    for (const std::size_t u : it->second) {
                        if (used[u]) continue;
                        for (int r = 0; r < 3 && !found; ++r)
                            found = corner_matches(got.triangles[t][0], sent.triangles[u][r]) && corner_matches(got.triangles[t][1], sent.triangles[u][(r + 1) % 3]) &&
                                    corner_matches(got.triangles[t][2], sent.triangles[u][(r + 2) % 3]);
                        if (found) {
                            used[u] = true;
                            break;
                        }
                    }
                }
        missing += !found;
    }
    return missing;
}

/// The block's confidence step in the stream: 1/65535 of its largest.
inline double confidence_step(const Mesh& m) {
    float c = 0;
    for (const float v : m.confidence) c = std::max(c, v);
    return c / 65535.0;
}

/// The same blocks (keys; triangles with their levels, corners within the stream's quarter of a
/// millimetre and confidence within its step).
inline void expect_same_blocks(const std::vector<MeshBlock>& got, const std::vector<MeshBlock>& expected, const std::string& what) {
    ASSERT_EQ(got.size(), expected.size()) << what;
    for (std::size_t i = 0; i < got.size(); ++i) {
        ASSERT_TRUE(got[i].key == expected[i].key) << what << ": block " << i;
        const Mesh &a = got[i].mesh, &b = expected[i].mesh;
        ASSERT_EQ(a.triangles.size(), b.triangles.size()) << what << ": block " << i;
        ASSERT_EQ(unmatched_triangles(a, b, 0.26e-3, confidence_step(b) + 1e-7), 0u) << what << ": block " << i;
    }
}

}  // namespace lidarsurf::test
