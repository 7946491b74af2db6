// The live stream's format (viz/live_stream.hpp) against its documented layout, computed here by
// hand and read with meshoptimizer's own decoders, and a round trip of the town drive's real
// blocks far from the world origin (positions relative to the stream's origin, quantized within
// their block, keep 0.25 mm); malformed messages are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include <meshoptimizer.h>

#include "../map/town_drive.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/viz/live_stream.hpp"
#include "lidarsurf/pipeline.hpp"
#include "live_client.hpp"

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
    b.mesh.intensity = {10.0f, NAN, 40.0f};
    return b;
}

}  // namespace

TEST(LiveStream, TheLayoutIsTheDocumentedOne) {
    const Eigen::Vector3d origin(1000, 2000, 10);
    const MeshBlock block = one_triangle();
    const std::string body = ls::encode_block(block, origin);
    // key 12, counts 8, lowest corner 12, steps 8, intensity base and step 8, code lengths 8; the
    // codes, each padded to 4
    ASSERT_GE(body.size(), 56u);
    EXPECT_EQ(read_at<std::int32_t>(body, 0), -3);
    EXPECT_EQ(read_at<std::int32_t>(body, 8), -1);
    EXPECT_EQ(read_at<std::uint32_t>(body, 12), 3u);
    EXPECT_EQ(read_at<std::uint32_t>(body, 16), 1u);
    EXPECT_EQ(read_at<float>(body, 20), 0.5f);   // the lowest corner, relative to the origin
    EXPECT_EQ(read_at<float>(body, 24), 0.25f);
    EXPECT_EQ(read_at<float>(body, 28), 0.0f);
    const float step = read_at<float>(body, 32), cstep = read_at<float>(body, 36);
    EXPECT_FLOAT_EQ(step, 0.5e-3f);        // the finest step (the block's 1 m extent needs no more than 2,000)
    EXPECT_FLOAT_EQ(cstep, 1.0f / 65535);  // its largest confidence (1) in 16 bits
    EXPECT_EQ(read_at<float>(body, 40), 10.0f);               // the block's least intensity
    EXPECT_FLOAT_EQ(read_at<float>(body, 44), 30.0f / 65534);  // its range in 65,534 steps
    const auto vertex_bytes = read_at<std::uint32_t>(body, 48), index_bytes = read_at<std::uint32_t>(body, 52);
    const auto pad = [](std::size_t n) { return (n + 3) / 4 * 4; };
    ASSERT_EQ(body.size(), 56 + pad(vertex_bytes) + pad(index_bytes));
    // meshoptimizer's decoders read the codes back: 12-byte records and the triangle.
    std::uint8_t records[3 * 12];
    ASSERT_EQ(meshopt_decodeVertexBuffer(records, 3, 12, reinterpret_cast<const unsigned char*>(body.data()) + 56, vertex_bytes), 0);
    std::uint32_t tri[3];
    ASSERT_EQ(meshopt_decodeIndexBuffer(tri, 3, 4, reinterpret_cast<const unsigned char*>(body.data()) + 56 + pad(vertex_bytes), index_bytes), 0);
    const auto record = [&](int i, int field) { return read_at<std::uint16_t>(std::string(reinterpret_cast<char*>(records), sizeof records), 12 * i + 2 * field); };
    // The one triangle keeps its orientation: its corners in cyclic order are vertices 0, 1, 2.
    int first = 0;
    while (record(tri[first], 0) != 0 || record(tri[first], 1) != 0) ++first;  // vertex 0: the lowest corner itself
    const int v1 = static_cast<int>(tri[(first + 1) % 3]), v2 = static_cast<int>(tri[(first + 2) % 3]);
    EXPECT_EQ(record(v1, 0), 2000);  // x = 1.5 - 0.5 = 1 m
    EXPECT_EQ(record(v1, 1), 0);
    EXPECT_EQ(record(v2, 1), 2000);  // y of vertex 2
    EXPECT_EQ(record(v2, 2), 1000);  // z = 0.5 m
    EXPECT_EQ(record(v1, 3), 16384);  // confidence 0.25: 16383.75 steps
    EXPECT_EQ(records[12 * v2 + 8], 3);  // level of vertex 2
    EXPECT_EQ(records[12 * v2 + 9], 0);  // a zero byte
    EXPECT_EQ(record(tri[first], 5), 0);      // intensity 10: the base
    EXPECT_EQ(record(v1, 5), 65535);          // none (NaN)
    EXPECT_EQ(record(v2, 5), 65534);          // 40: the top of the range

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
    EXPECT_EQ(read_at<std::uint32_t>(m, 4), 3u);
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

    // Read back: each vertex's intensity within half a step, none where it had none; a block
    // without intensity comes back without.
    const Mesh got = ls::decode(bytes_of(m)).changed.at(0).mesh;
    ASSERT_EQ(got.intensity.size(), 3u);
    for (std::size_t i = 0; i < 3; ++i)
        for (std::size_t j = 0; j < 3; ++j) {
            if ((got.vertices[i] - block.mesh.vertices[j]).norm() > 1e-3) continue;
            if (std::isnan(block.mesh.intensity[j])) EXPECT_TRUE(std::isnan(got.intensity[i])) << i;
            else EXPECT_NEAR(got.intensity[i], block.mesh.intensity[j], 0.5 * 30.0 / 65534 + 1e-5) << i;
        }
    MeshBlock plain = one_triangle();
    plain.mesh.intensity.clear();
    const std::string plain_body = ls::encode_block(plain, origin);
    EXPECT_EQ(read_at<float>(plain_body, 44), -1.0f);
    const std::string* plain_blocks[] = {&plain_body};
    EXPECT_TRUE(ls::decode(bytes_of(ls::encode_message(h, {}, {}, plain_blocks))).changed.at(0).mesh.intensity.empty());
}

TEST(LiveStream, TheTownDrivesBlocksComeBackWithinAQuarterOfAMillimetre) {
    // Within half a position step (0.25 mm, or 1/131070 of a block's extent if more) and a
    // confidence step: matched triangle by triangle, in the stream's own vertex order.
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
    std::size_t bytes = 0, v1_bytes = 0;
    for (std::size_t i = 0; i < m.changed.size(); ++i) {
        const Mesh &got = m.changed[i].mesh, &sent = delta.changed[i].mesh;
        EXPECT_TRUE(m.changed[i].key == delta.changed[i].key);
        ASSERT_EQ(got.triangles.size(), sent.triangles.size());
        ASSERT_LE(got.vertices.size(), sent.vertices.size());
        Eigen::AlignedBox3d box;
        for (const auto& v : sent.vertices) box.extend(v);
        const double half_step = std::max(box.sizes().maxCoeff() / 131070, 0.25e-3);
        ASSERT_LT(half_step, 0.26e-3);
        ASSERT_EQ(test::unmatched_triangles(got, sent, half_step + 1e-6, test::confidence_step(sent) + 1e-7), 0u) << "block " << i;
        bytes += bodies[i].size();
        v1_bytes += 20 + 17 * sent.vertices.size() + (4 - sent.vertices.size() % 4) % 4 + 12 * sent.triangles.size();
    }
    // Float32 arrays as they are took 4 times as much.
    EXPECT_LT(4 * bytes, v1_bytes + v1_bytes / 2);
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
    bad[4] = 1;  // version 1
    EXPECT_THROW(ls::decode(bytes_of(bad)), FormatError);
    bad = good;
    const std::uint32_t huge = 0xFFFFFFFFu;
    std::memcpy(bad.data() + 88, &huge, 4);  // a count larger than the message
    EXPECT_THROW(ls::decode(bytes_of(bad)), FormatError);
    for (const std::uint32_t nv : {2u, 70000u}) {  // fewer vertices than the triangle uses, or more than a block can hold
        bad = good;
        std::memcpy(bad.data() + 136 + 12, &nv, 4);  // the block follows the header (112), a trajectory point and a removed key
        EXPECT_THROW(ls::decode(bytes_of(bad)), FormatError) << nv;
    }
    for (std::size_t at = 136 + 56; at < good.size(); ++at) {  // any byte of the codes changed: refused, or triangles within the block
        bad = good;
        bad[at] = static_cast<char>(bad[at] ^ 0x5A);
        try {
            const ls::Message m = ls::decode(bytes_of(bad));
            for (const auto& t : m.changed.at(0).mesh.triangles)
                for (const std::uint32_t v : t) ASSERT_LT(v, 3u);
        } catch (const FormatError&) {
        }
    }
}
