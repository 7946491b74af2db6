#pragma once
// The frames of a recording's /tf and /tf_static as tf2 keeps them: a tree where each frame has one
// parent, each link either static or a series of stamped transforms. The pose of one frame in
// another over time chains the links between them, each moving link interpolated at the time
// (position linearly, rotation by slerp, as tf2 does), never extrapolated.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "lidarsurf/io/trajectory.hpp"

namespace lidarsurf {

struct FrameLink {
    std::string parent, child;
    bool is_static = false;
    std::size_t samples = 0;               ///< stamped transforms received (1 for a static link)
    std::int64_t first_ns = 0, last_ns = 0;  ///< their span (a static link: its stamp)
};

class TransformTree {
public:
    /// tf's parent_T_child at `stamp_ns`: `translation` and `rotation` map the child's coordinates
    /// into the parent's. A leading '/' of a frame name is dropped (ROS 1's tf used it). The
    /// quaternion is normalized. Throws FormatError naming `where` for an empty frame name, a frame
    /// linked to itself, a frame given a second parent, a link both static and moving, or a
    /// transform that is not finite or whose quaternion is not of unit length within 1%.
    void add(std::string parent, std::string child, std::int64_t stamp_ns, const Eigen::Vector3d& translation,
             const Eigen::Quaterniond& rotation, bool is_static, const std::string& where);

    bool empty() const { return links_.empty(); }
    bool has_frame(std::string frame) const;
    /// Every link, by child frame.
    std::vector<FrameLink> links() const;

    /// The pose of `frame` in `fixed` (fixed_T_frame) over time, sampled at every stamp of the
    /// moving links between them within the span all of those share. Throws InvalidArgument when
    /// a frame is not in the tree (naming those that are); InvalidInput when the two are not
    /// connected (naming each one's root), when no link between them moves or when the moving
    /// ones share no span; FormatError when the parents loop.
    Trajectory trajectory(std::string fixed, std::string frame) const;

private:
    struct Link {
        std::string parent;
        bool is_static = false;
        std::vector<std::int64_t> stamps;
        std::vector<Eigen::Isometry3d> poses;
    };
    // `frame` and its ancestors, the frame first and its root last.
    std::vector<std::string> ancestry(const std::string& frame) const;
    std::map<std::string, Link> links_;  // by child frame
};

}  // namespace lidarsurf
