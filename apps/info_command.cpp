// lidarsurf info: what a recording holds (topics, types, counts, time span) and the scans the
// other commands would read from it.
#include <cstdio>

#include "commands.hpp"
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
        "  lidarsurf info drive.bag --topic /points --json info.json\n");
    c->add_option("input", o.input, "A recording: .pcap (Ouster), ROS 1 .bag, ROS 2 bag (its directory, .db3 or .mcap)")->required();
    add_recording_options(c, o.recording);
    c->add_option("--json", o.json, "Also write the summary as JSON");
    return c;
}

int run_info(const InfoOptions& o) {
    if (!is_recording(o.input)) throw InvalidArgument(o.input + ": not a recording (.pcap, .bag, a ROS 2 bag directory, .db3, .mcap); `info` describes recordings");
    const RecordingSummary s = summarize_recording(o.input, recording_options(o.recording));
    std::printf("%s: %s\n", o.input.c_str(), s.container.c_str());
    std::printf("  %-32s %-36s %9s %10s\n", "topic", "type", "messages", "span (s)");
    for (const auto& t : s.topics)
        std::printf("  %-32s %-36s %9zu %10.3f\n", t.name.c_str(), t.type.c_str(), t.messages, seconds(t.last_ns - t.first_ns));
    std::printf("scans from %s:\n  %zu scans (%zu partial: less than a revolution), %zu points, %.3f s from first to last stamp, "
                "per-point times: %s\n",
                s.source.c_str(), s.scans, s.partial_scans, s.points, seconds(s.last_ns - s.first_ns), s.per_point_times ? "yes" : "no");
    if (!o.json.empty()) {
        nlohmann::json j;
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
