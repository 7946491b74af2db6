#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <Eigen/Geometry>
#include <png.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/png_writer.hpp"

using namespace lidarsurf;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir() {
    const fs::path d = fs::temp_directory_path() / ("lidarsurf_seq_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

TEST(KittiSequence, PosesRoundTripExactly) {
    const fs::path d = temp_dir();
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
    const fs::path d = temp_dir();
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

TEST(KittiSequence, CountsConsecutiveFrames) {
    const fs::path d = temp_dir();
    const KittiSequence seq{d};
    EXPECT_THROW(seq.frame_count(), IoError);
    fs::create_directories(d / "velodyne");
    EXPECT_EQ(seq.frame_count(), 0u);
    for (int i : {0, 1, 2, 4}) write(seq.scan(i), "");
    EXPECT_EQ(seq.frame_count(), 3u);  // stops at the first gap
    EXPECT_EQ(seq.scan(3).filename(), "000003.bin");
    fs::remove_all(d);
}

TEST(PngWriter, PixelsReadBackByLibpng) {
    const fs::path d = temp_dir();
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
