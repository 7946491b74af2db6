// libFuzzer harness for the poses held in bags: the input's first byte picks the encoding (ROS 1
// or CDR) and the message (tf2_msgs/TFMessage, nav_msgs/Odometry, geometry_msgs/PoseStamped); the
// rest is the message. Its transforms go into a TransformTree (names, parents, loops, quaternions)
// whose trajectory between two of its frames is then chained (tf's pose_messages.hpp and
// transform_tree.hpp).
#include "fuzz_common.hpp"
#include "lidarsurf/io/transform_tree.hpp"
#include "pose_messages.hpp"

using namespace lidarsurf;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const auto encoding = data[0] & 1 ? detail::MessageReader::Encoding::Cdr : detail::MessageReader::Encoding::Ros1;
    const int kind = (data[0] >> 1) % 3;
    const std::span<const std::uint8_t> body(data + 1, size - 1);
    fuzz::expect_typed([&] {
        std::vector<detail::StampedTransform> transforms;
        if (kind == 0) {
            transforms = detail::parse_tf_message(body, encoding, "fuzz message");
            fuzz::require(transforms.size() <= body.size() / 68, "more transforms than the message can hold");
        } else {
            transforms.push_back(detail::parse_pose_message(body, kind == 1 ? "nav_msgs/Odometry" : "geometry_msgs/msg/PoseStamped", encoding, "fuzz message"));
            if (transforms.back().child.empty()) transforms.back().child = "sensor";
        }
        TransformTree tree;
        for (std::size_t i = 0; i < transforms.size(); ++i) {
            const auto& t = transforms[i];
            tree.add(t.parent, t.child, t.stamp_ns, t.translation, t.rotation, i % 2 == 1, "fuzz message");
        }
        const auto links = tree.links();
        if (links.empty()) return;
        const Trajectory trajectory = tree.trajectory(links.front().parent, links.back().child);
        for (const auto& p : trajectory.poses()) {
            fuzz::require(p.matrix().allFinite(), "a pose that is not finite");
            fuzz::require(std::abs(p.linear().determinant() - 1) < 1e-6, "a rotation that is not one");
        }
    });
    return 0;
}
