// Trajectories and recorded drives: interpolation against analytic motion, and de-skew on a sweep
// taken while driving at 10 m/s and turning, in a world of planes ray-cast here (the recording's
// ranges), written as an Ouster pcap.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>

#include "io/ouster_test_writer.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/recorded_drive.hpp"
#include "lidarsurf/io/trajectory.hpp"

namespace lidarsurf {
namespace {

using namespace lidarsurf::test;

// The sensor's motion: 10 m/s along its heading, turning at 0.5 rad/s (yaw = 0.5 t). The
// position is the exact integral (a circle of radius 20 m), the pose at time t (seconds).
constexpr double kSpeed = 10, kYawRate = 0.5;
Eigen::Isometry3d motion(double t) {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    const double yaw = kYawRate * t, r = kSpeed / kYawRate;
    p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    p.translation() = Eigen::Vector3d(r * std::sin(yaw), r * (1 - std::cos(yaw)), 1.8);
    return p;
}

// TUM lines of the motion every `dt` seconds from 0 to `end`, with `t0` seconds added to the clock.
std::string tum(double dt, double end, double t0) {
    std::ostringstream s;
    s << std::setprecision(17) << "# t x y z qx qy qz qw\n";
    for (double t = 0; t <= end + 1e-9; t += dt) {
        const Eigen::Isometry3d p = motion(t);
        const Eigen::Quaterniond q(p.linear());
        s << t + t0 << ' ' << p.translation().x() << ' ' << p.translation().y() << ' ' << p.translation().z() << ' ' << q.x() << ' ' << q.y()
          << ' ' << q.z() << ' ' << q.w() << '\n';
    }
    return s.str();
}

TEST(Trajectory, InterpolationIsExactForAConstantTurnAtTheSamplesAndCloseBetween) {
    const Trajectory tr = parse_tum_trajectory(tum(0.01, 1.0, 100.0), "motion");
    EXPECT_EQ(tr.size(), 101u);
    for (double t = 0; t <= 1.0; t += 0.0037) {
        const auto p = tr.at(static_cast<std::int64_t>(std::llround((100.0 + t) * 1e9)));
        ASSERT_TRUE(p.has_value());
        const Eigen::Isometry3d truth = motion(t);
        // Rotation: slerp is exact for a constant rate about one axis; position: a chord of a
        // 20 m circle over 0.1 m departs from the arc by at most 0.1^2 / (8 * 20) m.
        EXPECT_LT((p->linear() - truth.linear()).norm(), 1e-9);
        EXPECT_LT((p->translation() - truth.translation()).norm(), 0.1 * 0.1 / (8 * 20) + 1e-9);
    }
    EXPECT_FALSE(tr.at(static_cast<std::int64_t>(99.999 * 1e9)).has_value());  // never extrapolated
    EXPECT_FALSE(tr.at(static_cast<std::int64_t>(101.001 * 1e9)).has_value());
}

TEST(Trajectory, BadFilesAreRefusedNamingTheLine) {
    auto message = [](const std::string& text) {
        try {
            parse_tum_trajectory(text, "traj.txt");
        } catch (const FormatError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    EXPECT_NE(message("0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0\n").find("line 2"), std::string::npos);
    EXPECT_NE(message("0 0 0 0 0 0 0 1\n0 1 0 0 0 0 0 1\n").find("line 2"), std::string::npos);   // time not increasing
    EXPECT_NE(message("0 0 0 0 0 0 0 2\n").find("line 1"), std::string::npos);                    // not a unit quaternion
    EXPECT_NE(message("0 nan 0 0 0 0 0 1\n").find("line 1"), std::string::npos);
    EXPECT_EQ(message("# nothing\n\n").find("accepted"), std::string::npos);
}

// The world: the ground z = 0, walls y = 30 and y = -12, a wall x = 45 (in the world frame; the
// sensor starts at the origin, 1.8 m up, heading +x).
double cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    double best = std::numeric_limits<double>::infinity();
    auto plane = [&](int axis, double at) {
        if (std::abs(d[axis]) < 1e-12) return;
        const double t = (at - o[axis]) / d[axis];
        if (t > 0.5) best = std::min(best, t);
    };
    plane(2, 0.0);
    plane(1, 30.0);
    plane(1, -12.0);
    plane(0, 45.0);
    return best;
}

double distance_to_world(const Eigen::Vector3d& p) {
    return std::min({std::abs(p.z()), std::abs(p.y() - 30), std::abs(p.y() + 12), std::abs(p.x() - 45)});
}

TEST(RecordedDrive, DeskewPutsASweepTakenWhileTurningAt10MetresASecondBackOnTheWorld) {
    const fs::path dir = temp_dir("deskew");
    Sensor s;
    s.beams = 16;
    s.columns = 512;
    const double sweep = 0.1, t0 = 5.0;  // 10 Hz; the recording's clock starts at 5 s
    const std::uint64_t column_ns = static_cast<std::uint64_t>(sweep * 1e9) / static_cast<std::uint64_t>(s.columns);
    // Two sweeps, starting at t = 0.1 s and 0.2 s of the motion. Each pixel's range is cast from
    // the sensor's pose at its column's time, along the manual's direction of that pixel.
    std::vector<std::vector<std::uint8_t>> packets;
    for (int frame = 1; frame <= 2; ++frame) {
        const double start = frame * sweep;
        const auto range = [&](int c, int b, int) -> std::uint32_t {
            const double t = start + static_cast<double>(column_ns * static_cast<std::uint64_t>(c)) * 1e-9;
            const double encoder = 2 * M_PI * (1 - c / double(s.columns));
            const double az = encoder - s.azimuth()[b] * M_PI / 180, alt = s.altitude()[b] * M_PI / 180;
            const Eigen::Vector3d local(std::cos(az) * std::cos(alt), std::sin(az) * std::cos(alt), std::sin(alt));
            const Eigen::Isometry3d pose = motion(t);
            const double r = cast(pose.translation(), pose.linear() * local);
            return std::isfinite(r) && r < 120 ? static_cast<std::uint32_t>(std::llround(r * 1000)) : 0;
        };
        const auto frame_start_ns = static_cast<std::uint64_t>(std::llround((t0 + start) * 1e9));
        for (auto& p : frame_packets(s, static_cast<std::uint32_t>(frame), range, frame_start_ns, column_ns)) packets.push_back(std::move(p));
    }
    write_pcap(dir / "turn.pcap", packets, 7502);
    std::ofstream(dir / "turn.json") << s.json();
    std::ofstream(dir / "turn_tum.txt") << tum(0.01, 0.5, t0);

    auto world_error = [&](bool deskew) {
        RecordedDriveOptions o;
        o.deskew = deskew;
        RecordedDrive drive(dir / "turn.pcap", read_tum_trajectory(dir / "turn_tum.txt"), o);
        EXPECT_EQ(drive.size(), 2u);
        EXPECT_EQ(drive.deskews(), deskew);
        std::vector<double> errors;
        for (std::size_t k = 0; k < drive.size(); ++k)
            for (const auto& p : drive.world_scan(k).points) errors.push_back(distance_to_world(p));
        return errors;
    };
    const auto with = world_error(true), without = world_error(false);
    ASSERT_GT(with.size(), 10000u);
    // De-skewed: every point on a plane of the world, to the range's millimetre and the
    // trajectory's chords (0.1^2 / 160 m).
    EXPECT_LT(*std::max_element(with.begin(), with.end()), 0.002 + 0.1 * 0.1 / 160);
    // As recorded, the sweep is smeared by the 1 m driven and 2.9 degrees turned during it.
    std::size_t off = 0;
    for (double e : without) off += e > 0.05;
    EXPECT_GT(static_cast<double>(off) / static_cast<double>(without.size()), 0.3);
    fs::remove_all(dir);
}

TEST(RecordedDrive, ScansOutsideTheTrajectoryAreSkippedAndCountedNeverExtrapolated) {
    const fs::path dir = temp_dir("span");
    Sensor s;
    std::vector<std::vector<std::uint8_t>> packets;
    for (int frame = 0; frame < 4; ++frame)
        for (auto& p : frame_packets(s, static_cast<std::uint32_t>(frame), [](int, int, int) { return 4000u; },
                                     static_cast<std::uint64_t>(1e9) * static_cast<std::uint64_t>(10 + frame), 1000))
            packets.push_back(std::move(p));
    write_pcap(dir / "four.pcap", packets, 7502);
    std::ofstream(dir / "four.json") << s.json();
    // The trajectory covers 10.5 s .. 12.5 s: scans 1 and 2 (at 11 s and 12 s) only.
    std::ofstream(dir / "traj.txt") << "10.5 0 0 0 0 0 0 1\n12.5 5 0 0 0 0 0 1\n";
    RecordedDrive drive(dir / "four.pcap", read_tum_trajectory(dir / "traj.txt"));
    EXPECT_EQ(drive.recorded(), 4u);
    ASSERT_EQ(drive.size(), 2u);
    EXPECT_EQ(drive.skipped(), 2u);
    EXPECT_EQ(drive.recording_index(0), 1u);
    EXPECT_NEAR(drive.pose(0).translation().x(), 5 * 0.5 / 2.0, 1e-9);
    // Read out of order: the recording is opened again.
    EXPECT_EQ(drive.scan(1).index, 2u);
    EXPECT_EQ(drive.scan(0).index, 1u);
    std::ofstream(dir / "late.txt") << "100 0 0 0 0 0 0 1\n101 0 0 0 0 0 0 1\n";
    EXPECT_THROW(RecordedDrive(dir / "four.pcap", read_tum_trajectory(dir / "late.txt")), InvalidInput);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lidarsurf
