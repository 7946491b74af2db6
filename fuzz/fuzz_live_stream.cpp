// libFuzzer harness for the live stream's reader (viz/live_stream.hpp): what a client of
// `fuse --serve` decodes. A message read back encodes to the same bytes, and every triangle index
// lies within its block.
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
        fuzz::require(live_stream::encode_message(m.header, m.trajectory, m.removed, blocks).size() == size,
                      "a message read back encodes to another size");
    });
    return 0;
}
