#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <tuple>

#include <lzf.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/io/point_writer.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

template <typename T>
void append(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    s.append(b, sizeof(T));
}

std::vector<Eigen::Vector3d> sample_points() {
    return {{1.5, -2.25, 0.125}, {10.0, 20.0, -1.75}, {-0.5, 0.0, 3.0}};
}

void expect_points(const PointCloud& c, const std::vector<Eigen::Vector3d>& expected, double tol = 0) {
    ASSERT_EQ(c.points.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_LE((c.points[i] - expected[i]).norm(), tol) << i;
}

TEST(KittiBin, RoundTripAndExtraFields) {
    const test::TempDir dir("bin");
    PointCloud cloud{sample_points()};
    write_points(cloud, dir / "a.bin");
    expect_points(read_points(dir / "a.bin"), sample_points());  // values are exact in float32
    std::string five;  // nuScenes layout: x, y, z, intensity, ring
    for (const auto& p : sample_points()) {
        for (int a = 0; a < 3; ++a) append<float>(five, static_cast<float>(p[a]));
        append<float>(five, 7.0f);
        append<float>(five, 3.0f);
    }
    expect_points(parse_kitti_bin(five, 5, "five"), sample_points());
    EXPECT_THROW(parse_kitti_bin(five, 4, "five"), FormatError);  // 60 bytes: not whole 16-byte records
}

TEST(PointWriter, EveryExtensionReadsBack) {
    const test::TempDir dir("point_writer");
    PointCloud cloud;
    cloud.points = {{1.0 / 3.0, -2.25, 1e5 + 0.125}, {10.0, 20.0, -1.75}, {-0.5, 0.0, 3.0}};
    for (const char* name : {"a.xyz", "a.txt", "a.CSV", "a.ply"}) {  // exact: text at 17 digits, PLY in double beyond 1e4
        write_points(cloud, dir / name);
        expect_points(read_points(dir / name), cloud.points);
    }
    std::vector<Eigen::Vector3d> as_float;  // float32 records
    for (const auto& p : cloud.points) as_float.push_back(p.cast<float>().cast<double>());
    for (const char* name : {"a.bin", "a.pcd"}) {
        write_points(cloud, dir / name);
        expect_points(read_points(dir / name), as_float);
    }
    EXPECT_THROW(write_points(cloud, dir / "a.las"), InvalidArgument);
    EXPECT_FALSE(std::filesystem::exists(dir / "a.las"));
    std::filesystem::remove_all(dir);
}

TEST(KittiBin, MalformedFiles) {
    EXPECT_THROW(parse_kitti_bin("", 4, "empty"), FormatError);
    EXPECT_THROW(parse_kitti_bin(std::string(17, '\0'), 4, "truncated"), FormatError);
    EXPECT_THROW(parse_kitti_bin(std::string(16, '\0'), 2, "fields"), InvalidArgument);
    EXPECT_THROW(read_points("/nonexistent/dir/scan.bin"), IoError);
    EXPECT_THROW(read_points("scan.unknownext"), InvalidArgument);
}

TEST(Ply, AsciiWithExtraPropertiesAndDoubles) {
    const std::string ply =
        "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty double x\nproperty double y\n"
        "property float intensity\nproperty double z\nproperty list uchar int extra\nend_header\n"
        "1.5 -2.25 9 0.125 2 1 2\n10 20 9 -1.75 0\n-0.5 0 9 3 1 5\n";
    expect_points(parse_ply_points(ply, "ascii"), sample_points());
}

TEST(Ply, BinaryBigAndLittleEndian) {
    for (bool big : {false, true}) {
        std::string ply = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                          " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar r\nend_header\n";
        for (const auto& p : sample_points()) {
            for (int a = 0; a < 3; ++a) {
                float f = static_cast<float>(p[a]);
                char b[4];
                std::memcpy(b, &f, 4);
                if (big) std::reverse(b, b + 4);
                ply.append(b, 4);
            }
            ply.push_back('\x7f');
        }
        expect_points(parse_ply_points(ply, "bin"), sample_points());
        EXPECT_THROW(parse_ply_points(ply.substr(0, ply.size() - 3), "truncated"), FormatError);
    }
}

TEST(Ply, MalformedHeaders) {
    EXPECT_THROW(parse_ply_points("", "e"), FormatError);
    EXPECT_THROW(parse_ply_points("plx\nformat ascii 1.0\nend_header\n", "magic"), FormatError);
    EXPECT_THROW(parse_ply_points("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "noend"), FormatError);
    EXPECT_THROW(parse_ply_points("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n", "noz"), FormatError);
    // A header claiming billions of vertices must fail before allocating.
    EXPECT_THROW(parse_ply_points("ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                                  "property float y\nproperty float z\nend_header\n0123456789AB", "huge"), FormatError);
    EXPECT_THROW(parse_ply_points("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                                  "property float z\nend_header\n1 2 3\n", "short"), FormatError);
    EXPECT_THROW(parse_ply_points("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                  "property float z\nend_header\n1 two 3\n", "nan"), FormatError);
}

TEST(Ply, AsciiRecordsWithTooFewOrTooManyValuesNameTheirLine) {
    // One record a line: read on, a short or long row would shift every later point.
    const std::string header = "ply\nformat ascii 1.0\ncomment c\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nend_header\n";  // 8 lines
    expect_points(parse_ply_points(header + "1.5 -2.25 0.125\n\n10 20 -1.75\n-0.5 0 3\n", "blank line"), sample_points());
    for (const auto& [body, line, words] : {std::tuple<std::string, std::string, std::string>{"1.5 -2.25 0.125\n10 20\n-0.5 0 3 4 5 6\n", "line 10", "fewer"},
                                            {"1.5 -2.25 0.125 9\n10 20 -1.75\n-0.5 0 3\n", "line 9", "more"},
                                            {"1.5 -2.25 0.125\n10 20 -1.75\n-0.5 0 3 7\n", "line 11", "more"}}) {
        try {
            parse_ply_points(header + body, "rows");
            ADD_FAILURE() << "accepted: " << body;
        } catch (const FormatError& e) {
            EXPECT_NE(std::string(e.what()).find(line), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        }
    }
}

std::string pcd_header(const std::string& data, std::size_t n) {
    return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\n"
           "COUNT 1 1 1 1\nWIDTH " + std::to_string(n) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) +
           "\nDATA " + data + "\n";
}

TEST(Pcd, AsciiBinaryAndCompressed) {
    const auto pts = sample_points();
    std::string ascii = pcd_header("ascii", 3);
    // The intensity field: 5, 6, 7 for the three points, read into the cloud's intensities.
    const auto intensity_of = [](std::size_t i) { return 5.0f + static_cast<float>(i); };
    const auto expect_intensities = [&](const PointCloud& c) {
        ASSERT_EQ(c.intensities.size(), pts.size());
        for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_EQ(c.intensities[i], intensity_of(i)) << i;
    };
    for (std::size_t i = 0; i < pts.size(); ++i)
        ascii += std::to_string(pts[i].x()) + " " + std::to_string(pts[i].y()) + " " + std::to_string(pts[i].z()) + " " + std::to_string(5 + i) + "\n";
    expect_points(parse_pcd_points(ascii, "ascii"), pts, 1e-6);
    expect_intensities(parse_pcd_points(ascii, "ascii"));

    std::string binary = pcd_header("binary", 3), aos, soa;
    for (std::size_t i = 0; i < pts.size(); ++i) {
        for (int a = 0; a < 3; ++a) append<float>(aos, static_cast<float>(pts[i][a]));
        append<float>(aos, intensity_of(i));
    }
    expect_points(parse_pcd_points(binary + aos, "binary"), pts);
    expect_intensities(parse_pcd_points(binary + aos, "binary"));
    EXPECT_THROW(parse_pcd_points(binary + aos.substr(0, 40), "truncated"), FormatError);

    for (int field = 0; field < 4; ++field)  // binary_compressed stores the fields one after another
        for (std::size_t i = 0; i < pts.size(); ++i) append<float>(soa, field < 3 ? static_cast<float>(pts[i][field]) : intensity_of(i));
    std::vector<char> packed(soa.size() * 2 + 16);
    const unsigned csize = lzf_compress(soa.data(), static_cast<unsigned>(soa.size()), packed.data(), static_cast<unsigned>(packed.size()));
    ASSERT_GT(csize, 0u);
    std::string compressed = pcd_header("binary_compressed", 3);
    append<std::uint32_t>(compressed, csize);
    append<std::uint32_t>(compressed, static_cast<std::uint32_t>(soa.size()));
    compressed.append(packed.data(), csize);
    expect_points(parse_pcd_points(compressed, "compressed"), pts);
    expect_intensities(parse_pcd_points(compressed, "compressed"));
    EXPECT_TRUE(parse_pcd_points("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n", "xyz").intensities.empty());
    // An intensity past float's range is no intensity (NaN), not an undefined conversion.
    const PointCloud far = parse_pcd_points("FIELDS x y z intensity\nSIZE 4 4 4 8\nTYPE F F F F\nPOINTS 1\nDATA ascii\n1 2 3 1e300\n", "far");
    ASSERT_EQ(far.intensities.size(), 1u);
    EXPECT_TRUE(std::isnan(far.intensities[0]));
    std::string corrupt = compressed;
    corrupt[corrupt.size() - csize] = '\xff';  // first LZF control byte: a back reference before the start
    EXPECT_THROW(parse_pcd_points(corrupt, "corrupt"), FormatError);
    EXPECT_THROW(parse_pcd_points(compressed.substr(0, compressed.size() - 2), "truncated"), FormatError);
}

TEST(Pcd, MalformedHeaders) {
    EXPECT_THROW(parse_pcd_points("", "e"), FormatError);
    EXPECT_THROW(parse_pcd_points("hello world\n", "magic"), FormatError);
    EXPECT_THROW(parse_pcd_points(pcd_header("binary", 3000000000ULL), "huge"), FormatError);
    EXPECT_THROW(parse_pcd_points(pcd_header("ascii", 2) + "1 2 3 4\n", "short"), FormatError);
    EXPECT_THROW(parse_pcd_points(pcd_header("zip", 1), "enc"), FormatError);
    EXPECT_THROW(parse_pcd_points("FIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n", "sizes"), FormatError);
}

TEST(Pcd, CountsWhoseProductWrapsAroundAreRefused) {
    // POINTS x record size = 2^64 + 2^19: a 64-bit product wraps to 2^19, which a valid LZF block
    // of that size then matches; the reader must refuse the header, not read 2^45 points from it.
    const std::uint64_t n = (std::uint64_t{1} << 45) + 1;
    const std::string header = "VERSION 0.7\nFIELDS x y z pad\nSIZE 8 8 8 8\nTYPE F F F F\nCOUNT 1 1 1 65533\nWIDTH " +
                               std::to_string(n) + "\nHEIGHT 1\nPOINTS " + std::to_string(n) + "\nDATA binary_compressed\n";
    std::string raw(std::size_t{1} << 19, '\0');
    std::uint64_t state = 12345;  // incompressible bytes: the block passes the expansion-ratio check
    for (char& c : raw) c = static_cast<char>((state = state * 6364136223846793005ULL + 1442695040888963407ULL) >> 56);
    std::string packed(raw.size() + raw.size() / 8, '\0');
    const unsigned csize = lzf_compress(raw.data(), static_cast<unsigned>(raw.size()), packed.data(), static_cast<unsigned>(packed.size()));
    ASSERT_GT(csize, 0u);
    packed.resize(csize);
    std::string data = header;
    append(data, static_cast<std::uint32_t>(packed.size()));
    append(data, static_cast<std::uint32_t>(raw.size()));
    data += packed;
    EXPECT_THROW(parse_pcd_points(data, "wrap"), FormatError);
    // WIDTH x HEIGHT past 2^64.
    EXPECT_THROW(parse_pcd_points("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 8000000000000000\nHEIGHT 8000000000000000\n"
                                  "DATA binary\n",
                                  "area"),
                 FormatError);
}

TEST(Text, DecimalCommaByteOrderMarkAndQuotedHeaders) {
    // A spreadsheet export in a decimal-comma locale: ';' between values, ',' in them.
    expect_points(parse_text_points("x;y;z\n1,5;-2,25;0,125\n10;20;-1,75\n-0,5;0;3\n", "decimal comma"), sample_points());
    expect_points(parse_text_points("1,5;-2,25;0,125\n10;20;-1,75\n-0,5;0;3\n", "no header"), sample_points());
    expect_points(parse_text_points("\xEF\xBB\xBF" "x,y,z\n1.5,-2.25,0.125\n10,20,-1.75\n-0.5,0,3\n", "bom"), sample_points());
    expect_points(parse_text_points("\xEF\xBB\xBF" "\"X\",\"Y\",\"Z\"\n1.5,-2.25,0.125\n10,20,-1.75\n-0.5,0,3\n", "quoted"), sample_points());
    expect_points(parse_text_points("\xEF\xBB\xBF" "1.5 -2.25 0.125\n10 20 -1.75\n-0.5 0 3\n", "bom, no header"), sample_points());
}

TEST(Text, XyzCsvAndHeaders) {
    expect_points(parse_text_points("# comment\n1.5 -2.25 0.125\n10 20 -1.75 7\n\n-0.5 0 3\n", "xyz"), sample_points());
    expect_points(parse_text_points("x,y,z,intensity\n1.5,-2.25,0.125,1\n10,20,-1.75,1\n-0.5,0,3,1\n", "csv"), sample_points());
    expect_points(parse_text_points("intensity;z;y;x\n1;0.125;-2.25;1.5\n1;-1.75;20;10\n1;3;0;-0.5\n", "reordered"), sample_points());
    EXPECT_THROW(parse_text_points("", "empty"), FormatError);
    EXPECT_THROW(parse_text_points("1 2 3\n4 5\n", "short"), FormatError);
    EXPECT_THROW(parse_text_points("1 2 3\n4 5 six\n", "bad"), FormatError);
    EXPECT_THROW(parse_text_points("a,b,c\n1,2,3\n", "nocols"), FormatError);
}

TEST(PointCloud, DropNonFinite) {
    const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
    PointCloud c{{{0, 0, 0}, {nan, 0, 0}, {1, 1, 1}, {0, -inf, 0}}};
    EXPECT_EQ(drop_non_finite(c), 2u);
    EXPECT_EQ(c.points.size(), 2u);
}

}  // namespace
