#pragma once
// Internal: the ROS messages that hold poses, ROS 1's or ROS 2's (CDR): tf2_msgs/TFMessage (also
// tf's tfMessage, the same layout), nav_msgs/Odometry, geometry_msgs/PoseStamped and
// PoseWithCovarianceStamped.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "message_reader.hpp"

namespace lidarsurf::detail {

struct StampedTransform {
    std::string parent, child;  ///< child empty: the message does not name it (PoseStamped)
    std::int64_t stamp_ns = 0;
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

/// The type without ROS 2's "/msg/": "nav_msgs/msg/Odometry" -> "nav_msgs/Odometry".
std::string ros1_type_name(const std::string& type);
bool is_tf_type(const std::string& type);
bool is_pose_type(const std::string& type);

/// Every transform of a TFMessage.
std::vector<StampedTransform> parse_tf_message(std::span<const std::uint8_t> bytes, MessageReader::Encoding encoding, const std::string& where);
/// The pose of an Odometry (its child_frame_id in its header's frame), a PoseStamped or a
/// PoseWithCovarianceStamped (no child frame). Throws InvalidInput for another type.
StampedTransform parse_pose_message(std::span<const std::uint8_t> bytes, const std::string& type, MessageReader::Encoding encoding,
                                    const std::string& where);

}  // namespace lidarsurf::detail
