// libFuzzer harness for sensor_msgs/PointCloud2 messages as a ROS 1 bag stores them (or, built
// with LIDARSURF_FUZZ_CDR, as ROS 2 does: CDR): the serialization (every length, alignment, the
// encapsulation) and the decoder (field layouts, types, endianness, organized clouds, per-point
// times).
#include "fuzz_common.hpp"
#include "lidarsurf/io/point_cloud2.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::expect_typed([&] {
#ifdef LIDARSURF_FUZZ_CDR
        const PointCloud2Message m = parse_cdr_point_cloud2({data, size}, "fuzz message");
#else
        const PointCloud2Message m = parse_ros1_point_cloud2({data, size}, "fuzz message");
#endif
        fuzz::require(m.data.size() <= size, "data beyond the message");
        std::size_t empty = 0;
        const RecordedScan scan = decode_point_cloud2(m, "fuzz message", &empty);
        fuzz::require(scan.cloud.points.size() + empty == std::size_t{m.width} * m.height, "every point kept or counted as no return");
        fuzz::require(scan.times.empty() || scan.times.size() == scan.cloud.points.size(), "a time a point, or none");
        for (const auto& p : scan.cloud.points) fuzz::require(p.allFinite(), "a point that is not finite");
    });
    return 0;
}
