// lidarsurf info: what a recording holds (topics, types, counts, time span) and the scans the
// other commands would read from it.
#include <algorithm>
#include <cstdio>

#include "commands.hpp"
#include "file_roles.hpp"
#include "lidarsurf/io/recorded_poses.hpp"
#include "lidarsurf/io/recording.hpp"

namespace lidarsurf::cli {
namespace {

double seconds(std::int64_t ns) { return 1e-9 * static_cast<double>(ns); }

}  // namespace

CLI::App* add_info_command(CLI::App& app, InfoOptions& o) {
    auto* c = app.add_subcommand("info", "List what a recording holds and the scans lidarsurf reads from it");
    c->footer(
        "Examples:\n"
        "  lidarsurf info OS-1-64.pcap           (metadata: OS-1-64.json beside it, or --metadata)\n"
        "  lidarsurf info drive.bag --topic /points --json info.json\n"
        "  lidarsurf info drive.bag --fixed-frame map --save-poses drive_tum.txt   (the tf tree, and the poses fuse takes)\n");
    c->add_option("input", o.input, "A recording: .pcap (Ouster), ROS 1 .bag, ROS 2 bag (its directory, .db3 or .mcap)")->required();
    add_recording_options(c, o.recording);
    add_pose_options(c, o.recorded_poses);
    c->add_option("--json", o.json, "Also write the summary as JSON");
    c->add_option("--save-poses", o.save_poses, "Also write the sensor's trajectory `fuse` would take from the bag, as TUM (t x y z qx qy qz qw)");
    return c;
}

int run_info(const InfoOptions& o) {
    if (!is_recording(o.input)) throw InvalidArgument(o.input + ": not a recording (.pcap, .bag, a ROS 2 bag directory, .db3, .mcap); `info` describes recordings");
    FileRoles files;
    files.input(o.input);
    if (!o.json.empty()) files.output(o.json, "--json");
    if (!o.save_poses.empty()) files.output(o.save_poses, "--save-poses");
    files.check();
    const RecordingSummary s = summarize_recording(o.input, recording_options(o.recording));
    std::printf("%s: %s\n", o.input.c_str(), s.container.c_str());
    std::printf("  %-32s %-36s %9s %10s\n", "topic", "type", "messages", "span (s)");
    for (const auto& t : s.topics)
        std::printf("  %-32s %-36s %9zu %10.3f\n", t.name.c_str(), t.type.c_str(), t.messages, seconds(t.last_ns - t.first_ns));
    std::printf("scans from %s:\n  %zu scans (%zu partial: less than a revolution), %zu points, %.3f s from first to last stamp, "
                "per-point times: %s\n",
                s.source.c_str(), s.scans, s.partial_scans, s.points, seconds(s.last_ns - s.first_ns), s.per_point_times ? "yes" : "no");
    // The tf tree and the poses `fuse` would take from it, or why it would take none.
    nlohmann::json frames = nlohmann::json::array(), poses;
    const auto options = recorded_poses_options(o.recorded_poses);
    TransformTree tree;
    if (has_recorded_poses(o.input)) {
        tree = read_transform_tree(o.input, options.pose_topic, options.sensor_frame.empty() ? s.frame_id : options.sensor_frame);
        std::printf("tf tree%s:\n", options.pose_topic.empty() ? "" : (" with " + options.pose_topic + " in place of /tf").c_str());
        for (const auto& l : tree.links()) {
            std::printf("  %-20s -> %-20s %s", l.parent.c_str(), l.child.c_str(), l.is_static ? "static" : "moving");
            if (!l.is_static) std::printf(", %zu transforms over %.3f s", l.samples, seconds(l.last_ns - l.first_ns));
            std::printf("\n");
            frames.push_back({{"parent", l.parent}, {"child", l.child}, {"static", l.is_static}, {"transforms", l.samples},
                              {"first_ns", l.first_ns}, {"last_ns", l.last_ns}});
        }
    }
    try {
        const RecordedPoses p = recorded_poses(tree, options, s.frame_id, o.input);
        const Trajectory& t = p.trajectory;
        const auto within = std::count_if(s.stamps_ns.begin(), s.stamps_ns.end(), [&](std::int64_t ns) { return ns >= t.first_ns() && ns <= t.last_ns(); });
        std::printf("poses for fuse: %s from %s to %s, %zu poses over %.3f s; %td of %zu scans stamped within\n", p.source.c_str(),
                    p.fixed_frame.c_str(), p.sensor_frame.c_str(), t.size(), seconds(t.last_ns() - t.first_ns()), within, s.scans);
        poses = {{"source", p.source}, {"fixed_frame", p.fixed_frame}, {"sensor_frame", p.sensor_frame}, {"poses", t.size()},
                 {"first_ns", t.first_ns()}, {"last_ns", t.last_ns()}, {"scans_within", within}};
        if (!o.save_poses.empty()) write_text(o.save_poses, format_tum_trajectory(t));
    } catch (const Error& e) {
        // What keeps fuse from taking poses is reported; a malformed recording is an error.
        if (!o.save_poses.empty() || (!dynamic_cast<const InvalidArgument*>(&e) && !dynamic_cast<const InvalidInput*>(&e))) throw;
        std::printf("poses for fuse: none from the recording (%s)\n", e.what());
    }
    if (!o.json.empty()) {
        nlohmann::json j;
        j["tf"] = frames;
        if (!poses.is_null()) j["poses"] = poses;
        j["container"] = s.container;
        j["source"] = s.source;
        j["scans"] = s.scans;
        j["partial_scans"] = s.partial_scans;
        j["points"] = s.points;
        j["first_stamp_ns"] = s.first_ns;
        j["last_stamp_ns"] = s.last_ns;
        j["per_point_times"] = s.per_point_times;
        for (const auto& t : s.topics)
            j["topics"].push_back({{"name", t.name}, {"type", t.type}, {"messages", t.messages}, {"first_ns", t.first_ns}, {"last_ns", t.last_ns}});
        write_json(o.json, j);
    }
    return 0;
}

}  // namespace lidarsurf::cli
