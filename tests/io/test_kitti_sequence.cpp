#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <Eigen/Geometry>
#include <png.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/viz/png_writer.hpp"
#include "test_util.hpp"

using namespace lidarsurf;
namespace fs = std::filesystem;

namespace {

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

TEST(KittiSequence, PosesRoundTripExactly) {
    const test::TempDir d("seq");
    std::vector<Eigen::Isometry3d> poses;
    for (int i = 0; i < 5; ++i) {
        Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
        p.rotate(Eigen::AngleAxisd(0.1 * i + 0.3, Eigen::Vector3d(1, 2, 3).normalized()));
        p.translation() = Eigen::Vector3d(1e5 + i / 3.0, -2.0 * i, 0.1);
        poses.push_back(p);
    }
    write_poses(poses, d / "poses.txt");
    const auto back = read_poses(d / "poses.txt");
    ASSERT_EQ(back.size(), poses.size());
    for (std::size_t i = 0; i < poses.size(); ++i) EXPECT_EQ(back[i].matrix(), poses[i].matrix());  // %.17g is exact
    fs::remove_all(d);
}

TEST(KittiSequence, MalformedPosesNameTheLine) {
    const test::TempDir d("seq");
    write(d / "short.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
    try {
        read_poses(d / "short.txt");
        FAIL() << "no throw";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
    }
    write(d / "nan.txt", "1 0 0 nan 0 1 0 0 0 0 1 0\n");
    EXPECT_THROW(read_poses(d / "nan.txt"), FormatError);
    write(d / "scaled.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n");
    EXPECT_THROW(read_poses(d / "scaled.txt"), FormatError);
    write(d / "long.txt", "1 0 0 0 0 1 0 0 0 0 1 0 7\n");
    EXPECT_THROW(read_poses(d / "long.txt"), FormatError);
    write(d / "blank.txt", "\n1 0 0 0 0 1 0 0 0 0 1 0\n\n");
    EXPECT_EQ(read_poses(d / "blank.txt").size(), 1u);
    EXPECT_THROW(read_poses(d / "missing.txt"), IoError);
    fs::remove_all(d);
}

// KITTI's calib.txt: the Tr: line among the projection matrices; and camera poses converted to
// the lidar's. Oracle: a lidar trajectory L_i and a velodyne-to-camera transform T give camera
// poses P_i = T L_i T^-1 (what KITTI publishes); converting them back must give L_i, and a point
// of scan i must land at the same world point (up to the fixed frame change) either way.
TEST(KittiSequence, CalibrationTrConvertsCameraPosesToTheLidars) {
    const test::TempDir d("seq");
    // KITTI's real odometry Tr (sequence 00), whose rotation is orthonormal to ~1e-7.
    const std::string tr_line =
        "Tr: 4.276802385584e-04 -9.999672484946e-01 -8.084491683471e-03 -1.198459927713e-02 "
        "-7.210626507497e-03 8.081198471645e-03 -9.999413164504e-01 -5.403984729748e-02 "
        "9.999738645903e-01 4.859485810390e-04 -7.206933692422e-03 -2.921968648686e-01\n";
    write(d / "calib.txt", "P0: 7.18856e+02 0 6.071928e+02 0 0 7.18856e+02 1.852157e+02 0 0 0 1 0\n" + tr_line);
    const Eigen::Isometry3d tr = read_calib_tr(d / "calib.txt");
    EXPECT_NEAR(tr.translation().z(), -0.2921968648686, 1e-15);
    EXPECT_NEAR(tr.linear()(0, 1), -0.9999672484946, 1e-15);
    Eigen::Isometry3d tr_inv;
    tr_inv.matrix() = tr.matrix().inverse();
    std::vector<Eigen::Isometry3d> lidar, camera;
    for (int i = 0; i < 4; ++i) {
        Eigen::Isometry3d l = Eigen::Isometry3d::Identity();
        l.rotate(Eigen::AngleAxisd(0.2 * i, Eigen::Vector3d::UnitZ()));
        l.translation() = Eigen::Vector3d(3.0 * i, 0.5 * i, 0.01 * i);
        lidar.push_back(l);
        camera.push_back(tr * l * tr_inv);
    }
    const std::vector<Eigen::Isometry3d> back = lidar_poses(camera, tr);
    ASSERT_EQ(back.size(), lidar.size());
    const Eigen::Vector3d p(12.0, -3.0, -1.7);  // a point of each scan, velodyne frame
    for (std::size_t i = 0; i < lidar.size(); ++i) {
        EXPECT_TRUE(back[i].matrix().isApprox(lidar[i].matrix(), 1e-12)) << i;
        // KITTI's way: world (camera 0) point = P_i Tr p; ours: Tr^-1 P_i Tr p, the same point in frame 0's velodyne frame.
        EXPECT_LT((tr * (back[i] * p) - camera[i] * (tr * p)).norm(), 1e-9) << i;
    }
    write(d / "no_tr.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n");
    EXPECT_THROW(read_calib_tr(d / "no_tr.txt"), FormatError);
    write(d / "short_tr.txt", "Tr: 1 0 0 0 0 1 0 0 0 0 1\n");
    EXPECT_THROW(read_calib_tr(d / "short_tr.txt"), FormatError);
    EXPECT_THROW(read_calib_tr(d / "missing.txt"), IoError);
    fs::remove_all(d);
}

TEST(KittiSequence, MirroredPoseOrCalibrationIsRefused) {
    // det = -1: orthonormal, but a reflection, which no sensor motion or mounting gives.
    const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
    const std::string mirrored = "-1 0 0 0 0 1 0 0 0 0 1 0\n";
    EXPECT_EQ(parse_poses(identity, "p").size(), 1u);
    try {
        parse_poses(identity + mirrored, "p");
        ADD_FAILURE() << "a mirrored pose was accepted";
    } catch (const FormatError& e) {
        EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("reflection"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parse_calib_tr("P0: 1 2 3\nTr: " + mirrored, "calib"), FormatError);
}

TEST(KittiSequence, CountsConsecutiveFrames) {
    const test::TempDir d("seq");
    const KittiSequence seq{d};
    EXPECT_THROW(seq.frame_count(), IoError);
    fs::create_directories(d / "velodyne");
    EXPECT_EQ(seq.frame_count(), 0u);
    for (int i : {0, 1, 2}) write(seq.scan(i), "");
    write(d / "velodyne" / "notes.txt", "");  // not a scan
    EXPECT_EQ(seq.frame_count(), 3u);
    EXPECT_EQ(seq.scan(3).filename(), "000003.bin");
    write(seq.scan(4), "");  // a gap: 000003.bin is missing, so 000004.bin would be left out silently
    try {
        seq.frame_count();
        ADD_FAILURE() << "a gap in the numbering was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("000003.bin is missing"), std::string::npos) << e.what();
    }
    fs::remove_all(d);
}

TEST(PngWriter, PixelsReadBackByLibpng) {
    const test::TempDir d("seq");
    Image img;
    img.width = 7;
    img.height = 3;
    for (int i = 0; i < 7 * 3 * 3; ++i) img.rgb.push_back(static_cast<std::uint8_t>(i * 37 % 256));
    write_png(img, d / "a.png");
    png_image read{};
    read.version = PNG_IMAGE_VERSION;
    ASSERT_TRUE(png_image_begin_read_from_file(&read, (d / "a.png").c_str()));
    read.format = PNG_FORMAT_RGB;
    std::vector<std::uint8_t> back(PNG_IMAGE_SIZE(read));
    ASSERT_TRUE(png_image_finish_read(&read, nullptr, back.data(), 0, nullptr));
    EXPECT_EQ(read.width, 7u);
    EXPECT_EQ(read.height, 3u);
    EXPECT_EQ(back, img.rgb);
    img.rgb.pop_back();
    EXPECT_THROW(write_png(img, d / "b.png"), InvalidArgument);
    EXPECT_FALSE(fs::exists(d / "b.png"));
    fs::remove_all(d);
}

}  // namespace
