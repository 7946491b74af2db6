// The live stream's format (viz/live_stream.hpp) against its documented layout, computed here by
// hand, and a round trip of the town drive's real blocks far from the world origin (float32
// positions relative to the stream's origin keep 0.1 mm); malformed messages are refused.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "../map/town_drive.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/viz/live_stream.hpp"
#include "lidarsurf/pipeline.hpp"

using namespace lidarsurf;
namespace ls = lidarsurf::live_stream;

namespace {

std::vector<std::uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

template <typename T>
T read_at(const std::string& s, std::size_t at) {
    T v;
    std::memcpy(&v, s.data() + at, sizeof(T));
    return v;
}

MeshBlock one_triangle() {
    MeshBlock b;
    b.key = VoxelKey(-3, 7, -1);
    b.mesh.vertices = {{1000.5, 2000.25, 10.0}, {1001.5, 2000.25, 10.0}, {1000.5, 2001.25, 10.5}};
    b.mesh.triangles = {{0, 1, 2}};
    b.mesh.levels = {1, 2, 3};
    b.mesh.confidence = {0.5f, 0.25f, 1.0f};
    return b;
}

}  // namespace

TEST(LiveStream, TheLayoutIsTheDocumentedOne) {
    const Eigen::Vector3d origin(1000, 2000, 10);
    const MeshBlock block = one_triangle();
    const std::string body = ls::encode_block(block, origin);
    // key 12 + counts 8 + positions 3*12 + confidence 3*4 + levels 3 padded to 4 + triangle 12
    ASSERT_EQ(body.size(), 12u + 8 + 36 + 12 + 4 + 12);
    EXPECT_EQ(read_at<std::int32_t>(body, 0), -3);
    EXPECT_EQ(read_at<std::int32_t>(body, 8), -1);
    EXPECT_EQ(read_at<std::uint32_t>(body, 12), 3u);
    EXPECT_EQ(read_at<std::uint32_t>(body, 16), 1u);
    EXPECT_EQ(read_at<float>(body, 20), 0.5f);    // x of vertex 0, relative to the origin
    EXPECT_EQ(read_at<float>(body, 20 + 32), 0.5f);  // z of vertex 2
    EXPECT_EQ(read_at<float>(body, 56 + 4), 0.25f);  // confidence of vertex 1
    EXPECT_EQ(static_cast<int>(static_cast<unsigned char>(body[68 + 2])), 3);  // level of vertex 2
    EXPECT_EQ(body[68 + 3], '\0');                    // padding
    EXPECT_EQ(read_at<std::uint32_t>(body, 72 + 8), 2u);

    ls::Header h;
    h.flags = ls::kReset | ls::kFinal;
    h.scans = 42;
    h.origin = origin;
    h.pose.translation() = Eigen::Vector3d(1003, 2004, 12);
    const std::vector<Eigen::Vector3d> trajectory = {{1001, 2001, 11}, {1003, 2004, 12}};
    const std::vector<VoxelKey> removed = {VoxelKey(5, -6, 7)};
    const std::string* blocks[] = {&body};
    const std::string m = ls::encode_message(h, trajectory, removed, blocks);
    ASSERT_EQ(m.size(), 112u + 2 * 12 + 12 + body.size());
    EXPECT_EQ(m.substr(0, 4), "LSLV");
    EXPECT_EQ(read_at<std::uint32_t>(m, 4), 1u);
    EXPECT_EQ(read_at<std::uint32_t>(m, 8), 3u);
    EXPECT_EQ(read_at<std::uint32_t>(m, 12), 42u);
    EXPECT_EQ(read_at<double>(m, 24), 2000.0);
    EXPECT_EQ(read_at<float>(m, 40), 1.0f);       // R(0, 0)
    EXPECT_EQ(read_at<float>(m, 40 + 28), 4.0f);  // t_y relative to the origin
    EXPECT_EQ(read_at<std::uint32_t>(m, 88), 2u);
    EXPECT_EQ(read_at<std::uint32_t>(m, 92), 1u);
    EXPECT_EQ(read_at<std::uint32_t>(m, 96), 1u);
    EXPECT_EQ(read_at<float>(m, 112 + 12), 3.0f);  // x of the second trajectory point
    EXPECT_EQ(read_at<std::int32_t>(m, 136 + 4), -6);
    EXPECT_EQ(m.substr(148), body);
}

TEST(LiveStream, TheTownDrivesBlocksComeBackWithinATenthOfAMillimetre) {
    // The drive moved 300 km away: the positions' float32 are relative to the stream's origin.
    const Eigen::Vector3d far(3e5, -2e5, 40);
    const std::vector<test::Scan>& drive = test::town_drive();
    Reconstructor rec(ReconstructionConfig{}, drive[0].from + far);
    std::vector<Eigen::Vector3d> points;
    for (const Eigen::Vector3d& p : drive[0].points) points.push_back(p + far);
    rec.integrate(points, drive[0].from + far);
    const MeshDelta delta = rec.update_mesh(0);
    ASSERT_GT(delta.changed.size(), 100u);

    ls::Header h;
    h.scans = 1;
    h.origin = drive[0].from + far;
    h.pose = drive[0].pose;
    h.pose.translation() += far;
    std::vector<std::string> bodies;
    for (const MeshBlock& b : delta.changed) bodies.push_back(ls::encode_block(b, h.origin));
    std::vector<const std::string*> blocks;
    for (const std::string& b : bodies) blocks.push_back(&b);
    const std::vector<VoxelKey> removed = {VoxelKey(-(1 << 20) + 1, (1 << 20) - 1, 0)};
    const std::vector<Eigen::Vector3d> trajectory = {h.pose.translation()};
    const ls::Message m = ls::decode(bytes_of(ls::encode_message(h, trajectory, removed, blocks)));

    EXPECT_EQ(m.header.scans, 1u);
    EXPECT_TRUE(m.header.origin == h.origin);
    EXPECT_LT((m.header.pose.matrix() - h.pose.matrix()).cwiseAbs().maxCoeff(), 1e-4);
    ASSERT_EQ(m.trajectory.size(), 1u);
    EXPECT_LT((m.trajectory[0] - h.pose.translation()).norm(), 1e-4);
    ASSERT_EQ(m.removed.size(), 1u);
    EXPECT_TRUE(m.removed[0] == removed[0]);
    ASSERT_EQ(m.changed.size(), delta.changed.size());
    for (std::size_t i = 0; i < m.changed.size(); ++i) {
        const Mesh &got = m.changed[i].mesh, &sent = delta.changed[i].mesh;
        EXPECT_TRUE(m.changed[i].key == delta.changed[i].key);
        ASSERT_EQ(got.vertices.size(), sent.vertices.size());
        EXPECT_TRUE(got.triangles == sent.triangles);
        EXPECT_TRUE(got.levels == sent.levels);
        EXPECT_TRUE(got.confidence == sent.confidence);
        for (std::size_t v = 0; v < got.vertices.size(); ++v) ASSERT_LT((got.vertices[v] - sent.vertices[v]).norm(), 1e-4);
    }
}

TEST(LiveStream, MalformedMessagesAreRefused) {
    const MeshBlock block = one_triangle();
    const std::string body = ls::encode_block(block, Eigen::Vector3d(1000, 2000, 10));
    const std::string* blocks[] = {&body};
    const std::vector<Eigen::Vector3d> trajectory = {{1, 2, 3}};
    const std::vector<VoxelKey> removed = {VoxelKey(1, 2, 3)};
    ls::Header h;
    h.origin = Eigen::Vector3d(1000, 2000, 10);
    const std::string good = ls::encode_message(h, trajectory, removed, blocks);
    EXPECT_NO_THROW(ls::decode(bytes_of(good)));
    for (std::size_t n = 0; n < good.size(); ++n)  // every truncation
        EXPECT_THROW(ls::decode(bytes_of(good.substr(0, n))), FormatError) << n << " bytes";
    EXPECT_THROW(ls::decode(bytes_of(good + '\0')), FormatError);
    std::string bad = good;
    bad[0] = 'X';
    EXPECT_THROW(ls::decode(bytes_of(bad)), FormatError);
    bad = good;
    bad[4] = 2;  // version 2
    EXPECT_THROW(ls::decode(bytes_of(bad)), FormatError);
    bad = good;
    const std::uint32_t huge = 0xFFFFFFFFu;
    std::memcpy(bad.data() + 88, &huge, 4);  // a count larger than the message
    EXPECT_THROW(ls::decode(bytes_of(bad)), FormatError);
    bad = good;
    const std::uint32_t out_of_block = 3;  // the block has vertices 0..2
    std::memcpy(bad.data() + bad.size() - 4, &out_of_block, 4);
    EXPECT_THROW(ls::decode(bytes_of(bad)), FormatError);
}
