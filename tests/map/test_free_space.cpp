// Free-space carving on the analytic street (analytic_street.hpp). The oracles are geometric:
// where the box was and no longer is, where the static surfaces are.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/map/free_space.hpp"
#include "analytic_street.hpp"
#include "test_util.hpp"

using namespace lidarsurf;
using namespace lidarsurf::test::street;

namespace {

// A carver of the 0.2 m grids below; the margin in metres (0.4 m: 2 voxels).
FreeSpaceCarver carver_of(double margin, int min_scans, double range, int stale_scans = 0) {
    CarvingConfig c;
    c.carve_margin_voxels = margin / 0.2;
    c.carve_min_scans = min_scans;
    c.carve_range = range;
    c.carve_stale_scans = stale_scans;
    return FreeSpaceCarver(c, 0.2);
}

struct Counts {
    std::size_t trail = 0, static_voxels = 0;
};
Counts count(const VoxelGrid& grid, int last) {
    Counts c;
    for (const VoxelStats& s : grid.stats()) {
        const Eigen::Vector3d p = grid.to_world(s.mean);
        c.trail += in_trail(p, last);
        c.static_voxels += on_static(p);
    }
    return c;
}

constexpr int kScans = 24;

// Mesh triangles whose centroid lies in `b` (grown by `grow`, above `z_min`).
std::size_t triangles_in(const Mesh& m, const Box& b, double grow = 0, double z_min = -1e9) {
    std::size_t n = 0;
    for (const auto& t : m.triangles) {
        const Eigen::Vector3d c = (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0;
        n += (c.array() > b.lo.array() - grow).all() && (c.array() < b.hi.array() + grow).all() && c.z() > z_min;
    }
    return n;
}

// The drives below are 40 scans long: a voxel gone stale is removed after three passes
// (carve_stale_passes) instead of six, what a 150-scan drive gives it time for.
constexpr int kStalePasses = 3;

// The map of a 40-scan drive with `boxes_at(i)` standing in the street at scan i, carved or not,
// the scans saying which of their rays returned nothing (`empty_rays`), the `dark` boxes absorbing
// what hits them and `dropout` of the returns lost at random.
template <typename F>
Mesh fused_with_rays(bool carve, F&& boxes_at, const std::vector<Box>& dark = {}, double dropout = 0, bool empty_rays = true,
                     double cluster_share = CarvingConfig{}.carve_cluster_share) {
    ReconstructionConfig c;
    c.carve = carve;
    c.carve_stale_passes = kStalePasses;
    c.carve_cluster_share = cluster_share;
    Reconstructor rec(c, sensor_at(0));
    for (int i = 0; i < 40; ++i) {
        std::vector<Eigen::Vector3f> no_return;
        const std::vector<Eigen::Vector3d> points = scan_with(i, boxes_at(i), {dark, dropout, empty_rays ? &no_return : nullptr});
        rec.integrate(points, sensor_at(i), no_return);
    }
    return rec.extract_mesh();
}

// The same with returns only.
template <typename F>
Mesh fused(bool carve, F&& boxes_at) {
    return fused_with_rays(carve, std::forward<F>(boxes_at), {}, 0, false);
}

}  // namespace

TEST(FreeSpace, CarvesAMovingCarsTrailAndKeepsTheGroundTheWallAndAPole) {
    VoxelGrid carved(0.2), kept(0.2);
    carved.enable_viewpoints(sensor_at(0));
    kept.enable_viewpoints(sensor_at(0));
    FreeSpaceCarver carver = carver_of(0.4, 2, 40.0);
    std::size_t removed = 0;
    for (int i = 0; i < kScans; ++i) {
        const std::vector<Eigen::Vector3d> points = scan(i, true);
        std::vector<VoxelGrid::Hit> hits;
        carved.insert(points, sensor_at(i), &hits);
        removed += carver.carve(carved, points, hits, sensor_at(i)).removed;
        kept.insert(points, sensor_at(i));
    }
    const Counts before = count(kept, kScans - 1), after = count(carved, kScans - 1);
    ASSERT_GT(before.trail, 200u) << "the scene must leave a trail to carve";
    // Most of the trail goes; what stays is mostly the car's last positions, seen through by too
    // few scans before the drive ends (docs/method.md, "Free space": limits).
    EXPECT_LT(after.trail, before.trail / 4) << after.trail << " of " << before.trail << " trail voxels left";
    // Static surfaces: at most 0.5 % of their voxels carved (grazing rays on the ground, the pole).
    EXPECT_GT(static_cast<double>(after.static_voxels), 0.995 * static_cast<double>(before.static_voxels))
        << after.static_voxels << " of " << before.static_voxels;
    EXPECT_GT(removed, before.trail / 2);
    // The grid stays consistent after removals: every voxel is found under its key.
    for (std::size_t v = 0; v < carved.size(); ++v) ASSERT_EQ(carved.find(carved.keys()[v]), &carved.stats()[v]);
    // Without the car, nothing is carved at all from the static street.
    VoxelGrid empty_street(0.2);
    empty_street.enable_viewpoints(sensor_at(0));
    FreeSpaceCarver quiet = carver_of(0.4, 2, 40.0);
    std::size_t static_removed = 0;
    for (int i = 0; i < kScans; ++i) {
        const std::vector<Eigen::Vector3d> points = scan(i, false);
        std::vector<VoxelGrid::Hit> hits;
        empty_street.insert(points, sensor_at(i), &hits);
        static_removed += quiet.carve(empty_street, points, hits, sensor_at(i)).removed;
    }
    EXPECT_LT(static_removed, empty_street.size() / 200) << static_removed << " of " << empty_street.size();
}

TEST(FreeSpace, TheMeshLosesTheTrailAndASingleScanIsUnchanged) {
    ReconstructionConfig on, off;
    off.carve = false;
    Reconstructor with(on, sensor_at(0)), without(off, sensor_at(0));
    for (int i = 0; i < kScans; ++i) {
        const std::vector<Eigen::Vector3d> points = scan(i, true);
        with.integrate(points, sensor_at(i));
        without.integrate(points, sensor_at(i));
    }
    const Mesh carved = with.extract_mesh(), kept = without.extract_mesh();
    auto trail_vertices = [](const Mesh& m) {
        return std::count_if(m.vertices.begin(), m.vertices.end(), [](const Eigen::Vector3d& p) { return in_trail(p, kScans - 1); });
    };
    ASSERT_GT(trail_vertices(kept), 100);
    EXPECT_LT(trail_vertices(carved), trail_vertices(kept) * 6 / 10) << trail_vertices(carved) << " of " << trail_vertices(kept);
    EXPECT_GT(with.summary().carved_voxels, 0u);
    // One scan with a viewpoint: nothing can be seen through by the scan that made it.
    for (int i : {0, 7}) {
        Reconstructor one_on(on, sensor_at(i)), one_off(off, sensor_at(i));
        const std::vector<Eigen::Vector3d> points = scan(i, true);
        one_on.integrate(points, sensor_at(i));
        one_off.integrate(points, sensor_at(i));
        test::expect_identical(one_on.extract_mesh(), one_off.extract_mesh(), "one scan, carving on and off");
        EXPECT_EQ(one_on.summary().carved_voxels, 0u);
    }
}

TEST(FreeSpace, IncrementalMeshesEqualTheOnePassMesh) {
    ReconstructionConfig config;
    Reconstructor along(config, sensor_at(0)), once(config, sensor_at(0));
    Mesh mesh;
    for (int i = 0; i < 12; ++i) {
        const std::vector<Eigen::Vector3d> points = scan(i, true);
        along.integrate(points, sensor_at(i));
        once.integrate(points, sensor_at(i));
        if (i % 3 == 2) mesh = along.extract_mesh();
    }
    ASSERT_GT(along.summary().carved_voxels, 0u);
    test::expect_identical(mesh, once.extract_mesh(), "carved drive, meshed every third scan");
}

TEST(FreeSpace, RejectsBadParameters) {
    EXPECT_THROW(carver_of(0, 2, 40), InvalidArgument);
    EXPECT_THROW(carver_of(0.4, 0, 40), InvalidArgument);
    EXPECT_THROW(carver_of(0.4, 2, std::nan("")), InvalidArgument);
    ReconstructionConfig c;
    c.carve_margin_voxels = 0.1;
    EXPECT_THROW(c.validate(), InvalidArgument);
    c = {};
    c.carve_min_scans = 0;
    EXPECT_THROW(c.validate(), InvalidArgument);
    c = {};
    c.carve_range = -1;
    EXPECT_THROW(c.validate(), InvalidArgument);
    c = {};
    c.carve_stale_scans = -1;
    EXPECT_THROW(c.validate(), InvalidArgument);
    EXPECT_THROW(carver_of(0.4, 2, 40.0, -1), InvalidArgument);
}

// A car parked for the first half of the drive, then gone; another parked all along; the pole. The
// oracle is the same drive fused without carving, and the boxes themselves. The car that went was
// hit by twenty scans: the passes since its last hit remove it (carve_stale_passes), its past hits
// do not outweigh them; its roof, at the sensor's height, is seen through by the few rays that
// return within the 40 m range.
TEST(FreeSpace, ACarThatLeftLosesWhatRaysReachAndOneParkedAllAlongStays) {
    const Box gone{{8.0, 2.1, 0.0}, {12.5, 3.9, 1.5}}, stays{{20.0, -3.9, 0.0}, {24.5, -2.1, 1.5}};
    const auto boxes = [&](int i) { return i < 20 ? std::vector<Box>{stays, gone} : std::vector<Box>{stays}; };
    const Mesh carved = fused(true, boxes), kept = fused(false, boxes);
    const Box where_it_stood{{8.0, 2.1, 0.3}, {12.5, 3.9, 1.6}};
    const std::size_t left = triangles_in(carved, where_it_stood), before = triangles_in(kept, where_it_stood);
    ASSERT_GT(before, 200u);
    EXPECT_LE(left, before / 20) << left << " of " << before << ": 5 % at most of the car that left stays";
    // The car parked all along and the pole keep their surfaces.
    const std::size_t on_car = triangles_in(carved, stays, 0.1, 0.2), on_car_kept = triangles_in(kept, stays, 0.1, 0.2);
    ASSERT_GT(on_car_kept, 300u);
    EXPECT_GE(on_car, on_car_kept * 98 / 100);
    const Box pole{{kPoleX - 0.25, kPoleY - 0.25, 0.3}, {kPoleX + 0.25, kPoleY + 0.25, 5.5}};
    ASSERT_GT(triangles_in(kept, pole), 10u);
    EXPECT_GE(triangles_in(carved, pole), triangles_in(kept, pole) * 9 / 10);
}

// A walker crossing 1 m in front of the wall: less than 5 % of what it leaves where it walked stays.
TEST(FreeSpace, AWalkersPathInFrontOfTheWallIsMostlyCarved) {
    const auto walker = [](int i) { return Box{{2.0 + 0.15 * i, 7.5, 0.0}, {2.5 + 0.15 * i, 8.0, 1.8}}; };
    const auto boxes = [&](int i) { return std::vector<Box>{walker(i)}; };
    const Mesh carved = fused(true, boxes), kept = fused(false, boxes);
    // Where it walked ten scans or more before the drive ends (what it left in the last scans, seen
    // through by too few scans yet, is the end of the drive's: docs/method.md, "Free space").
    const Box path{{2.0, 7.5, 0.3}, {walker(29).lo.x(), 8.0, 1.8}};
    const std::size_t left = triangles_in(carved, path), before = triangles_in(kept, path);
    ASSERT_GT(before, 300u);
    EXPECT_LT(left, before / 20) << left << " of " << before << " triangles left where it walked";
    // The wall behind it stays.
    const Box wall{{-5.0, kWallY - 0.2, 0.3}, {20.0, kWallY + 0.2, 3.0}};
    EXPECT_GE(triangles_in(carved, wall), triangles_in(kept, wall) * 98 / 100);
}

TEST(FreeSpace, SkippingScansThatReachNothingIsCarvingThem) {
    // The reference: scans far away (5 km) carved for real, their returns reaching no voxel of
    // the grid; the fast path counts them (skip). The drive stops in the middle for those scans,
    // long enough for the planar voxels to go stale (8 scans counted) and the young ones to be dropped.
    constexpr int kStale = 8, kAway = 6;
    struct Run {
        VoxelGrid grid{0.2};
        FreeSpaceCarver carver = carver_of(0.4, 2, 40.0, kStale);
        std::size_t removed = 0;
    };
    const Eigen::Vector3d away(5000, 0, 0);
    const auto drive = [&](Run& r, int mode) {  // 0: carve the far scans, 1: skip them, 2: neither
        r.grid.enable_viewpoints(sensor_at(0));
        for (int i = 0; i < kScans; ++i) {
            if (i == kScans / 2)
                for (int k = 0; k < kAway; ++k) {
                    if (mode == 1) r.carver.skip();
                    if (mode != 0) continue;
                    std::vector<Eigen::Vector3d> far = scan(i, true);
                    for (Eigen::Vector3d& p : far) p += away;
                    r.removed += r.carver.carve(r.grid, far, {}, sensor_at(i) + away).removed;
                }
            const std::vector<Eigen::Vector3d> points = scan(i, true);
            std::vector<VoxelGrid::Hit> hits;
            r.grid.insert(points, sensor_at(i), &hits);
            r.removed += r.carver.carve(r.grid, points, hits, sensor_at(i)).removed;
        }
    };
    Run carved, skipped, unaware;
    drive(carved, 0);
    drive(skipped, 1);
    drive(unaware, 2);
    // The voxels whose evidence differs from the reference's (a voxel missing counts).
    const auto differences = [&](const Run& r) {
        std::size_t n = r.grid.size() > carved.grid.size() ? r.grid.size() - carved.grid.size() : 0;
        for (std::size_t v = 0; v < carved.grid.size(); ++v) {
            const VoxelStats* s = r.grid.find(carved.grid.keys()[v]);
            if (!s) {
                ++n;
                continue;
            }
            const auto w = static_cast<std::size_t>(s - r.grid.stats().data());
            n += r.carver.hit_scans(w) != carved.carver.hit_scans(v) || r.carver.pass_scans(w) != carved.carver.pass_scans(v);
        }
        return n;
    };
    ASSERT_GT(carved.removed, 100u);
    EXPECT_EQ(skipped.carver.scans(), carved.carver.scans());
    EXPECT_EQ(skipped.removed, carved.removed);
    EXPECT_EQ(skipped.grid.size(), carved.grid.size());
    EXPECT_EQ(differences(skipped), 0u);
    // Not counting them gives other evidence: the count is not a formality.
    EXPECT_GT(differences(unaware), 0u);
}

// A van taller than the sensor parked for the first half of the drive on the side with no wall,
// then gone, the scans saying which rays returned nothing: the rays through the upper half of its
// side go up, to the sky, and return nothing, so only they see through it there (clusters off:
// they would take the rest of it too, see below).
const Box kVanGone{{8.0, -3.9, 0.0}, {13.0, -2.1, 2.4}}, kCarStays{{20.0, 2.1, 0.0}, {24.5, 3.9, 1.5}};
std::vector<Box> van_then_car(int i) { return i < 20 ? std::vector<Box>{kCarStays, kVanGone} : std::vector<Box>{kCarStays}; }

TEST(FreeSpace, RaysThatReturnNothingCarveTheUpperSideOfAVanThatLeft) {
    const Box &gone = kVanGone, &stays = kCarStays;
    const auto boxes = van_then_car;
    const Mesh carved = fused_with_rays(true, boxes, {}, 0, true, 1.0), returns_only = fused_with_rays(true, boxes, {}, 0, false, 1.0),
               kept = fused_with_rays(false, boxes);
    const Box upper{{8.0, -3.9, 1.8}, {13.0, -2.1, 2.5}};
    const std::size_t before = triangles_in(kept, gone, 0.1, 0.3);
    ASSERT_GT(before, 300u);
    ASSERT_GT(triangles_in(returns_only, upper, 0.1), 50u) << "the returns alone leave the upper side";
    EXPECT_LE(triangles_in(carved, gone, 0.1, 0.3), before / 20) << "5 % at most of the van that left stays";
    EXPECT_LE(triangles_in(carved, upper, 0.1), triangles_in(returns_only, upper, 0.1) / 3);
    const std::size_t on_car = triangles_in(carved, stays, 0.1, 0.2), on_car_kept = triangles_in(kept, stays, 0.1, 0.2);
    ASSERT_GT(on_car_kept, 300u);
    EXPECT_GE(on_car, on_car_kept * 98 / 100);
    const Box pole{{kPoleX - 0.25, kPoleY - 0.25, 0.3}, {kPoleX + 0.25, kPoleY + 0.25, 5.5}};
    EXPECT_GE(triangles_in(carved, pole), triangles_in(kept, pole) * 98 / 100);
    const Box wall{{-5.0, kWallY - 0.2, 0.3}, {30.0, kWallY + 0.2, 5.0}};
    EXPECT_GE(triangles_in(carved, wall), triangles_in(kept, wall) * 98 / 100);
}

// The same van, returns only: the rays that return behind it carve its lower side, none sees
// through the upper one, and the cluster that is left, mostly carved, goes whole. The car that
// stays, the pole and the wall are not taken with it.
TEST(FreeSpace, TheRestOfAMostlyCarvedVanGoesWithIt) {
    const auto boxes = van_then_car;
    const Mesh clusters = fused_with_rays(true, boxes, {}, 0, false), no_clusters = fused_with_rays(true, boxes, {}, 0, false, 1.0),
               kept = fused_with_rays(false, boxes);
    const std::size_t before = triangles_in(kept, kVanGone, 0.1, 0.3);
    ASSERT_GT(before, 300u);
    ASSERT_GT(triangles_in(no_clusters, kVanGone, 0.1, 0.3), before / 10) << "without clusters, the upper side stays";
    EXPECT_LE(triangles_in(clusters, kVanGone, 0.1, 0.3), before / 20) << "5 % at most of the van that left stays";
    const std::size_t on_car_kept = triangles_in(kept, kCarStays, 0.1, 0.2);
    ASSERT_GT(on_car_kept, 300u);
    EXPECT_GE(triangles_in(clusters, kCarStays, 0.1, 0.2), on_car_kept * 98 / 100);
    const Box pole{{kPoleX - 0.25, kPoleY - 0.25, 0.3}, {kPoleX + 0.25, kPoleY + 0.25, 5.5}};
    EXPECT_GE(triangles_in(clusters, pole), triangles_in(kept, pole) * 98 / 100);
    const Box wall{{-5.0, kWallY - 0.2, 0.3}, {30.0, kWallY + 0.2, 5.0}};
    EXPECT_GE(triangles_in(clusters, wall), triangles_in(kept, wall) * 98 / 100);
    const Box ground{{-5.0, -8.0, -0.2}, {30.0, 8.0, 0.2}};
    EXPECT_GE(triangles_in(clusters, ground), triangles_in(kept, ground) * 98 / 100);
}

// A car parked all along whose hull returns nothing (too dark), its cabin returning, between the
// drive and the wall; 2 % of the returns lost at random: what the hull swallows and the lost rays
// carve nothing that stands (the cabin, the wall behind the car, the ground, the pole).
TEST(FreeSpace, ADarkCarTheWallBehindItAndRandomDropoutsStay) {
    const Box hull{{14.0, 2.1, 0.3}, {18.5, 3.9, 1.0}}, cabin{{15.0, 2.2, 1.0}, {17.5, 3.8, 1.45}};
    const auto boxes = [&](int) { return std::vector<Box>{cabin}; };
    const Mesh carved = fused_with_rays(true, boxes, {hull}, 0.02), kept = fused_with_rays(false, boxes, {hull}, 0.02);
    const std::size_t on_cabin = triangles_in(kept, cabin, 0.1, 1.05);
    ASSERT_GT(on_cabin, 100u);
    EXPECT_GE(triangles_in(carved, cabin, 0.1, 1.05), on_cabin * 98 / 100);
    const Box wall_behind{{8.0, kWallY - 0.2, 0.3}, {26.0, kWallY + 0.2, 4.0}};
    ASSERT_GT(triangles_in(kept, wall_behind), 300u);
    EXPECT_GE(triangles_in(carved, wall_behind), triangles_in(kept, wall_behind) * 98 / 100);
    const Box ground{{-5.0, -8.0, -0.2}, {30.0, 8.0, 0.2}};
    EXPECT_GE(triangles_in(carved, ground), triangles_in(kept, ground) * 98 / 100);
    const Box pole{{kPoleX - 0.25, kPoleY - 0.25, 0.3}, {kPoleX + 0.25, kPoleY + 0.25, 5.5}};
    EXPECT_GE(triangles_in(carved, pole), triangles_in(kept, pole) * 98 / 100);
}

// Two cars parked nose to tail, 0.6 m apart, then 0.2 m (their voxels touch: one cluster); the
// first leaves halfway: the other stays whole, in both, returns only or with the empty rays.
TEST(FreeSpace, OfTwoCarsParkedSideBySideTheOneThatStaysIsWhole) {
    for (const double gap : {0.6, 0.2}) {
        const Box leaves{{8.0, 2.1, 0.0}, {12.5, 3.9, 1.5}}, stays{{12.5 + gap, 2.1, 0.0}, {17.0 + gap, 3.9, 1.5}};
        const auto boxes = [&](int i) { return i < 20 ? std::vector<Box>{leaves, stays} : std::vector<Box>{stays}; };
        const Mesh kept = fused_with_rays(false, boxes);
        const std::size_t on_car = triangles_in(kept, stays, 0.1, 0.2);
        ASSERT_GT(on_car, 300u);
        for (const bool rays : {true, false}) {
            const Mesh carved = fused_with_rays(true, boxes, {}, 0, rays);
            EXPECT_GE(triangles_in(carved, stays, 0.1, 0.2), on_car * 98 / 100) << "gap " << gap << (rays ? ", empty rays" : ", returns only");
            if (gap > 0.5 && rays) {
                const Box where_it_stood{{8.0, 2.1, 0.3}, {12.3, 3.9, 1.6}};
                EXPECT_LE(triangles_in(carved, where_it_stood), triangles_in(kept, where_it_stood) / 20);
            }
        }
    }
}
