// Builds against the installed lidarsurf::recording component: a trajectory interpolated, and a
// recording refused with the typed exception its readers throw.
#include <cstdio>

#include <lidarsurf/core/errors.hpp>
#include <lidarsurf/io/recording.hpp>
#include <lidarsurf/io/trajectory.hpp>

int main() {
    const lidarsurf::Trajectory t = lidarsurf::parse_tum_trajectory("0 0 0 0 0 0 0 1\n2 4 0 0 0 0 0 1\n", "inline");
    const double x = t.at(1000000000)->translation().x();
    try {
        lidarsurf::open_recording("no_such_recording.pcap");
        return 1;
    } catch (const lidarsurf::IoError& e) {
        std::printf("lidarsurf::recording: x(1 s) = %.1f; %s\n", x, e.what());
    }
    return x == 2.0 ? 0 : 1;
}
