// The live mesh (map/live_mesh.hpp) against oracles outside it: the exact extraction (with no
// threshold and no budget the live mesh is the exact mesh, triangle for triangle), an independent
// client applying the deltas, the geometry of the analytic street (what the car left is gone from
// the live mesh too), and the distances of the blocks a budgeted update meshed.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <ostream>
#include <tuple>
#include <vector>

#include "analytic_street.hpp"
#include "town_drive.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/map/live_mesh.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/simulator.hpp"
#include "test_util.hpp"

using namespace lidarsurf;
using lidarsurf::test::Scan;
using lidarsurf::test::town_drive;
using lidarsurf::test::Triangle;
using lidarsurf::test::triangles_of;

namespace {

// The client's copy of the live mesh, kept with nothing of the library but the deltas.
using KeyTuple = std::tuple<int, int, int>;
KeyTuple tuple_of(const VoxelKey& k) { return {k.z(), k.y(), k.x()}; }
void apply_to(std::map<KeyTuple, Mesh>& client, const MeshDelta& delta) {
    for (const VoxelKey& key : delta.removed) {
        ASSERT_EQ(client.count(tuple_of(key)), 1u) << "a removed block the client never had";
        client.erase(tuple_of(key));
    }
    for (const MeshBlock& b : delta.changed) {
        ASSERT_FALSE(b.mesh.triangles.empty());
        b.mesh.check();
        client[tuple_of(b.key)] = b.mesh;
    }
}
std::vector<Triangle> triangles_of(const std::map<KeyTuple, Mesh>& client) {
    std::vector<Triangle> out;
    for (const auto& [key, mesh] : client) {
        const std::vector<Triangle> t = test::triangles_of(mesh);
        out.insert(out.end(), t.begin(), t.end());
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace

TEST(LiveMesh, WithoutThresholdOrBudgetItIsTheExactMesh) {
    ReconstructionConfig c;
    c.live_growth = 0;  // every change re-meshes
    ReconstructionConfig map = c;
    map.bridge_reach = 0;  // a map has no bridges (Reconstructor::surface_config)
    c.live_reach_blocks = (map.max_reach() + 7) / 8;  // everything a vertex depends on
    c.live_halo_cubes = 16;
    c.live_range = 1e3;
    const std::vector<Scan>& drive = town_drive();
    Reconstructor live(c, drive[0].from), exact(c, drive[0].from);
    std::map<KeyTuple, Mesh> client;
    for (std::size_t i = 0; i < drive.size(); ++i) {
        live.integrate(drive[i].points, drive[i].from);
        exact.integrate(drive[i].points, drive[i].from);
        const MeshDelta delta = live.update_mesh(0);
        EXPECT_EQ(delta.pending, 0u);
        apply_to(client, delta);
        const std::vector<Triangle> expected = triangles_of(exact.extract_mesh());
        ASSERT_GT(expected.size(), 20000u);
        const std::vector<Triangle> got = triangles_of(live.live_mesh());
        EXPECT_EQ(got.size(), expected.size()) << "scan " << i;
        EXPECT_TRUE(got == expected) << "scan " << i << ": the live mesh is not the exact mesh";
        EXPECT_TRUE(triangles_of(client) == got) << "scan " << i << ": the deltas do not give the live mesh";
    }
    EXPECT_GT(live.summary().carved_voxels, 0u) << "the drive must carve, so that blocks lose voxels";
}

TEST(LiveMesh, DeltasAppliedInOrderGiveTheLiveMeshAndTheExactMeshIsUntouched) {
    const ReconstructionConfig c;
    const std::vector<Scan>& drive = town_drive();
    Reconstructor live(c, drive[0].from), batch(c, drive[0].from);
    std::map<KeyTuple, Mesh> client;
    std::vector<MeshBlock> blocks;  // the library's own client, apply()
    std::size_t changed = 0, pending = 0;
    for (std::size_t i = 0; i < drive.size(); ++i) {
        live.integrate(drive[i].points, drive[i].from);
        batch.integrate(drive[i].points, drive[i].from);
        const MeshDelta delta = live.update_mesh(5.0);  // a budget: some blocks wait
        apply_to(client, delta);
        apply(delta, blocks);
        changed += delta.changed.size();
        pending += delta.pending;
        const Mesh mesh = live.live_mesh();
        EXPECT_EQ(live.live()->triangle_count(), mesh.triangles.size());
        EXPECT_TRUE(triangles_of(client) == triangles_of(mesh)) << "scan " << i;
        test::expect_identical(concatenate(blocks), mesh, "apply() after scan " + std::to_string(i));
    }
    EXPECT_GT(changed, 100u);
    EXPECT_GT(pending, 0u) << "a 5 ms budget should leave blocks for later on a 120k-point scan";
    // The live updates leave the grid and the exact extraction as they were.
    test::expect_identical(live.extract_mesh(), batch.extract_mesh(), "exact mesh with and without live updates");
    // Everything due, at once: the live mesh catches up (nothing left pending within range).
    const MeshDelta rest = live.update_mesh(0);
    apply_to(client, rest);
    EXPECT_TRUE(triangles_of(client) == triangles_of(live.live_mesh()));
}

TEST(LiveMesh, ABudgetedUpdateMeshesTheNearestBlocksFirst) {
    ReconstructionConfig c;
    c.threads = 1;
    const std::vector<Scan>& drive = town_drive();
    Reconstructor rec(c, drive[0].from);
    rec.integrate(drive[0].points, drive[0].from);
    const MeshDelta first = rec.update_mesh(1e-3);  // one batch
    ASSERT_GT(first.pending, 0u);
    const MeshDelta second = rec.update_mesh(0);  // the rest
    ASSERT_FALSE(first.changed.empty());
    ASSERT_FALSE(second.changed.empty());
    const Eigen::Vector3d local = rec.grid().to_local(drive[0].from);
    auto distance = [&](const VoxelKey& key) { return ((key.cast<double>() * 8 + Eigen::Vector3d::Constant(4)) * c.voxel_size - local).norm(); };
    double farthest_first = 0, nearest_second = 1e9;
    for (const MeshBlock& b : first.changed) farthest_first = std::max(farthest_first, distance(b.key));
    for (const MeshBlock& b : second.changed) nearest_second = std::min(nearest_second, distance(b.key));
    EXPECT_LE(farthest_first, nearest_second + 1e-9);
    EXPECT_LE(farthest_first, 20.0) << "one batch covers the blocks around the sensor";
}

// Carving removes the car's trail from the grid: the blocks that lost a voxel are due at once,
// those around them count the points removed as a change. With every change re-meshing everything
// within the reach of every dependency (growth 0, 2 blocks for the default's 13 voxels), the live
// mesh loses the trail as the exact mesh does, to the triangle; with the defaults (growth 0.25,
// reach 1), within a fifth (what a removal changes around it waits until the change is large
// enough there).
struct ReachCase {
    int reach;
    double growth;
};
void PrintTo(const ReachCase& c, std::ostream* os) { *os << "reach " << c.reach << ", growth " << c.growth; }
class LiveMeshReach : public ::testing::TestWithParam<ReachCase> {};
TEST_P(LiveMeshReach, WhatTheCarLeftIsGoneFromTheLiveMesh) {
    using namespace test::street;
    constexpr int kScans = 24;
    ReconstructionConfig c;
    c.live_reach_blocks = GetParam().reach;
    c.live_growth = GetParam().growth;
    const bool every_dependency = c.live_reach_blocks * 8 >= c.max_reach() && c.live_growth == 0;
    Reconstructor rec(c, sensor_at(0));
    std::map<KeyTuple, Mesh> client;
    std::size_t most_in_trail = 0;
    auto in_trail_count = [](const Mesh& m) {  // triangles (the live mesh repeats the vertices on block faces)
        return static_cast<std::size_t>(std::count_if(m.triangles.begin(), m.triangles.end(), [&](const auto& t) {
            return in_trail((m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0, kScans - 1);
        }));
    };
    for (int i = 0; i < kScans; ++i) {
        rec.integrate(scan(i, true), sensor_at(i));
        apply_to(client, rec.update_mesh(0));
        std::vector<MeshBlock> blocks;
        for (const auto& [key, m] : client) blocks.push_back({VoxelKey(std::get<2>(key), std::get<1>(key), std::get<0>(key)), m});
        most_in_trail = std::max(most_in_trail, in_trail_count(concatenate(blocks)));
    }
    ASSERT_GT(rec.summary().carved_voxels, 100u);
    const Mesh exact = rec.extract_mesh();
    const Mesh live = rec.live_mesh();
    const std::size_t in_live = in_trail_count(live), in_exact = in_trail_count(exact);
    ASSERT_GT(most_in_trail, 300u) << "the car must have been meshed on its way";
    const std::size_t allowed = every_dependency ? in_exact : in_exact + in_exact / 5 + 10;
    EXPECT_LE(in_live, allowed) << in_live << " live, " << in_exact << " exact, at most " << most_in_trail << " on the way";
    ASSERT_LT(in_exact + 50, most_in_trail) << "carving must have removed part of the trail";
    EXPECT_LE(in_live, most_in_trail - (most_in_trail - in_exact) / 2) << "the live mesh lost at least half of what the exact mesh lost";
    // And the static street is there: the wall and the ground near the sensor.
    std::size_t wall = 0, ground = 0;
    for (const Eigen::Vector3d& p : live.vertices) {
        wall += std::fabs(p.y() - kWallY) < 0.1;
        ground += std::fabs(p.z()) < 0.1 && std::fabs(p.x() - sensor_at(kScans - 1).x()) < 10;
    }
    EXPECT_GT(wall, 500u);
    EXPECT_GT(ground, 500u);
}
INSTANTIATE_TEST_SUITE_P(Reach, LiveMeshReach, ::testing::Values(ReachCase{1, 0.25}, ReachCase{2, 0.0}),
                         [](const ::testing::TestParamInfo<ReachCase>& c) {
                             return c.param.growth == 0 ? "EveryDependency" : "Defaults";
                         });

TEST(LiveMesh, RefusesThePaperAsWrittenAndABadBudget) {
    Reconstructor paper(ReconstructionConfig::paper(), Eigen::Vector3d::Zero());
    paper.integrate(town_drive()[0].points, town_drive()[0].from);
    EXPECT_THROW(paper.update_mesh(10), InvalidArgument);
    Reconstructor rec(ReconstructionConfig{}, Eigen::Vector3d::Zero());
    EXPECT_THROW(rec.update_mesh(std::nan("")), InvalidArgument);
    // Before any point: an empty delta, an empty live mesh.
    const MeshDelta none = rec.update_mesh(10);
    EXPECT_TRUE(none.changed.empty() && none.removed.empty());
    EXPECT_TRUE(rec.live_mesh().triangles.empty());
    ReconstructionConfig c;
    c.live_growth = -1;
    EXPECT_THROW(c.validate(), InvalidArgument);
    c = {};
    c.live_range = 0;
    EXPECT_THROW(c.validate(), InvalidArgument);
    c = {};
    c.live_halo_cubes = -1;
    EXPECT_THROW(c.validate(), InvalidArgument);
}
