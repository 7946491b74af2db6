// libFuzzer harness for the KITTI poses reader: every pose returned is a finite rigid motion.
#include "fuzz_common.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    fuzz::expect_typed([&] {
        const auto poses = parse_poses(fuzz::as_view(data, size), "fuzz_poses.txt");
        fuzz::require(poses.size() <= size / 24 + 1, "more poses than lines of 12 numbers");
        for (const auto& pose : poses) {
            fuzz::require(pose.matrix().allFinite(), "non-finite pose");
            fuzz::require(std::abs(pose.linear().determinant()) > 0.99, "rotation is not orthonormal");
        }
    });
    return 0;
}
