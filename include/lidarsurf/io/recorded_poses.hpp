#pragma once
// The sensor's trajectory held in a recording (ROS 1 and ROS 2 bags): /tf and /tf_static chained
// from a fixed frame to the scans' frame, or a pose topic (nav_msgs/Odometry,
// geometry_msgs/PoseStamped, PoseWithCovarianceStamped) chained through /tf_static to it.
#include <filesystem>
#include <string>

#include "lidarsurf/io/recording.hpp"
#include "lidarsurf/io/trajectory.hpp"
#include "lidarsurf/io/transform_tree.hpp"

namespace lidarsurf {

struct RecordedPosesOptions {
    /// The world frame. Empty: the pose topic's frame; with /tf, "odom" when the tree has it,
    /// else "map".
    std::string fixed_frame;
    /// A topic of poses to use instead of /tf. An Odometry moves its child_frame_id, chained
    /// through /tf_static to the scans' frame; a PoseStamped or PoseWithCovarianceStamped names no
    /// child and is taken as the pose of the scans' frame.
    std::string pose_topic;
    /// The frame the scans' points are in. Empty: the first scan's frame_id.
    std::string sensor_frame;
};

struct RecordedPoses {
    Trajectory trajectory;  ///< sensor-to-world: the sensor frame's pose in the fixed frame
    std::string fixed_frame, sensor_frame;
    std::string source;     ///< "/tf" or the pose topic
};

/// True when the recording is a bag with /tf, /tf_static or pose topics.
bool has_recorded_poses(const std::filesystem::path& path);

/// The frames of the recording's /tf and /tf_static, or those of `pose_topic` (when given): an
/// Odometry's with /tf_static, a PoseStamped's (moving `pose_child`) alone. Throws as open_recording, FormatError for malformed messages or a frame with two
/// parents, InvalidArgument for a pcap or a pose topic that is not there.
TransformTree read_transform_tree(const std::filesystem::path& path, const std::string& pose_topic = {},
                                  const std::string& pose_child = {});

/// The trajectory in `tree` (see RecordedPosesOptions) of the sensor frame, `scans_frame` unless
/// options.sensor_frame names another. `where` names the recording in errors. Throws as
/// TransformTree::trajectory; InvalidArgument for an empty tree; InvalidInput when `scans_frame`
/// is not in the tree or no default world frame is.
RecordedPoses recorded_poses(const TransformTree& tree, const RecordedPosesOptions& options, const std::string& scans_frame,
                             const std::string& where);

/// The sensor's trajectory read from the recording (see RecordedPosesOptions). `scans` chooses the scans whose frame is
/// the sensor's. Throws as read_transform_tree and recorded_poses.
RecordedPoses read_recorded_poses(const std::filesystem::path& path, const RecordedPosesOptions& options = {},
                                  const RecordingOptions& scans = {});

}  // namespace lidarsurf
