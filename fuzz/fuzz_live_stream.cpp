// libFuzzer harness for the live stream's reader (viz/live_stream.hpp): what a client of
// `fuse --serve` decodes, meshoptimizer's codecs included. Every triangle index lies within its
// block, and a message read back encodes to one that reads back with the same blocks and counts.
#include <vector>

#include "fuzz_common.hpp"
#include "lidarsurf/viz/live_stream.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::expect_typed([&] {
        const live_stream::Message m = live_stream::decode({data, size});
        std::vector<std::string> bodies;
        for (const MeshBlock& b : m.changed) {
            b.mesh.check();
            bodies.push_back(live_stream::encode_block(b, m.header.origin));
        }
        std::vector<const std::string*> blocks;
        for (const std::string& b : bodies) blocks.push_back(&b);
        const std::string again = live_stream::encode_message(m.header, m.trajectory, m.removed, blocks);
        const live_stream::Message back = live_stream::decode({reinterpret_cast<const std::uint8_t*>(again.data()), again.size()});
        fuzz::require(back.changed.size() == m.changed.size() && back.removed.size() == m.removed.size() && back.trajectory.size() == m.trajectory.size(),
                      "a message read back encodes to another one");
        for (std::size_t i = 0; i < m.changed.size(); ++i)
            fuzz::require(back.changed[i].mesh.triangles.size() == m.changed[i].mesh.triangles.size(), "a block read back encodes with other triangles");
    });
    return 0;
}
