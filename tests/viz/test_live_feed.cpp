// The live feed (viz/live_feed.hpp): clients that read every update, join late, or are slow all
// end with the live mesh (LiveMesh::blocks(), the oracle: an independent path from the updates'
// deltas), a slow client gets each block once however many updates it missed, a catch-up is cut
// into messages of the size asked, and after finish() every client holds the final mesh.
#include <gtest/gtest.h>

#include <set>
#include <tuple>

#include "../map/town_drive.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/viz/live_feed.hpp"
#include "live_client.hpp"

using namespace lidarsurf;

namespace {

// Reads every message the client is due.
void drain(LiveFeed& feed, LiveFeed::Client id, test::LiveClient& client, std::size_t* messages = nullptr) {
    while (std::optional<std::string> m = feed.next_message(id)) {
        client.take(*m);
        if (messages) ++*messages;
    }
}

std::set<std::tuple<int, int, int>> keys_of(const MeshDelta& d) {
    std::set<std::tuple<int, int, int>> out;
    for (const MeshBlock& b : d.changed) out.insert({b.key.x(), b.key.y(), b.key.z()});
    for (const VoxelKey& k : d.removed) out.insert({k.x(), k.y(), k.z()});
    return out;
}

}  // namespace

TEST(LiveFeed, EveryClientEndsWithTheLiveMeshHoweverItReads) {
    const std::vector<test::Scan>& drive = test::town_drive();
    Reconstructor rec(ReconstructionConfig{}, drive[0].from);
    LiveFeed feed;
    test::LiveClient eager, slow, late;
    const LiveFeed::Client eager_id = feed.add_client(), slow_id = feed.add_client();
    LiveFeed::Client late_id = 0;
    std::set<std::tuple<int, int, int>> missed;  // what the slow client missed since its last read
    for (std::size_t i = 0; i < drive.size(); ++i) {
        rec.integrate(drive[i].points, drive[i].from);
        MeshDelta delta = rec.update_mesh(5.0);  // a budget: blocks wait, carving may empty some
        const auto keys = keys_of(delta);
        missed.insert(keys.begin(), keys.end());
        feed.publish(std::move(delta), drive[i].pose, static_cast<std::uint32_t>(i + 1));
        drain(feed, eager_id, eager);
        test::expect_same_blocks(eager.blocks, rec.live()->blocks(), "eager client, scan " + std::to_string(i));
        if (i == 2) late_id = feed.add_client();
        if (i % 3 == 2) {
            // The slow one reads every third update: each block it lacks comes once, in one message.
            std::size_t messages = 0;
            const std::size_t before = slow.headers_only.size();
            drain(feed, slow_id, slow, &messages);
            EXPECT_EQ(messages, 1u);
            const live_stream::Message& m = slow.headers_only[before];
            EXPECT_EQ(m.header.scans, i + 1);
            EXPECT_EQ(m.trajectory.size(), 3u);  // the three poses since its last read
            std::size_t changed_blocks = 0;
            for (const MeshBlock& b : slow.blocks) changed_blocks += missed.count({b.key.x(), b.key.y(), b.key.z()});
            EXPECT_EQ(m.removed.size() + changed_blocks, missed.size()) << "each missed block once, as removed or changed";
            missed.clear();
            test::expect_same_blocks(slow.blocks, rec.live()->blocks(), "slow client, scan " + std::to_string(i));
        }
    }
    // Three blocks left without a triangle go; the eager client read every earlier update, so its
    // last message holds exactly these three removals.
    MeshDelta removal;
    std::vector<MeshBlock> expected = rec.live()->blocks();
    for (int k = 0; k < 3; ++k) {
        removal.removed.push_back(expected[static_cast<std::size_t>(10 * k)].key);
        expected.erase(expected.begin() + 10 * k);
    }
    feed.publish(removal, drive.back().pose, static_cast<std::uint32_t>(drive.size()));
    drain(feed, eager_id, eager);
    EXPECT_EQ(eager.headers_only.back().removed.size(), 3u);
    test::expect_same_blocks(eager.blocks, expected, "eager client, after the removals");
    drain(feed, late_id, late);
    EXPECT_TRUE(late.headers_only.front().header.flags & live_stream::kReset);
    EXPECT_EQ(late.trajectory, drive.size()) << "a late client gets the whole trajectory";
    test::expect_same_blocks(late.blocks, expected, "late client");
    EXPECT_FALSE(feed.next_message(eager_id)) << "nothing new: no message";

    // The end: the exact mesh, cut at the blocks, replaces the live one for every client.
    const Mesh exact = rec.extract_mesh();
    std::vector<MeshBlock> final_blocks = split_into_blocks(exact, rec.grid().origin(), ReconstructionConfig{}.voxel_size);
    feed.finish(final_blocks, drive.back().pose, static_cast<std::uint32_t>(drive.size()));
    for (test::LiveClient* c : {&eager, &slow, &late}) {
        const LiveFeed::Client id = c == &eager ? eager_id : c == &slow ? slow_id : late_id;
        drain(feed, id, *c);
        EXPECT_TRUE(c->final);
        test::expect_same_blocks(c->blocks, final_blocks, "the final mesh");
    }
    EXPECT_FALSE(feed.next_message(eager_id)) << "the final message is sent once";
}

TEST(LiveFeed, ACatchUpIsCutIntoMessagesOfTheSizeAsked) {
    const std::vector<test::Scan>& drive = test::town_drive();
    Reconstructor rec(ReconstructionConfig{}, drive[0].from);
    constexpr std::size_t kMax = 256 * 1024;
    LiveFeed feed(kMax);
    for (std::size_t i = 0; i < 2; ++i) {
        rec.integrate(drive[i].points, drive[i].from);
        feed.publish(rec.update_mesh(0), drive[i].pose, static_cast<std::uint32_t>(i + 1));
    }
    const LiveFeed::Client id = feed.add_client();
    test::LiveClient client;
    std::vector<std::size_t> sizes;
    while (std::optional<std::string> m = feed.next_message(id)) {
        sizes.push_back(m->size());
        client.take(*m);
    }
    ASSERT_GT(sizes.size(), 3u) << "a map of several MB in pieces of 256 kB";
    for (std::size_t i = 0; i < sizes.size(); ++i) {
        const std::uint32_t flags = client.headers_only[i].header.flags;
        EXPECT_EQ((flags & live_stream::kReset) != 0, i == 0);
        EXPECT_EQ((flags & live_stream::kMore) != 0, i + 1 < sizes.size());
        EXPECT_LE(sizes[i], kMax + 64 * 1024) << "a message holds at most one block beyond the size asked";
    }
    test::expect_same_blocks(client.blocks, rec.live()->blocks(), "after the catch-up");
    EXPECT_THROW(LiveFeed(16), InvalidArgument);
}

TEST(LiveFeed, SplitIntoBlocksKeepsEveryTriangleInTheBlockOfItsCentroid) {
    const std::vector<test::Scan>& drive = test::town_drive();
    Reconstructor rec(ReconstructionConfig{}, drive[0].from);
    rec.integrate(drive[0].points, drive[0].from);
    const Mesh exact = rec.extract_mesh();
    const double alpha = ReconstructionConfig{}.voxel_size;
    const std::vector<MeshBlock> blocks = split_into_blocks(exact, rec.grid().origin(), alpha);
    EXPECT_TRUE(test::triangles_of(concatenate(blocks)) == test::triangles_of(exact));
    for (const MeshBlock& b : blocks) {
        b.mesh.check();
        const Eigen::Vector3d lo = rec.grid().origin() + 8 * alpha * b.key.cast<double>();
        for (const auto& t : b.mesh.triangles) {
            const Eigen::Vector3d c = (b.mesh.vertices[t[0]] + b.mesh.vertices[t[1]] + b.mesh.vertices[t[2]]) / 3;
            ASSERT_TRUE(((c - lo).array() >= -1e-9).all() && ((c - lo).array() < 8 * alpha + 1e-9).all());
        }
    }
}
