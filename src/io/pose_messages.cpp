// Messages that hold poses (see pose_messages.hpp), read in the order of their .msg files.
#include "pose_messages.hpp"

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::detail {
namespace {

// geometry_msgs/Vector3 or Point: three float64.
Eigen::Vector3d vector3(MessageReader& r) {
    const double x = r.scalar<double>(), y = r.scalar<double>(), z = r.scalar<double>();
    return {x, y, z};
}

// geometry_msgs/Quaternion: x, y, z, w.
Eigen::Quaterniond quaternion(MessageReader& r) {
    const double x = r.scalar<double>(), y = r.scalar<double>(), z = r.scalar<double>(), w = r.scalar<double>();
    return Eigen::Quaterniond(w, x, y, z);
}

StampedTransform headed(MessageReader& r) {
    StampedTransform t;
    auto h = r.header();
    t.stamp_ns = h.stamp_ns;
    t.parent = std::move(h.frame_id);
    return t;
}

}  // namespace

std::string ros1_type_name(const std::string& type) {
    const auto at = type.find("/msg/");
    return at == std::string::npos ? type : type.substr(0, at) + type.substr(at + 4);
}

bool is_tf_type(const std::string& type) {
    const std::string t = ros1_type_name(type);
    return t == "tf2_msgs/TFMessage" || t == "tf/tfMessage";
}

bool is_pose_type(const std::string& type) {
    const std::string t = ros1_type_name(type);
    return t == "nav_msgs/Odometry" || t == "geometry_msgs/PoseStamped" || t == "geometry_msgs/PoseWithCovarianceStamped";
}

std::vector<StampedTransform> parse_tf_message(std::span<const std::uint8_t> bytes, MessageReader::Encoding encoding, const std::string& where) {
    MessageReader r(bytes, where, encoding);
    const auto n = r.scalar<std::uint32_t>();
    // Each TransformStamped takes at least 68 bytes (7 float64 and two string lengths).
    if (n > bytes.size() / 68) throw FormatError(where + ": a TFMessage of " + std::to_string(n) + " transforms in " + std::to_string(bytes.size()) + " bytes");
    std::vector<StampedTransform> out(n);
    for (auto& t : out) {
        t = headed(r);
        t.child = r.string();
        t.translation = vector3(r);
        t.rotation = quaternion(r);
    }
    return out;
}

StampedTransform parse_pose_message(std::span<const std::uint8_t> bytes, const std::string& type, MessageReader::Encoding encoding,
                                    const std::string& where) {
    MessageReader r(bytes, where, encoding);
    const std::string t = ros1_type_name(type);
    if (!is_pose_type(t)) throw InvalidInput(where + ": " + type + " holds no pose (nav_msgs/Odometry, geometry_msgs/PoseStamped or PoseWithCovarianceStamped do)");
    StampedTransform out = headed(r);
    if (t == "nav_msgs/Odometry") out.child = r.string();
    out.translation = vector3(r);  // pose(.pose).position
    out.rotation = quaternion(r);  // pose(.pose).orientation; the covariance and twist that follow are not needed
    return out;
}

}  // namespace lidarsurf::detail
