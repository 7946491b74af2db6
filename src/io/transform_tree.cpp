// A recording's frames (see transform_tree.hpp).
#include "lidarsurf/io/transform_tree.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

std::string frame_name(std::string f) {
    if (!f.empty() && f.front() == '/') f.erase(0, 1);
    return f;
}

}  // namespace

void TransformTree::add(std::string parent, std::string child, std::int64_t stamp_ns, const Eigen::Vector3d& translation,
                        const Eigen::Quaterniond& rotation, bool is_static, const std::string& where) {
    parent = frame_name(std::move(parent));
    child = frame_name(std::move(child));
    if (parent.empty() || child.empty()) throw FormatError(where + ": a transform without its parent or child frame name");
    if (parent == child) throw FormatError(where + ": a transform of frame '" + child + "' to itself");
    const double norm = rotation.norm();
    if (!translation.allFinite() || !rotation.coeffs().allFinite() || std::abs(norm - 1) > 0.01)
        throw FormatError(where + ": the transform of '" + child + "' in '" + parent + "' is not finite or its quaternion is not of unit length (" +
                          std::to_string(norm) + ")");
    auto [it, fresh] = links_.try_emplace(child);
    Link& link = it->second;
    if (fresh) {
        link.parent = parent;
        link.is_static = is_static;
    } else if (link.parent != parent) {
        throw FormatError(where + ": frame '" + child + "' has two parents, '" + link.parent + "' and '" + parent + "' (tf allows one)");
    } else if (link.is_static != is_static) {
        throw FormatError(where + ": the link of '" + child + "' in '" + parent + "' is both static (/tf_static) and moving (/tf)");
    }
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = Eigen::Quaterniond(rotation.coeffs() / norm).toRotationMatrix();
    pose.translation() = translation;
    if (is_static) {  // the latest static transform wins, as in tf2
        link.stamps.assign(1, stamp_ns);
        link.poses.assign(1, pose);
        return;
    }
    link.stamps.push_back(stamp_ns);
    link.poses.push_back(pose);
}

bool TransformTree::has_frame(std::string frame) const {
    frame = frame_name(std::move(frame));
    if (links_.count(frame)) return true;
    return std::any_of(links_.begin(), links_.end(), [&](const auto& l) { return l.second.parent == frame; });
}

std::vector<FrameLink> TransformTree::links() const {
    std::vector<FrameLink> out;
    for (const auto& [child, l] : links_) {
        FrameLink f;
        f.parent = l.parent;
        f.child = child;
        f.is_static = l.is_static;
        f.samples = l.stamps.size();
        f.first_ns = *std::min_element(l.stamps.begin(), l.stamps.end());
        f.last_ns = *std::max_element(l.stamps.begin(), l.stamps.end());
        out.push_back(std::move(f));
    }
    return out;
}

std::vector<std::string> TransformTree::ancestry(const std::string& frame) const {
    std::vector<std::string> up{frame};
    for (auto it = links_.find(frame); it != links_.end(); it = links_.find(up.back())) {
        if (std::find(up.begin(), up.end(), it->second.parent) != up.end()) {
            std::string loop;
            for (const auto& f : up) loop += f + " <- ";
            throw FormatError("the tf frames loop: " + loop + it->second.parent);
        }
        up.push_back(it->second.parent);
    }
    return up;
}

Trajectory TransformTree::trajectory(std::string fixed, std::string frame) const {
    fixed = frame_name(std::move(fixed));
    frame = frame_name(std::move(frame));
    for (const auto* f : {&fixed, &frame}) {
        if (has_frame(*f)) continue;
        std::vector<std::string> names;
        for (const auto& [child, l] : links_) names.push_back(child), names.push_back(l.parent);
        std::sort(names.begin(), names.end());
        names.erase(std::unique(names.begin(), names.end()), names.end());
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
        throw InvalidArgument("no frame '" + *f + "' in the tf tree (its frames: " + list + ")");
    }
    const auto up_fixed = ancestry(fixed), up_frame = ancestry(frame);
    if (up_fixed.back() != up_frame.back())
        throw InvalidInput("no tf path from '" + fixed + "' to '" + frame + "': the first is in the tree of '" + up_fixed.back() +
                              "', the second in that of '" + up_frame.back() + "'");
    // The nearest common ancestor; the path is fixed -> ... -> common <- ... <- frame.
    std::size_t a = up_fixed.size() - 1, b = up_frame.size() - 1;
    while (a > 0 && b > 0 && up_fixed[a - 1] == up_frame[b - 1]) --a, --b;
    struct Step {
        Trajectory moving;                 // empty for a static link
        Eigen::Isometry3d fixed_pose;      // the static link's
        bool inverse = false;              // on the fixed side: its inverse is applied
    };
    std::vector<Step> steps;
    std::vector<std::int64_t> stamps;
    std::int64_t first = INT64_MIN, last = INT64_MAX;
    const auto add_step = [&](const std::string& child, bool inverse) {
        const Link& l = links_.at(child);
        Step s;
        s.inverse = inverse;
        if (l.is_static) {
            s.fixed_pose = l.poses.front();
        } else {
            // Stamps sorted; a repeated stamp keeps its first transform.
            std::vector<std::size_t> order(l.stamps.size());
            std::iota(order.begin(), order.end(), 0);
            std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return l.stamps[i] < l.stamps[j]; });
            std::vector<std::int64_t> ts;
            std::vector<Eigen::Isometry3d> ps;
            for (std::size_t i : order) {
                if (!ts.empty() && ts.back() == l.stamps[i]) continue;
                ts.push_back(l.stamps[i]);
                ps.push_back(l.poses[i]);
            }
            first = std::max(first, ts.front());
            last = std::min(last, ts.back());
            stamps.insert(stamps.end(), ts.begin(), ts.end());
            s.moving = Trajectory(std::move(ts), std::move(ps));
        }
        steps.push_back(std::move(s));
    };
    for (std::size_t i = 0; i < a; ++i) add_step(up_fixed[i], true);     // fixed's side, walked up
    for (std::size_t i = b; i-- > 0;) add_step(up_frame[i], false);      // frame's side, walked down
    if (stamps.empty())
        throw InvalidInput("the transform from '" + fixed + "' to '" + frame + "' never changes (only static links): it gives no trajectory");
    if (first > last) throw InvalidInput("the moving tf links from '" + fixed + "' to '" + frame + "' share no span of time");
    std::sort(stamps.begin(), stamps.end());
    stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
    std::vector<std::int64_t> out_stamps;
    std::vector<Eigen::Isometry3d> out_poses;
    for (const std::int64_t t : stamps) {
        if (t < first || t > last) continue;
        // fixed_T_frame = (common_T_fixed)^-1 * common_T_frame; the fixed side's links come
        // child first, so their inverses multiply in that order.
        Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
        for (const Step& s : steps) {
            const Eigen::Isometry3d link = s.moving.empty() ? s.fixed_pose : *s.moving.at(t);
            pose = pose * (s.inverse ? link.inverse() : link);
        }
        out_stamps.push_back(t);
        out_poses.push_back(pose);
    }
    return Trajectory(std::move(out_stamps), std::move(out_poses));
}

}  // namespace lidarsurf
