// A recording's poses (see recorded_poses.hpp).
#include "lidarsurf/io/recorded_poses.hpp"

#include <algorithm>

#include "lidarsurf/core/errors.hpp"
#include "pose_messages.hpp"
#include "recording_sources.hpp"

namespace lidarsurf {
namespace {

bool is_ros1_bag(const std::filesystem::path& path) { return detail::lower_extension(path) == ".bag"; }

std::vector<detail::TopicType> topic_types(const std::filesystem::path& path) {
    if (is_ros1_bag(path)) return detail::ros1_bag_topic_types(path);
    if (detail::is_ros2_bag(path)) return detail::ros2_bag_topic_types(path);
    throw InvalidArgument(path.string() + ": a pcap holds no poses: give the sensor's trajectory with --poses");
}

std::unique_ptr<detail::MessageStream> open_messages(const std::filesystem::path& path, const std::vector<std::string>& topics) {
    return is_ros1_bag(path) ? detail::open_ros1_messages(path, topics) : detail::open_ros2_messages(path, topics);
}

bool is_static_topic(const std::string& topic) { return topic == "/tf_static" || topic == "tf_static"; }

}  // namespace

bool has_recorded_poses(const std::filesystem::path& path) {
    if (!is_ros1_bag(path) && !detail::is_ros2_bag(path)) return false;
    const auto topics = topic_types(path);
    return std::any_of(topics.begin(), topics.end(), [](const auto& t) { return detail::is_tf_type(t.type) || detail::is_pose_type(t.type); });
}

namespace {

// read_transform_tree on the bag's topics and types, listed once by the caller.
TransformTree transform_tree(const std::filesystem::path& path, const std::vector<detail::TopicType>& types, const std::string& pose_topic,
                             const std::string& pose_child) {
    const std::string pose_type = pose_topic.empty() ? "" : detail::ros1_type_name(detail::type_of(types, pose_topic));
    if (!pose_topic.empty()) {
        if (pose_type.empty()) throw InvalidArgument(path.string() + ": no topic " + pose_topic);
        if (!detail::is_pose_type(pose_type))
            throw InvalidArgument(path.string() + ": " + pose_topic + " is " + detail::type_of(types, pose_topic) +
                                  ", not nav_msgs/Odometry, geometry_msgs/PoseStamped or PoseWithCovarianceStamped");
    }
    // With a pose topic, /tf is left out: its moving links would give a frame a second parent. A
    // PoseStamped is the sensor's own pose: /tf_static is left out too.
    std::vector<std::string> topics;
    for (const auto& t : types)
        if (detail::is_tf_type(t.type) && (pose_topic.empty() || (pose_type == "nav_msgs/Odometry" && is_static_topic(t.name))))
            topics.push_back(t.name);
    if (!pose_topic.empty()) topics.push_back(pose_topic);
    TransformTree tree;
    if (topics.empty()) return tree;
    auto messages = open_messages(path, topics);
    detail::RawMessage m;
    while (messages->next(m)) {
        const auto encoding = m.cdr ? detail::MessageReader::Encoding::Cdr : detail::MessageReader::Encoding::Ros1;
        if (m.topic == pose_topic) {
            auto p = detail::parse_pose_message(m.data, m.type, encoding, m.where);
            if (p.child.empty()) p.child = pose_child;
            if (p.child.empty()) throw InvalidArgument(path.string() + ": " + pose_topic + " names no child frame: give the sensor's frame");
            tree.add(p.parent, p.child, p.stamp_ns, p.translation, p.rotation, false, m.where);
            continue;
        }
        const bool is_static = is_static_topic(m.topic);
        for (const auto& t : detail::parse_tf_message(m.data, encoding, m.where))
            tree.add(t.parent, t.child, t.stamp_ns, t.translation, t.rotation, is_static, m.where);
    }
    return tree;
}

}  // namespace

TransformTree read_transform_tree(const std::filesystem::path& path, const std::string& pose_topic, const std::string& pose_child) {
    return transform_tree(path, topic_types(path), pose_topic, pose_child);
}

RecordedPoses recorded_poses(const TransformTree& tree, const RecordedPosesOptions& options, const std::string& scans_frame,
                             const std::string& where) {
    if (tree.empty())
        throw InvalidArgument(where + ": no /tf, /tf_static or pose topic: give the sensor's trajectory with --poses, or a --pose-topic");
    RecordedPoses out;
    out.sensor_frame = options.sensor_frame.empty() ? scans_frame : options.sensor_frame;
    if (out.sensor_frame.empty()) throw InvalidInput(where + ": the scans name no frame: give the sensor's frame");
    out.source = options.pose_topic.empty() ? "/tf" : options.pose_topic;
    out.fixed_frame = options.fixed_frame;
    if (out.fixed_frame.empty() && !options.pose_topic.empty()) {
        // The pose topic's own frame: the parent of the one moving link (its /tf is left out).
        for (const auto& l : tree.links())
            if (!l.is_static) out.fixed_frame = l.parent;
    }
    if (out.fixed_frame.empty()) {
        for (const char* f : {"odom", "map"})
            if (tree.has_frame(f)) {
                out.fixed_frame = f;
                break;
            }
        if (out.fixed_frame.empty()) throw InvalidInput(where + ": the tf tree has no 'odom' or 'map' frame: name the world frame (--fixed-frame)");
    }
    try {
        out.trajectory = tree.trajectory(out.fixed_frame, out.sensor_frame);
    } catch (const InvalidArgument& e) {
        // A frame that is absent: the scans' own frame is the recording's fault, a named one the user's.
        if (options.sensor_frame.empty() && !tree.has_frame(out.sensor_frame))
            throw InvalidInput(where + ": the scans' frame '" + out.sensor_frame + "' is not linked in the tf tree (" + e.what() + ")");
        throw InvalidArgument(where + ": " + e.what());
    } catch (const InvalidInput& e) {
        throw InvalidInput(where + ": " + e.what());
    } catch (const FormatError& e) {
        throw FormatError(where + ": " + e.what());
    }
    return out;
}

RecordedPoses read_recorded_poses(const std::filesystem::path& path, const RecordedPosesOptions& options, const RecordingOptions& scans) {
    std::string scans_frame;
    if (options.sensor_frame.empty()) {
        RecordedScan first;
        if (!open_recording(path, scans)->next(first)) throw InvalidInput(path.string() + ": no scans");
        scans_frame = first.frame_id;
    }
    const std::string sensor = options.sensor_frame.empty() ? scans_frame : options.sensor_frame;
    const auto types = topic_types(path);
    const TransformTree tree = transform_tree(path, types, options.pose_topic, sensor);
    const auto links = tree.links();
    if (options.pose_topic.empty() && std::none_of(links.begin(), links.end(), [](const FrameLink& l) { return !l.is_static; })) {
        // Nothing moves in /tf: name the pose topics there are.
        std::string pose_topics;
        for (const auto& t : types)
            if (detail::is_pose_type(t.type)) pose_topics += (pose_topics.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
        if (!pose_topics.empty())
            throw InvalidArgument(path.string() + ": no moving link in /tf: name one of its pose topics with --pose-topic: " + pose_topics);
    }
    return recorded_poses(tree, options, scans_frame, path.string());
}

}  // namespace lidarsurf
