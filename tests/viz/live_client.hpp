#pragma once
// A client of the live stream for the tests: decodes the messages (viz/live_stream.hpp) into its
// own copy of the blocks, and compares blocks with what was published (float32 positions).
#include <gtest/gtest.h>

#include <string>
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

/// The same blocks (keys, triangles, levels) with vertices within 0.1 mm.
inline void expect_same_blocks(const std::vector<MeshBlock>& got, const std::vector<MeshBlock>& expected, const std::string& what) {
    ASSERT_EQ(got.size(), expected.size()) << what;
    for (std::size_t i = 0; i < got.size(); ++i) {
        ASSERT_TRUE(got[i].key == expected[i].key) << what << ": block " << i;
        const Mesh &a = got[i].mesh, &b = expected[i].mesh;
        ASSERT_TRUE(a.triangles == b.triangles) << what << ": block " << i;
        ASSERT_EQ(a.vertices.size(), b.vertices.size()) << what;
        for (std::size_t v = 0; v < a.vertices.size(); ++v) ASSERT_LT((a.vertices[v] - b.vertices[v]).norm(), 1e-4) << what;
        if (!b.levels.empty()) {
            ASSERT_TRUE(a.levels == b.levels) << what;
        }
    }
}

}  // namespace lidarsurf::test
