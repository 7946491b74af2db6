// Recordings: Ouster packets written here from the firmware manual's layout (every profile),
// pcaps written by libpcap's own writer, ROS 1 bags written by ROS's own writer (python3-rosbag),
// and the real Ouster recordings of ../shared/data (skipped when absent).
#include <gtest/gtest.h>

#include <pcap/pcap.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>

#include <unistd.h>

#include <Eigen/Eigenvalues>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/ouster.hpp"
#include "lidarsurf/io/pcap.hpp"
#include "lidarsurf/io/point_cloud2.hpp"
#include "lidarsurf/io/recording.hpp"
#include "io/ouster_test_writer.hpp"

namespace lidarsurf {
namespace {

using namespace lidarsurf::test;

const char* kProfiles[] = {"LEGACY", "RNG19_RFL8_SIG16_NIR16", "RNG19_RFL8_SIG16_NIR16_DUAL", "RNG15_RFL8_NIR8", "FUSA_RNG15_RFL8_NIR8_DUAL"};

double wrap(double a) { return std::remainder(a, 2 * M_PI); }

TEST(OusterSweeps, EveryProfileGivesTheManualsRayDirectionsAtTheEncodedRange) {
    for (const char* profile : kProfiles) {
        SCOPED_TRACE(profile);
        Sensor s;
        s.profile = profile;
        const OusterMetadata m = s.metadata();
        OusterSweeps sweeps(m);
        // Ranges multiple of 8 mm (RNG15 profiles keep 8 mm steps); one pixel in 7 returned nothing.
        const auto range = [](int c, int b, int) -> std::uint32_t { return (c * 8 + b) % 7 == 3 ? 0 : 4000 + 8 * ((c + 3 * b) % 500); };
        for (const auto& p : frame_packets(s, 42, range)) EXPECT_FALSE(sweeps.add(p, "test"));
        ASSERT_TRUE(sweeps.finish());
        const RecordedScan scan = sweeps.take();
        EXPECT_NEAR(scan.completeness, 1.0, 1e-12);
        EXPECT_EQ(scan.stamp_ns, 1000000000);
        std::size_t expected = 0, empty = 0;
        for (int c = 0; c < s.columns; ++c)
            for (int b = 0; b < s.beams; ++b) (range(c, b, 0) ? expected : empty) += 1;
        ASSERT_EQ(scan.cloud.points.size(), expected);
        EXPECT_EQ(scan.no_return.size(), empty);
        ASSERT_EQ(scan.times.size(), expected);
        ASSERT_EQ(scan.cloud.rings.size(), expected);
        ASSERT_EQ(scan.cloud.intensities.size(), expected);
        std::size_t i = 0;
        for (int c = 0; c < s.columns; ++c) {
            for (int b = 0; b < s.beams; ++b) {
                if (!range(c, b, 0)) continue;
                const Eigen::Vector3d& p = scan.cloud.points[i];
                // The manual: range from the lidar origin (beam offset 0 here); altitude is the
                // beam's; azimuth = encoder angle 2 pi (1 - c / W) minus the beam's azimuth offset.
                EXPECT_NEAR(p.norm(), 1e-3 * range(c, b, 0), 1e-9);
                EXPECT_NEAR(std::asin(p.z() / p.norm()), s.altitude()[b] * M_PI / 180, 1e-9);
                EXPECT_NEAR(wrap(std::atan2(p.y(), p.x()) - (2 * M_PI * (1 - c / double(s.columns)) - s.azimuth()[b] * M_PI / 180)), 0, 1e-9);
                EXPECT_EQ(scan.cloud.rings[i], b);
                EXPECT_EQ(scan.cloud.intensities[i], reflectivity_of(c, b, 0));
                EXPECT_NEAR(scan.times[i], 50e-6 * c, 1e-9);
                ++i;
            }
        }
    }
}

TEST(OusterSweeps, DualProfilesGiveSecondReturnsWhenAsked) {
    for (const char* profile : {"RNG19_RFL8_SIG16_NIR16_DUAL", "FUSA_RNG15_RFL8_NIR8_DUAL"}) {
        SCOPED_TRACE(profile);
        Sensor s;
        s.profile = profile;
        OusterSweeps sweeps(s.metadata(), OusterReturns::Both);
        const auto range = [](int, int b, int r) -> std::uint32_t { return r == 0 ? 3000 : (b % 2 ? 9000 : 0); };
        for (const auto& p : frame_packets(s, 1, range)) sweeps.add(p, "test");
        ASSERT_TRUE(sweeps.finish());
        const RecordedScan scan = sweeps.take();
        std::size_t near = 0, far = 0;
        for (const auto& p : scan.cloud.points) (std::abs(p.norm() - 3) < 1e-9 ? near : far) += 1;
        ASSERT_EQ(scan.cloud.intensities.size(), scan.cloud.points.size());
        for (std::size_t i = 0; i < scan.cloud.points.size(); ++i) {  // each return its own reflectivity
            const int c = static_cast<int>(std::lround(scan.times[i] / 50e-6)), r = std::abs(scan.cloud.points[i].norm() - 3) < 1e-9 ? 0 : 1;
            EXPECT_EQ(scan.cloud.intensities[i], reflectivity_of(c, scan.cloud.rings[i], r)) << i;
        }
        EXPECT_EQ(near, std::size_t(s.columns * s.beams));
        EXPECT_EQ(far, std::size_t(s.columns * s.beams / 2));
    }
}

TEST(OusterSweeps, BeamOriginsAndTheLidarToSensorTransformPlaceThePoints) {
    Sensor s;
    s.beam_offset_mm = 20;
    s.lidar_to_sensor = "[-1,0,0,0, 0,-1,0,0, 0,0,1,36.18, 0,0,0,1]";  // the firmware's: turned half a revolution, 36.18 mm up
    OusterSweeps sweeps(s.metadata());
    for (const auto& p : frame_packets(s, 0, [](int, int, int) { return 5000u; })) sweeps.add(p, "test");
    sweeps.finish();
    const RecordedScan scan = sweeps.take();
    EXPECT_NEAR(scan.origin.z(), 0.03618, 1e-12);
    std::size_t i = 0;
    for (int c = 0; c < s.columns; ++c) {
        const double encoder = 2 * M_PI * (1 - c / double(s.columns));
        for (int b = 0; b < s.beams; ++b, ++i) {
            // Back in the lidar frame: the beam starts on the circle of radius 20 mm at the encoder
            // angle; the range counts from the lidar origin, so the point is (5 m - 20 mm) from there.
            const Eigen::Vector3d sensor = scan.cloud.points[i];
            const Eigen::Vector3d lidar(-sensor.x(), -sensor.y(), sensor.z() - 0.03618);
            const Eigen::Vector3d beam_origin(0.02 * std::cos(encoder), 0.02 * std::sin(encoder), 0);
            EXPECT_NEAR((lidar - beam_origin).norm(), 5.0 - 0.02, 1e-9);
            EXPECT_NEAR(std::asin((lidar - beam_origin).z() / (lidar - beam_origin).norm()), s.altitude()[b] * M_PI / 180, 1e-9);
        }
    }
}

TEST(OusterSweeps, ASweepEndsWhereTheFrameIdChangesAndPartialSweepsSayHowPartial) {
    Sensor s;
    OusterSweeps sweeps(s.metadata());
    const auto range = [](int, int, int) { return 7000u; };
    // The recording starts mid-revolution: the last 3 packets of frame 9, then all of frame 10,
    // then 2 packets of frame 11; one packet of frame 10 comes twice.
    int closed = 0;
    std::vector<RecordedScan> scans;
    auto feed = [&](const std::vector<std::uint8_t>& p) {
        if (sweeps.add(p, "test")) {
            ++closed;
            scans.push_back(sweeps.take());
        }
    };
    for (int first = s.columns - 3 * s.per_packet; first < s.columns; first += s.per_packet) feed(packet(s, 9, first, range));
    for (const auto& p : frame_packets(s, 10, range)) feed(p);
    feed(packet(s, 10, 0, range));
    for (int first = 0; first < 2 * s.per_packet; first += s.per_packet) feed(packet(s, 11, first, range));
    ASSERT_TRUE(sweeps.finish());
    scans.push_back(sweeps.take());
    ASSERT_EQ(scans.size(), 3u);
    EXPECT_EQ(closed, 2);
    EXPECT_NEAR(scans[0].completeness, 3.0 * s.per_packet / s.columns, 1e-12);
    EXPECT_NEAR(scans[1].completeness, 1.0, 1e-12);
    EXPECT_EQ(scans[1].cloud.points.size(), std::size_t(s.columns * s.beams));  // the repeated packet counted once
    EXPECT_NEAR(scans[2].completeness, 2.0 * s.per_packet / s.columns, 1e-12);
    for (std::size_t k = 0; k < scans.size(); ++k) EXPECT_EQ(scans[k].index, k);
}

TEST(OusterSweeps, PacketsThatDisagreeWithTheMetadataAreRefusedNamingWhere) {
    Sensor s;
    OusterSweeps sweeps(s.metadata());
    auto p = packet(s, 0, 0, [](int, int, int) { return 1000u; });
    auto shorter = p;
    shorter.pop_back();
    try {
        sweeps.add(shorter, "cap.pcap: packet 7");
        FAIL() << "a short packet was accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("cap.pcap: packet 7"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(std::to_string(p.size() - 1) + " bytes"), std::string::npos) << e.what();
    }
    put<std::uint16_t>(p, 32 + 8, static_cast<std::uint16_t>(s.columns));  // measurement id past the frame
    EXPECT_THROW(sweeps.add(p, "test"), FormatError);
}

TEST(OusterMetadata, TheNestedLayoutOfNewerFirmwareReadsAsTheFlatOne) {
    Sensor s;
    s.beam_offset_mm = 15.806;
    const OusterMetadata flat = s.metadata();
    std::string nested = "{\"beam_intrinsics\":{\"beam_altitude_angles\":[20,14.2857142857,8.57142857143,2.85714285714,-2.85714285714,"
                         "-8.57142857143,-14.2857142857,-20],\"beam_azimuth_angles\":[-1.5,1.5,-1.5,1.5,-1.5,1.5,-1.5,1.5],"
                         "\"beam_to_lidar_transform\":[1,0,0,15.806,0,1,0,0,0,0,1,0,0,0,0,1]},"
                         "\"config_params\":{\"lidar_mode\":\"128x10\",\"udp_port_lidar\":7502},"
                         "\"lidar_data_format\":{\"pixels_per_column\":8,\"columns_per_packet\":16,\"columns_per_frame\":128,"
                         "\"column_window\":[0,127],\"udp_profile_lidar\":\"RNG19_RFL8_SIG16_NIR16\"},"
                         "\"lidar_intrinsics\":{\"lidar_to_sensor_transform\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]},"
                         "\"sensor_info\":{\"prod_line\":\"TEST\"}}";
    const OusterMetadata n = parse_ouster_metadata(nested, "nested");
    EXPECT_EQ(n.profile, flat.profile);
    EXPECT_EQ(n.packet_size(), flat.packet_size());
    EXPECT_NEAR(n.beam_offset_x_mm, flat.beam_offset_x_mm, 1e-12);
    for (int b = 0; b < 8; ++b) EXPECT_NEAR(n.altitude_deg[b], flat.altitude_deg[b], 1e-9);
    EXPECT_EQ(n.prod_line, "TEST");
    EXPECT_THROW(parse_ouster_metadata("{\"beam_altitude_angles\":[1,2]}", "m"), FormatError);
    EXPECT_THROW(parse_ouster_metadata("not json", "m"), FormatError);
    Sensor unknown;
    unknown.profile = "RNG99";
    EXPECT_THROW(unknown.metadata(), FormatError);
}

TEST(OusterPcap, APcapOfFragmentedPacketsGivesTheSweepsOfThePackets) {
    const fs::path dir = temp_dir("pcap");
    Sensor s;
    s.beams = 64;  // 16 columns x (12 + 64 x 12) bytes: 12,544-byte packets, 9 fragments each
    const auto range = [](int c, int b, int) -> std::uint32_t { return 2000 + 10 * c + b; };
    auto packets = frame_packets(s, 5, range);
    for (const auto& p : frame_packets(s, 6, range)) packets.push_back(p);
    write_pcap(dir / "os.pcap", packets, 7502);
    std::ofstream(dir / "os.json") << s.json();  // beside it, under the same base name
    OusterSweeps direct(s.metadata());
    for (const auto& p : frame_packets(s, 5, range)) direct.add(p, "direct");
    direct.finish();
    const RecordedScan expected = direct.take();
    auto source = open_recording(dir / "os.pcap");
    RecordedScan scan;
    std::size_t scans = 0;
    while (source->next(scan)) {
        ++scans;
        ASSERT_EQ(scan.cloud.points.size(), expected.cloud.points.size());
        for (std::size_t i = 0; i < expected.cloud.points.size(); ++i) EXPECT_EQ(scan.cloud.points[i], expected.cloud.points[i]);
    }
    EXPECT_EQ(scans, 2u);
    EXPECT_EQ(read_recorded_scan(dir / "os.pcap", 1).index, 1u);
    EXPECT_THROW(read_recorded_scan(dir / "os.pcap", 2), InvalidArgument);
    const RecordingSummary summary = summarize_recording(dir / "os.pcap");
    EXPECT_EQ(summary.scans, 2u);
    ASSERT_EQ(summary.topics.size(), 1u);
    EXPECT_EQ(summary.topics[0].messages, 2u * 8);  // 8 datagrams a sweep (of 9 fragments each)
    fs::remove_all(dir);
}

TEST(OusterPcap, CapturesThatCannotBeReadAreRefusedNamingThePacket) {
    const fs::path dir = temp_dir("pcap_bad");
    Sensor s;
    std::ofstream(dir / "os.json") << s.json();
    std::ofstream(dir / "usb.json") << s.json();
    std::ofstream(dir / "snap.json") << s.json();
    std::ofstream(dir / "cut.json") << s.json();
    const auto packets = frame_packets(s, 1, [](int, int, int) { return 3000u; });
    write_pcap(dir / "os.pcap", packets, 7502);
    // A file cut in the middle of a packet.
    const auto size = fs::file_size(dir / "os.pcap");
    fs::copy_file(dir / "os.pcap", dir / "cut.pcap");
    fs::resize_file(dir / "cut.pcap", size - 100);
    EXPECT_THROW({
        auto src = open_recording(dir / "cut.pcap");
        RecordedScan scan;
        while (src->next(scan)) {
        }
    }, FormatError);
    // A capture whose snapshot length cut a packet.
    write_pcap(dir / "snap.pcap", packets, 7502, DLT_EN10MB, 200);
    try {
        auto src = open_recording(dir / "snap.pcap");
        RecordedScan scan;
        while (src->next(scan)) {
        }
        FAIL() << "a cut packet was accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("packet"), std::string::npos) << e.what();
    }
    // A USB capture: no IP in it.
    write_pcap(dir / "usb.pcap", packets, 7502, DLT_USB_LINUX);
    EXPECT_THROW(open_recording(dir / "usb.pcap"), FormatError);
    // No metadata beside it.
    fs::copy_file(dir / "os.pcap", dir / "alone.pcap");
    EXPECT_THROW(open_recording(dir / "alone.pcap"), InvalidArgument);
    // Not a capture.
    std::ofstream(dir / "text.pcap") << "hello";
    std::ofstream(dir / "text.json") << s.json();
    EXPECT_THROW(open_recording(dir / "text.pcap"), FormatError);
    fs::remove_all(dir);
}

TEST(PointCloud2, AnEmptyCloudOfBillionsOfRowsIsEmptyAtOnce) {
    // The fuzzer's input (fuzz_point_cloud2): width 0, height 2^32 - 1, row_step 0, no data; it
    // walked every empty row.
    PointCloud2Message m;
    m.width = 0;
    m.height = 0xffffffffu;
    m.point_step = 16;
    m.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}};
    std::size_t empty = 1;
    EXPECT_TRUE(decode_point_cloud2(m, "fuzz", &empty).cloud.points.empty());
    EXPECT_EQ(empty, 0u);
    m.width = 2;  // rows of 32 bytes, none in the data
    EXPECT_THROW(decode_point_cloud2(m, "fuzz"), FormatError);
}

TEST(PointCloud2, AnOrganizedCloudsEmptyRaysPointWhereTheirBeamAndColumnLook) {
    // 16 beams (elevation -15 + 2 b degrees, azimuth offsets of +-1.2 degrees) by 360 columns (one
    // degree apart, turning clockwise from 90 degrees), as an organized cloud: NaN where a ray
    // returned nothing (the sky above 7 degrees, and one ray in 5 below), zeros in two of them.
    const std::uint32_t height = 16, width = 360;
    const auto el = [](std::uint32_t b) { return (-15.0 + 2.0 * b) * M_PI / 180; };
    const auto az = [](std::uint32_t b, std::uint32_t c) { return (90.0 - c + (b % 2 ? 1.2 : -1.2)) * M_PI / 180; };
    const auto empty_at = [](std::uint32_t b, std::uint32_t c) { return b > 11 || (b * 7 + c) % 5 == 0; };
    std::vector<std::uint8_t> data(std::size_t{height} * width * 12);
    for (std::uint32_t b = 0; b < height; ++b) {
        for (std::uint32_t c = 0; c < width; ++c) {
            const double r = 10 + (b * 13 + c * 7) % 40;  // 10 to 49 m
            float v[3] = {static_cast<float>(r * std::cos(el(b)) * std::cos(az(b, c))), static_cast<float>(r * std::cos(el(b)) * std::sin(az(b, c))),
                          static_cast<float>(r * std::sin(el(b)))};
            if (empty_at(b, c)) v[0] = v[1] = v[2] = (b + c) % 2 ? std::nanf("") : 0.0f;
            std::memcpy(data.data() + (std::size_t{b} * width + c) * 12, v, sizeof v);
        }
    }
    PointCloud2Message m;
    m.height = height, m.width = width, m.point_step = 12, m.row_step = 12 * width;
    m.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}};
    m.data = data;
    std::size_t empty = 0;
    const RecordedScan scan = decode_point_cloud2(m, "organized", &empty);
    std::vector<Eigen::Vector3d> expected;
    for (std::uint32_t b = 0; b < height; ++b)
        for (std::uint32_t c = 0; c < width; ++c)
            if (empty_at(b, c) && b <= 11)  // the sky's rows have no return to place them
                expected.emplace_back(std::cos(el(b)) * std::cos(az(b, c)), std::cos(el(b)) * std::sin(az(b, c)), std::sin(el(b)));
    ASSERT_EQ(scan.no_return.size(), expected.size());
    EXPECT_GT(empty, expected.size());
    double worst = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
        const Eigen::Vector3d d = scan.no_return[i].cast<double>();
        worst = std::max(worst, std::atan2(d.cross(expected[i]).norm(), d.dot(expected[i])));  // the angle between them
    }
    EXPECT_LT(worst, 1e-5);  // radians: float32 points
    // The same points shuffled over the grid are no beams by azimuths: no direction is guessed.
    std::vector<std::uint8_t> shuffled(data.size());
    for (std::size_t i = 0; i < std::size_t{height} * width; ++i)
        std::memcpy(shuffled.data() + 12 * ((i * 7919) % (std::size_t{height} * width)), data.data() + 12 * i, 12);
    m.data = shuffled;
    EXPECT_TRUE(decode_point_cloud2(m, "shuffled").no_return.empty());
}

// ---- The real Ouster recordings (the SDK's test data). ----

fs::path shared_ouster() { return fs::path(LIDARSURF_SHARED_DATA) / "ouster"; }

// The streets the sensors stood in are level: the lowest points 3-15 m around the sensor lie on
// a plane whose normal is vertical, below the sensor: a check of the angles and signs of the
// pixel-to-point model (a wrong altitude sign or beam order tilts or folds that ring).
void expect_level_ground(const RecordedScan& scan) {
    std::vector<Eigen::Vector3d> ring;
    for (const auto& p : scan.cloud.points)
        if (p.head<2>().norm() > 3 && p.head<2>().norm() < 15) ring.push_back(p);
    ASSERT_GT(ring.size(), 500u);
    std::vector<double> z;
    for (const auto& p : ring) z.push_back(p.z());
    std::nth_element(z.begin(), z.begin() + z.size() / 20, z.end());
    const double ground = z[z.size() / 20];
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> low;
    for (const auto& p : ring)
        if (std::abs(p.z() - ground) < 0.15) low.push_back(p), mean += p;
    ASSERT_GT(low.size(), 100u);
    mean /= static_cast<double>(low.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& p : low) cov += (p - mean) * (p - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d normal = eig.eigenvectors().col(0);
    EXPECT_GT(std::abs(normal.z()), std::cos(5 * M_PI / 180)) << "ground normal " << normal.transpose();
    EXPECT_LT(ground, -0.3);  // the sensor stood above the ground
}

TEST(RealOuster, EverySdkRecordingIsReadAndItsGroundIsLevel) {
    if (!fs::exists(shared_ouster())) GTEST_SKIP() << shared_ouster() << " is absent";
    std::size_t recordings = 0;
    for (const auto& entry : fs::directory_iterator(shared_ouster())) {
        if (entry.path().extension() != ".pcap" || !fs::exists(fs::path(entry.path()).replace_extension(".json"))) continue;
        SCOPED_TRACE(entry.path().filename().string());
        ++recordings;
        auto source = open_recording(entry.path());
        RecordedScan scan;
        bool whole = false;
        while (source->next(scan)) {
            const double period = 1.0 / read_ouster_metadata(fs::path(entry.path()).replace_extension(".json")).frequency_hz;
            for (float t : scan.times) ASSERT_TRUE(t >= 0 && t <= period) << t;
            // OS-1-64_1024x10_fw20 stood among walls with no ground 3-15 m around it (its
            // points: 90 % within 8 m, the lowest 1.8 m below the sensor).
            if (scan.completeness > 0.99) {
                whole = true;
                if (entry.path().filename().string().rfind("OS-1-64_", 0) != 0) expect_level_ground(scan);
            }
        }
        if (entry.path().filename().string().rfind("OS-1-128_", 0) != 0) {
            EXPECT_TRUE(whole);  // the OS-1-128 recording holds 8 packets
        }
    }
    EXPECT_GE(recordings, 7u);
}

#ifdef LIDARSURF_HAVE_ROSBAG
TEST(RealOuster, TheDriversRawPacketBagIsReadWithItsMetadataTopic) {
    const fs::path bag = shared_ouster() / "ouster_ros_512x10_raw.bag";
    if (!fs::exists(bag)) GTEST_SKIP() << bag << " is absent";
    auto source = open_recording(bag);
    EXPECT_NE(source->description().find("/os_node0/lidar_packets"), std::string::npos);
    RecordedScan scan;
    ASSERT_TRUE(source->next(scan));
    EXPECT_GT(scan.completeness, 0.99);
    expect_level_ground(scan);
}

// ---- ROS 1 bags written by ROS's own writer. ----

struct Expected {
    std::vector<std::vector<std::array<double, 5>>> messages;  // x y z t i (t, i NaN: none)
};

Expected read_expected(const fs::path& path) {
    Expected e;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("message", 0) == 0) {
            e.messages.emplace_back();
            continue;
        }
        std::istringstream s(line);
        std::array<double, 5> v{};
        std::string t, i;
        s >> v[0] >> v[1] >> v[2] >> t >> i;
        v[3] = t == "none" ? NAN : std::stod(t);
        v[4] = i == "none" ? NAN : std::stod(i);
        e.messages.back().push_back(v);
    }
    return e;
}

class Ros1Bag : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = temp_dir("bag");
        const std::string cmd = "/usr/bin/python3 " + std::string(LIDARSURF_SOURCE_DIR) + "/tests/io/write_ros1_bag.py " + dir_.string() + " 2>&1";
        written_ = std::system(cmd.c_str()) == 0 && fs::exists(dir_ / "clouds.bag");
    }
    static void TearDownTestSuite() { fs::remove_all(dir_); }
    void SetUp() override {
        if (!written_) GTEST_SKIP() << "python3-rosbag (ROS's own bag writer) is not installed";
    }
    static inline fs::path dir_;
    static inline bool written_ = false;
};

TEST_F(Ros1Bag, EveryPointCloud2LayoutGivesThePointsAndTimesTheWriterPutIn) {
    for (const char* bag : {"clouds.bag", "clouds_bz2.bag", "clouds_lz4.bag"})
    for (const char* topic : {"float32_padded", "float64_big", "organized", "hesai"}) {
        SCOPED_TRACE(std::string(bag) + " " + topic);
        const Expected e = read_expected(dir_ / (std::string(topic) + ".txt"));
        RecordingOptions o;
        o.topic = std::string("/") + topic;
        auto source = open_recording(dir_ / bag, o);
        RecordedScan scan;
        std::size_t k = 0;
        for (; source->next(scan); ++k) {
            ASSERT_LT(k, e.messages.size());
            const auto& want = e.messages[k];
            ASSERT_EQ(scan.cloud.points.size(), want.size());
            EXPECT_EQ(scan.frame_id, "lidar");
            const bool times = !std::isnan(want.front()[3]);
            ASSERT_EQ(scan.times.size(), times ? want.size() : 0u);
            const bool intensities = !std::isnan(want.front()[4]);
            ASSERT_EQ(scan.cloud.intensities.size(), intensities ? want.size() : 0u);
            for (std::size_t i = 0; i < want.size(); ++i) {
                for (int a = 0; a < 3; ++a) EXPECT_NEAR(scan.cloud.points[i][a], want[i][a], 1e-6 * (1 + std::abs(want[i][a])));
                if (times) {
                    EXPECT_NEAR(scan.times[i], want[i][3], 2e-6);
                }
                if (intensities) {
                    EXPECT_EQ(scan.cloud.intensities[i], want[i][4]);
                }
            }
        }
        EXPECT_EQ(k, e.messages.size());
    }
}

TEST_F(Ros1Bag, ACloudWhoseSizesDisagreeIsRefusedNamingItsMessage) {
    RecordingOptions o;
    o.topic = "/bad_row_step";
    auto source = open_recording(dir_ / "clouds.bag", o);
    RecordedScan scan;
    ASSERT_TRUE(source->next(scan));
    try {
        source->next(scan);
        FAIL() << "the bad cloud was accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("message 1 on /bad_row_step"), std::string::npos) << e.what();
    }
    // Several PointCloud2 topics: the user must choose.
    EXPECT_THROW(open_recording(dir_ / "clouds.bag"), InvalidArgument);
    o.topic = "/nothing";
    EXPECT_THROW(open_recording(dir_ / "clouds.bag", o), InvalidArgument);
    // Not a bag.
    std::ofstream(dir_ / "text.bag") << "#ROSBAG V2.0\nnot really";
    EXPECT_THROW(open_recording(dir_ / "text.bag"), FormatError);
}
#endif

}  // namespace
}  // namespace lidarsurf
