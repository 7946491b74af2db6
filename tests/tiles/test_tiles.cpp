// A map fused in tiles (tiles/tiles.hpp), and one map meshed and written tile by tile, against the same
// map fused and meshed whole (the oracle: one Reconstructor over every scan, one extraction): the
// parts' triangles together are the whole map's, none lost and none twice, each in the tile whose
// square holds its cube; the seams are welded; a tile that a scan cannot reach counts it without
// its points.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/tiles/tile_writer.hpp"
#include "lidarsurf/tiles/tiles.hpp"
#include "test_util.hpp"
#include "map/town_drive.hpp"

using namespace lidarsurf;

namespace {

// A 180 m town drive there and back seen by a sensor of 40 m range: scans at one end do not reach
// the tiles at the other, which the drive leaves and comes back to; a parked car leaves and
// moving ones pass (carving removes them).
const std::vector<test::Scan>& short_range_drive() {
    static const std::vector<test::Scan> scans = [] {
        sim::SceneConfig scene;
        scene.length = 180;
        scene.leaving_cars = 1;
        sim::SimulatorConfig sc;
        sc.frames = 9;
        sc.gt_beams = 0;
        sc.sensor.max_range = 40;
        const sim::Simulator simulator(sim::make_world(scene), sc);
        std::vector<test::Scan> out;
        for (std::size_t i = 0; i < simulator.frame_count(); ++i) {
            const sim::SimulatedFrame f = simulator.frame(i);
            test::Scan s{{}, f.pose.translation(), f.pose};
            for (const Eigen::Vector3d& p : f.scan.points) s.points.push_back(f.pose * p);
            out.push_back(std::move(s));
        }
        for (std::size_t i = simulator.frame_count(); i-- > 0;) out.push_back(out[i]);  // back the same way
        return out;
    }();
    return scans;
}

TilePlan plan_of(const std::vector<test::Scan>& drive, const ReconstructionConfig& config, const TileConfig& tiles) {
    std::vector<ScanReach> reach;
    for (const test::Scan& s : drive) reach.push_back(scan_reach(s.points, s.from));
    return TilePlan(std::move(reach), config, tiles);
}

// The whole map: one Reconstructor over every scan.
std::unique_ptr<Reconstructor> whole_map(const std::vector<test::Scan>& drive, const ReconstructionConfig& config) {
    auto rec = std::make_unique<Reconstructor>(config, drive.front().from);
    for (const test::Scan& s : drive) rec->integrate(s.points, s.from);
    return rec;
}

// Parts of a map welded one after the other (Mesh::append with the welder's indices, as a
// MeshStreamWriter writes them).
struct Tiled {
    Mesh mesh;
    std::map<TileKey, Mesh> parts;
    void append(SeamWelder& welder, const TileKey& t, const Mesh& part) {
        mesh.append(part, welder.weld(t, part, mesh.vertices.size()));
        parts[t] = part;
    }
};
// Every tile fused apart.
Tiled tiled_map(const TilePlan& plan, const std::vector<test::Scan>& drive) {
    Tiled out;
    SeamWelder welder(plan);
    for (const TileKey& t : plan.tiles()) out.append(welder, t, fuse_tile(plan, t, [&](std::size_t i) { return drive[i].points; }));
    return out;
}
// The tiles fused group by group (TileConfig::group), each group in one pass over the scans that
// shares their reading and range images; each scan read once per group.
Tiled grouped_map(const TilePlan& plan, const std::vector<test::Scan>& drive) {
    Tiled out;
    SeamWelder welder(plan);
    std::size_t handed = 0, reads = 0;
    for (const std::vector<TileKey>& group : plan.groups()) {
        std::vector<std::size_t> read(drive.size(), 0);
        const TilePassStats stats = fuse_tiles(
            plan, group,
            [&](std::size_t i, std::vector<Eigen::Vector3f>&) {
                ++read[i];
                return PointCloud{drive[i].points};
            },
            [&](const TileKey& t, Mesh&& part, const ReconstructionSummary&) {
                EXPECT_TRUE(std::find(group.begin(), group.end(), t) != group.end());
                out.append(welder, t, part);
                ++handed;
            });
        for (std::size_t i = 0; i < drive.size(); ++i) {
            const bool wanted = std::any_of(group.begin(), group.end(), [&](const TileKey& t) { return plan.reaches(t, i); });
            EXPECT_EQ(read[i], wanted ? 1u : 0u) << "scan " << i << ": read once for its group when a tile of it takes it";
            reads += read[i];
        }
        EXPECT_EQ(stats.scans_read, static_cast<std::size_t>(std::count_if(read.begin(), read.end(), [](std::size_t n) { return n > 0; })));
        EXPECT_LE(stats.most_open, group.size());
    }
    EXPECT_EQ(handed, plan.tiles().size()) << "every tile handed over once";
    EXPECT_GT(reads, 0u);
    return out;
}
// One map, meshed tile by tile (what `fuse` writes: tile_writer.hpp).
Tiled tiles_of(Reconstructor& rec, const TilePlan& plan) {
    Tiled out;
    SeamWelder welder(plan);
    mesh_in_tiles(rec, plan, [&](const TileKey& t, const Mesh& part) { out.append(welder, t, part); });
    return out;
}

void expect_tiles_equal_the_whole_map(const std::vector<test::Scan>& drive, const TileConfig& tiles, std::size_t min_tiles,
                                      const ReconstructionConfig& config = {}) {
    const TilePlan plan = plan_of(drive, config, tiles);
    ASSERT_GE(plan.tiles().size(), min_tiles);
    EXPECT_LT(plan.groups().size(), plan.tiles().size()) << "groups of several tiles";
    const std::unique_ptr<Reconstructor> rec = whole_map(drive, config);
    const Mesh whole = rec->extract_mesh();
    ASSERT_GT(whole.triangles.size(), 10000u);
    const auto expect_whole = [&](const Mesh& mesh, const char* what) {
        EXPECT_EQ(mesh.triangles.size(), whole.triangles.size()) << what;
        EXPECT_TRUE(test::triangles_of(mesh) == test::triangles_of(whole)) << what << ": the same triangles, none lost, none twice";
        EXPECT_EQ(mesh.vertices.size(), whole.vertices.size()) << what << ": each vertex on a seam written once";
    };
    // The whole map meshed tile by tile, in memory and as fuse writes it, and the tiles fused apart.
    expect_whole(tiles_of(*rec, plan).mesh, "one map in tiles");
    // Written: against the whole mesh written in one piece (the same float coordinates).
    const test::TempDir dir("tiles");
    const ReconstructionSummary written = write_in_tiles(*rec, plan, (dir / "map.ply").string(), MeshFormat::PlyBinary);
    EXPECT_EQ(written.mesh_triangles, whole.triangles.size());
    write_mesh(whole, dir / "whole.ply", MeshFormat::PlyBinary);
    const Mesh file = read_mesh(dir / "map.ply"), whole_file = read_mesh(dir / "whole.ply");
    EXPECT_EQ(file.triangles.size(), whole_file.triangles.size());
    EXPECT_EQ(file.vertices.size(), whole_file.vertices.size()) << "each vertex on a seam written once";
    EXPECT_TRUE(test::triangles_of(file) == test::triangles_of(whole_file)) << "one map written in tiles: the same triangles";
    const Tiled tiled = tiled_map(plan, drive);
    expect_whole(tiled.mesh, "tiles");
    expect_whole(grouped_map(plan, drive).mesh, "tiles in groups");
    std::size_t with_triangles = 0;
    for (const auto& [key, part] : tiled.parts) {
        with_triangles += !part.triangles.empty();
        const Eigen::AlignedBox3d square = plan.square(key);
        for (const auto& tri : part.triangles) {
            const Eigen::Vector3d c = (part.vertices[tri[0]] + part.vertices[tri[1]] + part.vertices[tri[2]]) / 3;
            // A triangle lies in its cube: within a voxel of the tile's square.
            EXPECT_LE(square.exteriorDistance(Eigen::Vector3d(c.x(), c.y(), 0)), config.voxel_size);
        }
    }
    EXPECT_GE(with_triangles, min_tiles);
}

}  // namespace

TEST(Tiles, TheTilesMeshIsTheWholeMapsMesh) {
    TileConfig tiles;
    tiles.tile_size = 30;  // groups of 2 x 2 tiles
    expect_tiles_equal_the_whole_map(test::town_drive(), tiles, 5);
}

TEST(Tiles, AGroupReadsTheNextScanWhileItFusesOne) {
    // Two scans of the town: the group's pass reads on a thread of its own (and ThreadSanitizer
    // watches it: Makefile, TSAN_FILTER); its tiles are still the map fused whole.
    const std::vector<test::Scan> drive(test::town_drive().begin(), test::town_drive().begin() + 2);
    TileConfig tiles;
    tiles.tile_size = 30;
    const TilePlan plan = plan_of(drive, ReconstructionConfig{}, tiles);
    ASSERT_LT(plan.groups().size(), plan.tiles().size());
    const Mesh whole = whole_map(drive, ReconstructionConfig{})->extract_mesh();
    ASSERT_GT(whole.triangles.size(), 1000u);
    EXPECT_TRUE(test::triangles_of(grouped_map(plan, drive).mesh) == test::triangles_of(whole));
}

TEST(Tiles, SimplifiedTilesKeepTheirSeamsClosed) {
    // Each part keeps its border vertices in place (mesh/simplify.hpp), so the seams weld as
    // unsimplified: the welded map has no open edge that the unsimplified tiles' map has not.
    TileConfig tiles;
    tiles.tile_size = 30;
    const std::vector<test::Scan>& drive = test::town_drive();
    ReconstructionConfig simplified;
    simplified.simplify = 0.02;
    const TilePlan plan = plan_of(drive, ReconstructionConfig{}, tiles);
    ASSERT_GE(plan.tiles().size(), 5u);
    Tiled full = tiles_of(*whole_map(drive, ReconstructionConfig{}), plan), simple = tiles_of(*whole_map(drive, simplified), plan);
    EXPECT_LT(simple.mesh.triangles.size(), full.mesh.triangles.size() / 2);
    const auto full_open = test::open_edges(full.mesh);
    std::size_t opened = 0;
    for (const auto& e : test::open_edges(simple.mesh)) opened += !full_open.count(e);
    EXPECT_EQ(opened, 0u) << "open edges the unsimplified tiles' map has not: a seam opened";
}

TEST(Tiles, ScansThatCannotReachATileAreCountedNotIntegrated) {
    TileConfig tiles;
    tiles.tile_size = 25;
    const std::vector<test::Scan>& drive = short_range_drive();
    // Staleness within the drive: a tile counts the scans it skips, or the voxels it sees again on
    // the way back would go stale late.
    ReconstructionConfig config;
    config.carve_stale_scans = 2;
    const TilePlan plan = plan_of(drive, config, tiles);
    // Tiles at the two ends of the drive take only some of its scans: the first, left and come back to.
    std::size_t revisited = 0;
    for (const TileKey& t : plan.tiles()) {
        std::size_t runs = 0;
        for (std::size_t i = 0; i < drive.size(); ++i) runs += plan.reaches(t, i) && (i == 0 || !plan.reaches(t, i - 1));
        revisited += runs > 1;
    }
    EXPECT_GE(revisited, 2u);
    // Every tile in one pass: tiles opened at their first scan, some left and come back to while
    // others are open, each meshed after its last scan.
    tiles.group = 64;
    std::size_t largest = 0;
    for (const auto& group : plan_of(drive, config, tiles).groups()) largest = std::max(largest, group.size());
    ASSERT_GE(largest, 4u);
    expect_tiles_equal_the_whole_map(drive, tiles, 7, config);
}

TEST(Tiles, BadPlansAreRefused) {
    for (const TileConfig& bad : {TileConfig{0.5, 32}, TileConfig{std::nan(""), 32}, TileConfig{100, 2}, TileConfig{100, 2000},
                                  TileConfig{100, 32, 0}, TileConfig{100, 32, 65}})
        EXPECT_THROW(bad.validate(), InvalidArgument);
    ReconstructionConfig filtered;
    filtered.min_component_triangles = 10;
    const std::vector<Eigen::Vector3d> points = {{1, 2, 3}};
    EXPECT_THROW(TilePlan({scan_reach(points, Eigen::Vector3d::Zero())}, filtered, TileConfig{}), InvalidArgument);
    const std::vector<Eigen::Vector3d> nothing = {Eigen::Vector3d::Constant(std::nan(""))};
    EXPECT_THROW(TilePlan({scan_reach(nothing, Eigen::Vector3d::Zero())}, ReconstructionConfig{}, TileConfig{}), InvalidInput);
}
