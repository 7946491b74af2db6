// libFuzzer harness for the point-cloud readers. One source, four binaries: LIDARSURF_FUZZ_FORMAT
// selects KITTI .bin, PLY, PCD or XYZ/CSV text (each gets its own corpus and coverage).
#include "fuzz_common.hpp"
#include "lidarsurf/io/point_reader.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::expect_typed([&] {
        std::string_view in = fuzz::as_view(data, size);
#if LIDARSURF_FUZZ_FORMAT == 0
        // The first byte picks the record width (3..8 floats; 4 = KITTI, 5 = nuScenes) and whether
        // the last value is read as the ring (as nuScenes stores it).
        if (in.empty()) return;
        const auto first = static_cast<unsigned char>(in.front());
        const int fields = 3 + first % 6;
        const int ring_field = (first / 6) % 2 == 1 && fields > 3 ? fields - 1 : -1;
        in.remove_prefix(1);
        const PointCloud cloud = parse_kitti_bin(in, fields, "fuzz.bin", ring_field);
        fuzz::require(cloud.points.size() * 4u * static_cast<unsigned>(fields) == in.size(), "bin: points * record != size");
        fuzz::require(cloud.rings.size() == (ring_field >= 0 ? cloud.points.size() : 0u), "bin: one ring per point");
#elif LIDARSURF_FUZZ_FORMAT == 1
        const PointCloud cloud = parse_ply_points(in, "fuzz.ply");
#elif LIDARSURF_FUZZ_FORMAT == 2
        const PointCloud cloud = parse_pcd_points(in, "fuzz.pcd");
#else
        const PointCloud cloud = parse_text_points(in, "fuzz.xyz");
#endif
        // No allocation beyond what the bytes can hold: a point costs at least one byte, or
        // (LZF-compressed PCD) at most ~100 bytes expanded from one compressed byte.
        fuzz::require(cloud.points.size() <= 100 * size + 16, "more points than the file can hold");
    });
    return 0;
}
