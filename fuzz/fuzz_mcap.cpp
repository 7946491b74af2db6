// libFuzzer harness for MCAP files: the records and their lengths, chunks (zstd, lz4 and
// uncompressed: the declared sizes, the CRC), schemas and channels, the summary section, and the
// CDR PointCloud2 decoder on every message of a PointCloud2 channel.
#include <cstdio>

#include "fuzz_common.hpp"
#include "lidarsurf/io/mcap.hpp"
#include "lidarsurf/io/point_cloud2.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    std::FILE* f = fmemopen(const_cast<std::uint8_t*>(data), size, "rb");
    if (!f) return 0;
    fuzz::expect_typed([&] {
        McapReader summary(f, "fuzz.mcap");
        summary.read_summary_channels();
    });
    std::rewind(f);
    fuzz::expect_typed([&] {
        McapReader reader(f, "fuzz.mcap");
        McapMessage m;
        while (reader.next(m)) {
            fuzz::require(m.channel != nullptr, "a message without its channel");
            if (m.channel->schema_name != "sensor_msgs/msg/PointCloud2") continue;
            fuzz::expect_typed([&] {
                const auto scan = decode_point_cloud2(parse_cdr_point_cloud2(m.data, "fuzz message"), "fuzz message");
                for (const auto& p : scan.cloud.points) fuzz::require(p.allFinite(), "a point that is not finite");
            });
        }
    });
    std::fclose(f);
    return 0;
}
