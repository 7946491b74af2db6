// Velodyne packets written here from the manuals' layout (12 blocks of 0xEEFF/0xDDFF, azimuth,
// 32 x (distance, intensity), timestamp, return mode, product), their calibration YAML in both of
// YAML's styles, pcaps written by libpcap's own writer, and the refused inputs. The points are
// checked against the manuals' geometry and timing written out again here; the decoder of the
// format's users (@foxglove/velodyne-cloud) checks the same packets in python/tests/test_velodyne.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include "io/ouster_test_writer.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/recording.hpp"
#include "lidarsurf/io/velodyne.hpp"

namespace lidarsurf {
namespace {

using namespace lidarsurf::test;

// raw distance (2 mm counts) of channel j of block b of packet k; 0 = no return.
using RawOf = std::function<std::uint16_t(int packet, int block, int channel)>;

// The reflectivity byte of channel j of block b in the test packets.
std::uint8_t channel_reflectivity(int block, int channel) { return static_cast<std::uint8_t>((block * 31 + channel * 7) % 255); }

constexpr std::uint32_t kPastHourUs = 800000000;  // the test pcaps are captured 800 s past an hour

std::vector<std::uint8_t> velodyne_packet(int k, int first_azimuth, int azimuth_step, const RawOf& raw, std::uint8_t product = 0x22,
                                          std::uint8_t mode = 0x37, std::uint32_t stamp_us = kPastHourUs, bool dual = false) {
    std::vector<std::uint8_t> b(1206, 0);
    for (int blk = 0; blk < 12; ++blk) {
        const std::size_t at = 100 * blk;
        put<std::uint16_t>(b, at, 0xEEFF);
        const int firing = dual ? blk / 2 : blk;
        put<std::uint16_t>(b, at + 2, static_cast<std::uint16_t>((first_azimuth + azimuth_step * firing) % 36000));
        for (int j = 0; j < 32; ++j) {
            put<std::uint16_t>(b, at + 4 + 3 * j, raw(k, blk, j));
            b[at + 6 + 3 * j] = channel_reflectivity(blk, j);  // the manual: 2 bytes of distance, 1 of reflectivity
        }
    }
    put<std::uint32_t>(b, 1200, stamp_us);
    b[1204] = mode;
    b[1205] = product;
    return b;
}

// A VLP-16 turning at 10 Hz: 20 hundredths of a degree a block (110.592 us), 240 a packet.
std::vector<std::vector<std::uint8_t>> vlp16_packets(int count, int first_azimuth, const RawOf& raw) {
    std::vector<std::vector<std::uint8_t>> out;
    for (int k = 0; k < count; ++k)
        out.push_back(velodyne_packet(k, (first_azimuth + 240 * k) % 36000, 20, raw, 0x22, 0x37,
                                      kPastHourUs + static_cast<std::uint32_t>(std::lround(k * 12 * 110.592))));
    return out;
}

double elevation_deg(int laser) { return laser % 2 ? laser : -15 + laser; }  // the VLP-16 manual's table

TEST(VelodyneSweeps, AVlp16PacketGivesTheManualsAnglesRangesAndFiringTimes) {
    const auto raw = [](int, int b, int j) -> std::uint16_t { return (b + j) % 9 == 4 ? 0 : static_cast<std::uint16_t>(2000 + 37 * b + 11 * j); };
    const auto packets = vlp16_packets(1, 1000, raw);
    VelodyneSweeps sweeps(VelodyneModel::VLP16, *velodyne_factory_calibration(VelodyneModel::VLP16));
    EXPECT_FALSE(sweeps.add(packets[0], 1699999200LL * 1000000000 + kPastHourUs * 1000LL, "test"));
    ASSERT_TRUE(sweeps.finish());
    const RecordedScan scan = sweeps.take();
    EXPECT_EQ(scan.frame_id, "velodyne");
    // The sensor's clock is the capture clock's: the stamp is the top of the hour plus its microseconds.
    EXPECT_EQ(scan.stamp_ns, 1699999200LL * 1000000000 + kPastHourUs * 1000LL);
    EXPECT_NEAR(scan.completeness, 12 * 20 / 36000.0, 1e-12);
    std::size_t i = 0, empty = 0;
    for (int b = 0; b < 12; ++b) {
        for (int j = 0; j < 32; ++j) {
            if (!raw(0, b, j)) {
                ++empty;
                continue;
            }
            ASSERT_LT(i, scan.cloud.points.size());
            const Eigen::Vector3d p = scan.cloud.points[i];
            const int laser = j % 16;
            // Firing j / 16 of the block, laser j % 16 of it, 2.304 us apart, 55.296 us a firing.
            const double t_us = b * 110.592 + (j / 16) * 55.296 + laser * 2.304;
            const double azimuth_deg = (1000 + 20 * b) / 100.0 + 0.2 * (t_us - b * 110.592) / 110.592;
            EXPECT_NEAR(p.norm(), 0.002 * raw(0, b, j), 1e-9);
            EXPECT_NEAR(std::asin(p.z() / p.norm()) * 180 / M_PI, elevation_deg(laser), 1e-9);
            // Velodyne's azimuth turns clockwise from ahead (x): in ROS's frame, y = -sin.
            EXPECT_NEAR(std::atan2(-p.y(), p.x()) * 180 / M_PI, azimuth_deg, 1e-9);
            EXPECT_NEAR(scan.times[i], t_us * 1e-6, 1e-9);
            // Rings from the top: laser 15 (+15 degrees) is ring 0, laser 0 (-15) ring 15.
            EXPECT_EQ(scan.cloud.rings[i], laser % 2 ? 7 - (laser - 1) / 2 : 15 - laser / 2);
            EXPECT_EQ(scan.cloud.intensities.at(i), channel_reflectivity(b, j));
            ++i;
        }
    }
    EXPECT_EQ(i, scan.cloud.points.size());
    EXPECT_EQ(scan.no_return.size(), empty);
    for (const auto& d : scan.no_return) EXPECT_NEAR(d.norm(), 1.0f, 1e-6f);
}

TEST(VelodyneSweeps, ASweepEndsWhereTheAzimuthWrapsAndPartialSweepsSayHowPartial) {
    const auto raw = [](int, int, int) -> std::uint16_t { return 5000; };
    // 300 packets from 300 degrees: 60 degrees of a first revolution, a whole one, and 300 degrees.
    const auto packets = vlp16_packets(300, 30000, raw);
    VelodyneSweeps sweeps(VelodyneModel::VLP16, *velodyne_factory_calibration(VelodyneModel::VLP16));
    std::vector<RecordedScan> scans;
    std::int64_t capture = 1699999200LL * 1000000000 + kPastHourUs * 1000LL;
    for (const auto& p : packets) {
        if (sweeps.add(p, capture, "test")) scans.push_back(sweeps.take());
        capture += 1327104;
    }
    ASSERT_TRUE(sweeps.finish());
    scans.push_back(sweeps.take());
    ASSERT_EQ(scans.size(), 3u);
    EXPECT_NEAR(scans[0].completeness, 6000.0 / 36000, 1e-9);
    EXPECT_NEAR(scans[1].completeness, 1.0, 1e-9);
    EXPECT_NEAR(scans[2].completeness, (300 * 240 - 6000 - 36000) / 36000.0, 1e-9);
    EXPECT_EQ(scans[1].cloud.points.size(), 36000u / 20 * 32);
    // A revolution starts at azimuth 0, 300 blocks after the first sweep's start: at packet 25's
    // stamp (whole microseconds); its last point 1800 blocks of 110.592 us later (to 1 us).
    EXPECT_EQ(scans[1].stamp_ns - scans[0].stamp_ns, 1000 * std::lround(25 * 12 * 110.592));
    EXPECT_NEAR(scans[1].times.back(), (1799 * 110.592 + 55.296 + 15 * 2.304) * 1e-6, 1e-6);
    for (std::size_t s = 0; s < 3; ++s) EXPECT_EQ(scans[s].index, s);

    // 50 packets lost mid-revolution (120 degrees): that sweep covers two thirds of a turn.
    VelodyneSweeps lossy(VelodyneModel::VLP16, *velodyne_factory_calibration(VelodyneModel::VLP16));
    scans.clear();
    for (std::size_t k = 0; k < packets.size(); ++k) {
        if (k >= 100 && k < 150) continue;
        if (lossy.add(packets[k], 0, "test")) scans.push_back(lossy.take());
    }
    ASSERT_EQ(scans.size(), 2u);
    EXPECT_NEAR(scans[1].completeness, 2.0 / 3, 1e-9);
}

TEST(VelodyneSweeps, DualReturnsKeepTheFirstBlockOrBothWithoutRepeats) {
    // Even blocks: the last return at 20 m; odd blocks: the strongest, at 8 m on even channels and
    // the same 20 m (one return only) on odd ones.
    const auto raw = [](int, int b, int j) -> std::uint16_t { return b % 2 == 0 || j % 2 ? 10000 : 4000; };
    const auto packet = velodyne_packet(0, 500, 20, raw, 0x22, 0x39, kPastHourUs, true);
    for (auto returns : {VelodyneReturns::First, VelodyneReturns::Both}) {
        VelodyneSweeps sweeps(VelodyneModel::VLP16, *velodyne_factory_calibration(VelodyneModel::VLP16), returns);
        sweeps.add(packet, 1699999200LL * 1000000000 + kPastHourUs * 1000LL, "test");
        ASSERT_TRUE(sweeps.finish());
        const RecordedScan scan = sweeps.take();
        std::size_t near = 0, far = 0;
        for (const auto& p : scan.cloud.points) (std::abs(p.norm() - 8) < 1e-9 ? near : far) += 1;
        EXPECT_EQ(far, 6u * 32);  // 6 firings of 32 channels
        EXPECT_EQ(near, returns == VelodyneReturns::Both ? 6u * 16 : 0u);
        // Both blocks of a firing are one firing's time: the second return is not 110 us later.
        EXPECT_NEAR(*std::max_element(scan.times.begin(), scan.times.end()), (5 * 110.592 + 55.296 + 15 * 2.304) * 1e-6, 1e-9);
    }
}

TEST(VelodyneSweeps, ASensorThatDoesNotTurnGivesOneFiringOfTheSmallestCompleteness) {
    // Every block at one azimuth (a sensor stopped, or blocks sent again): one firing is kept, the
    // rest are repeats; its sweep covers no step but is not empty.
    const auto packet = velodyne_packet(0, 12345, 0, [](int, int, int) -> std::uint16_t { return 4000; });
    VelodyneSweeps sweeps(VelodyneModel::VLP16, *velodyne_factory_calibration(VelodyneModel::VLP16));
    sweeps.add(packet, 0, "test");
    sweeps.add(packet, 0, "test");
    ASSERT_TRUE(sweeps.finish());
    const RecordedScan scan = sweeps.take();
    EXPECT_EQ(scan.cloud.points.size(), 32u);
    EXPECT_GT(scan.completeness, 0);
    EXPECT_LT(scan.completeness, 1e-3);
}

TEST(VelodyneSweeps, HdlSixtyFourBanksAndOffsetsFollowTheCalibration) {
    // Two banks: 0xEEFF blocks carry lasers 0-31, 0xDDFF blocks lasers 32-63, in pairs of one azimuth.
    VelodyneCalibration c;
    c.name = "test";
    for (int i = 0; i < 64; ++i) {
        VelodyneLaser l;
        l.vert_correction = (2.0 - 0.4 * i) * M_PI / 180;
        l.rot_correction = (i % 3 - 1) * 0.02;
        l.vert_offset_correction = 0.2;
        l.horiz_offset_correction = i % 2 ? 0.026 : -0.026;
        l.dist_correction = 1.4;
        c.lasers.push_back(l);
    }
    std::vector<std::uint8_t> b(1206, 0);
    for (int blk = 0; blk < 12; ++blk) {
        put<std::uint16_t>(b, 100 * blk, blk % 2 ? 0xDDFF : 0xEEFF);
        put<std::uint16_t>(b, 100 * blk + 2, static_cast<std::uint16_t>(9000 + 17 * (blk / 2)));
        for (int j = 0; j < 32; ++j) put<std::uint16_t>(b, 100 * blk + 4 + 3 * j, 6000);
    }
    put<std::uint32_t>(b, 1200, kPastHourUs);
    b[1204] = 'T', b[1205] = 0x41;  // status bytes, not a product id
    VelodyneSweeps sweeps(VelodyneModel::HDL64E, c);
    sweeps.add(b, 1699999200LL * 1000000000 + kPastHourUs * 1000LL, "test");
    ASSERT_TRUE(sweeps.finish());
    const RecordedScan scan = sweeps.take();
    ASSERT_EQ(scan.cloud.points.size(), 12u * 32);
    for (int blk = 0; blk < 12; ++blk) {
        for (int j = 0; j < 32; ++j) {
            const int laser = j + (blk % 2 ? 32 : 0);
            const VelodyneLaser& l = c.lasers[laser];
            const Eigen::Vector3d p = scan.cloud.points[static_cast<std::size_t>(32 * blk + j)];
            // The laser sits vert_offset up and horiz_offset sideways (along the azimuth's normal);
            // its ray leaves at its elevation, corrected distance d = 12 m + 1.4 m.
            const double alpha = (9000 + 17 * (blk / 2)) * M_PI / 18000 - l.rot_correction;
            const double d = 12.0 + 1.4, w = l.vert_correction;
            // In the sensor's own frame (y ahead at azimuth 0, x right).
            const double xy = d * std::cos(w) - l.vert_offset_correction * std::sin(w);
            const Eigen::Vector3d expect_sensor(xy * std::sin(alpha) - l.horiz_offset_correction * std::cos(alpha),
                                                xy * std::cos(alpha) + l.horiz_offset_correction * std::sin(alpha),
                                                d * std::sin(w) + l.vert_offset_correction * std::cos(w));
            EXPECT_NEAR((p - Eigen::Vector3d(expect_sensor.y(), -expect_sensor.x(), expect_sensor.z())).norm(), 0, 1e-9) << laser;
        }
    }
}

TEST(VelodyneCalibration, BothYamlStylesGiveTheLasersByIdAndBadOnesAreRefused) {
    const std::string flow =
        "lasers:\n"
        "- {dist_correction: 0.01, laser_id: 1, rot_correction: 0.02, vert_correction: 0.1}\n"
        "- {dist_correction: 0.0, laser_id: 0, rot_correction: -0.02, vert_correction: -0.1, two_pt_correction_available: true,\n"
        "   dist_correction_x: 0.03, dist_correction_y: 0.04, vert_offset_correction: 0.2, horiz_offset_correction: 0.026}\n"
        "num_lasers: 2\n";
    const std::string block =
        "distance_resolution: 0.004\n"
        "lasers:\n"
        "- laser_id: 0\n  vert_correction: -0.1\n  rot_correction: -0.02\n  two_pt_correction_available: true\n"
        "  dist_correction_x: 0.03\n  dist_correction_y: 0.04\n  vert_offset_correction: 0.2\n  horiz_offset_correction: 0.026\n"
        "- laser_id: 1\n  vert_correction: 0.1\n  rot_correction: 0.02\n  dist_correction: 0.01\n";
    for (const std::string& text : {flow, block}) {
        const VelodyneCalibration c = parse_velodyne_calibration(text, "cal.yaml");
        ASSERT_EQ(c.lasers.size(), 2u);
        EXPECT_DOUBLE_EQ(c.lasers[0].vert_correction, -0.1);
        EXPECT_TRUE(c.lasers[0].two_pt_correction);
        EXPECT_DOUBLE_EQ(c.lasers[0].dist_correction_y, 0.04);
        EXPECT_DOUBLE_EQ(c.lasers[0].horiz_offset_correction, 0.026);
        EXPECT_DOUBLE_EQ(c.lasers[1].dist_correction, 0.01);
        EXPECT_FALSE(c.lasers[1].two_pt_correction);
        EXPECT_EQ(c.rings(), (std::vector<std::uint16_t>{1, 0}));
    }
    EXPECT_DOUBLE_EQ(parse_velodyne_calibration(block, "cal.yaml").distance_resolution, 0.004);
    EXPECT_DOUBLE_EQ(parse_velodyne_calibration(flow, "cal.yaml").distance_resolution, 0.002);
    const std::pair<std::string, std::string> bad[] = {
        {"lasers: [{laser_id: 0, vert_correction: 0.1}, {laser_id: 0, vert_correction: 0.2}]", "repeats"},
        {"lasers: [{laser_id: 0, vert_correction: 0.1}, {laser_id: 2, vert_correction: 0.2}]", "outside"},
        {"lasers: [{vert_correction: 0.1}]", "no laser_id"},
        {"lasers: [{laser_id: 0, vert_correction: abc}]", "not a finite number"},
        {"lasers: [{laser_id: 0, vert_correction: 3}]", "out of range"},
        {"lasers: [{laser_id: 0}]\nnum_lasers: 16", "num_lasers says 16"},
        {"lasers: [{laser_id: 0}]\ndistance_resolution: 0", "distance_resolution"},
        {"lasers: {laser_id: 0}", "not a list"},
        {"num_lasers: 16", "no lasers"},
        {"lasers: [{laser_id: 0, vert_correction: [1]}]", "not a value"},
        {"lasers: [unclosed", "not YAML"},
        {"- 1\n- 2", "not a YAML mapping"},
    };
    for (const auto& [text, why] : bad) {
        SCOPED_TRACE(text);
        try {
            parse_velodyne_calibration(text, "cal.yaml");
            ADD_FAILURE() << "accepted";
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find("cal.yaml"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    }
    VelodyneCalibration sixteen = *velodyne_factory_calibration(VelodyneModel::VLP16);
    EXPECT_THROW(VelodyneSweeps(VelodyneModel::HDL32E, sixteen), FormatError);
    EXPECT_FALSE(velodyne_factory_calibration(VelodyneModel::HDL64E));
}

TEST(VelodyneSweeps, PacketsThatDisagreeWithTheSensorAreRefusedNamingThePacket) {
    const auto raw = [](int, int, int) -> std::uint16_t { return 3000; };
    const auto good = velodyne_packet(0, 0, 20, raw);
    const auto refused = [&](std::vector<std::uint8_t> p, const std::string& why) {
        SCOPED_TRACE(why);
        VelodyneSweeps sweeps(VelodyneModel::VLP16, *velodyne_factory_calibration(VelodyneModel::VLP16));
        try {
            sweeps.add(p, 0, "cap.pcap: packet 7");
            ADD_FAILURE() << "accepted";
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find("cap.pcap: packet 7"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
        }
    };
    refused(std::vector<std::uint8_t>(good.begin(), good.end() - 6), "1200 bytes");
    auto other = good;
    other[1205] = 0x21;
    refused(other, "HDL-32E");
    auto lower = good;
    put<std::uint16_t>(lower, 300, 0xDDFF);
    refused(lower, "block 3 has flag 0xddff");
    auto azimuth = good;
    put<std::uint16_t>(azimuth, 502, 36000);
    refused(azimuth, "azimuth 36000");
    auto late = good;
    put<std::uint32_t>(late, 1200, 3600000000u);
    refused(late, "past the hour");
}

TEST(VelodyneRecording, APcapGivesItsSweepsWithTheFactoryAnglesOrTheCalibrationBesideIt) {
    const fs::path dir = temp_dir("velodyne");
    const auto raw = [](int k, int b, int j) -> std::uint16_t { return static_cast<std::uint16_t>(3000 + (k * 12 + b + j) % 500); };
    auto packets = vlp16_packets(150, 35000, raw);  // 10 degrees before the wrap, then 350 after it
    write_pcap(dir / "vlp.pcap", packets, 2368);
    auto source = open_recording(dir / "vlp.pcap");
    EXPECT_NE(source->description().find("Velodyne VLP-16, strongest return, 16 lasers (built-in VLP-16), UDP port 2368"), std::string::npos)
        << source->description();
    RecordedScan scan;
    std::vector<RecordedScan> scans;
    while (source->next(scan)) scans.push_back(scan);
    ASSERT_EQ(scans.size(), 2u);
    EXPECT_EQ(scans[0].cloud.points.size(), 1000u / 20 * 32);
    EXPECT_EQ(scans[0].cloud.points.size() + scans[1].cloud.points.size(), 150u * 12 * 32);
    const RecordingSummary summary = summarize_recording(dir / "vlp.pcap");
    EXPECT_EQ(summary.scans, 2u);
    EXPECT_EQ(summary.partial_scans, 2u);
    EXPECT_TRUE(summary.per_point_times);
    ASSERT_EQ(summary.topics.size(), 1u);
    EXPECT_EQ(summary.topics[0].name, "udp:2368");

    // A calibration beside the pcap (X.yaml) replaces the factory angles: every laser at 0 degrees.
    std::ofstream(dir / "vlp.yaml") << "lasers:\n" << [] {
        std::string s;
        for (int i = 0; i < 16; ++i) s += "- {laser_id: " + std::to_string(i) + ", vert_correction: 0.0}\n";
        return s;
    }();
    const RecordedScan flat = read_recorded_scan(dir / "vlp.pcap", 0);
    for (const auto& p : flat.cloud.points) EXPECT_NEAR(p.z(), 0, 1e-12);
    // One of another sensor is refused naming the sensor.
    std::ofstream(dir / "vlp.yaml") << "lasers: [{laser_id: 0}]\n";
    try {
        open_recording(dir / "vlp.pcap");
        ADD_FAILURE() << "accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("1 lasers for a Velodyne VLP-16"), std::string::npos) << e.what();
    }
    fs::remove(dir / "vlp.yaml");

    // Without a product id (an HDL-64E), a calibration must be given.
    for (auto& p : packets) p[1205] = 0;
    write_pcap(dir / "hdl.pcap", packets, 2368);
    EXPECT_THROW(open_recording(dir / "hdl.pcap"), InvalidArgument);
    // A truncated data packet on the sensor's port names its packet.
    packets = vlp16_packets(5, 0, raw);
    packets[3].resize(1000);
    write_pcap(dir / "cut.pcap", packets, 2368);
    try {
        auto s = open_recording(dir / "cut.pcap");
        while (s->next(scan)) {
        }
        ADD_FAILURE() << "accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("cut.pcap: packet 3: a Velodyne data packet of 1000 bytes"), std::string::npos) << e.what();
    }
    fs::remove_all(dir);
}

TEST(VelodyneRecording, AFreeRunningSensorClockIsAnchoredAtTheFirstPacketsCaptureTime) {
    const fs::path dir = temp_dir("velodyne_clock");
    const auto raw = [](int, int, int) -> std::uint16_t { return 3000; };
    std::vector<std::vector<std::uint8_t>> packets;
    // 5 s past its own hour, 795 s from the capture's: the sensor is not synchronised.
    for (int k = 0; k < 3; ++k)
        packets.push_back(velodyne_packet(k, 240 * k, 20, raw, 0x22, 0x37, 5000000 + static_cast<std::uint32_t>(std::lround(k * 1327.104))));
    write_pcap(dir / "free.pcap", packets, 2368);
    const RecordedScan scan = read_recorded_scan(dir / "free.pcap", 0);
    EXPECT_EQ(scan.stamp_ns, 1700000000LL * 1000000000 + 10000);  // the first packet's capture time (10 us)
    EXPECT_NEAR(scan.times.back(), (35 * 110.592 + 55.296 + 15 * 2.304) * 1e-6, 1e-6);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lidarsurf
