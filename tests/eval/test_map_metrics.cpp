// The map protocol on meshes whose answers are known by construction: the truth itself, the truth
// plus a ghost quad of known area, the truth with a hole.
#include <gtest/gtest.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/map_metrics.hpp"

using namespace lidarsurf;

namespace {

// A flat square [x0, x1] x [y0, y1] at height z, as two triangles appended to `m`.
void quad(Mesh& m, double x0, double x1, double y0, double y1, double z) {
    const auto base = static_cast<std::uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}});
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
}

// The ground truth: a grid of points on the truth quad, 0.1 m apart.
std::vector<Eigen::Vector3d> gt_points() {
    std::vector<Eigen::Vector3d> gt;
    for (double x = -19.95; x < 20; x += 0.1)
        for (double y = -9.95; y < 10; y += 0.1) gt.emplace_back(x, y, 0.0);
    return gt;
}

// The truth: the 40 x 20 m quad, its distance field, the crop of a drive along it.
Mesh flat_truth() {
    Mesh truth;
    quad(truth, -20, 20, -10, 10, 0.0);
    return truth;
}

struct FlatStreet {
    Mesh truth = flat_truth();
    MeshDistance distance{truth};
    DriveCrop crop{{{-20, 0, 1.7}, {20, 0, 1.7}}, 30.0};
};

}  // namespace

TEST(MapMetrics, TruthScoresPerfectAGhostQuadCountsItsAreaAHoleCostsRecall) {
    const FlatStreet street;
    const Mesh& truth = street.truth;
    const MeshDistance& distance = street.distance;
    const DriveCrop& crop = street.crop;
    MapGroundTruth builder(distance, crop, 0.1);
    std::vector<Eigen::Vector3d> scan = gt_points();
    scan.emplace_back(0, 0, 1.0);  // a point on a moving object: not on the static scene, dropped
    builder.add(scan);
    builder.add(scan);  // the same cells again: kept once
    const std::vector<Eigen::Vector3d> gt = builder.points();
    EXPECT_EQ(gt.size(), gt_points().size());
    MapEvaluationConfig config;
    config.sample_spacing = 0.1;

    const MapMetrics perfect = evaluate_map(truth, distance, gt, crop, config);
    EXPECT_DOUBLE_EQ(perfect.precision, 1.0);
    EXPECT_DOUBLE_EQ(perfect.recall, 1.0);
    EXPECT_NEAR(perfect.mesh_area, 800.0, 1e-6);
    EXPECT_EQ(perfect.ghost_area, 0.0);
    // A 4 x 2 m ghost 1 m above the ground: 8 m^2 of ghost in 808 m^2 (sampling: a few per cent).
    Mesh ghost = truth;
    quad(ghost, 0, 4, 1, 3, 1.0);
    const MapMetrics g = evaluate_map(ghost, distance, gt, crop, config);
    EXPECT_NEAR(g.ghost_area, 8.0, 0.5);
    EXPECT_NEAR(g.ghost_share(), 8.0 / 808.0, 0.001);
    EXPECT_NEAR(g.precision, 800.0 / 808.0, 0.001);
    EXPECT_DOUBLE_EQ(g.recall, 1.0);
    // Only half of the truth meshed: recall about one half, precision 1; the cut edge is a boundary.
    Mesh half;
    quad(half, -20, 0, -10, 10, 0.0);
    const MapMetrics h = evaluate_map(half, distance, gt, crop, config);
    EXPECT_NEAR(h.recall, 0.5, 0.01);
    EXPECT_DOUBLE_EQ(h.precision, 1.0);
    ASSERT_EQ(h.boundary_by_height.size(), 4u);
    EXPECT_EQ(h.boundary_by_height[0].boundary_edges, 4u);  // the square's four sides, on the ground
    EXPECT_EQ(h.boundary_by_height[0].edges, 5u);           // and its diagonal
    // The crop: a drive 100 m away sees nothing of the map.
    const DriveCrop far({{0, 200, 0}}, 30.0);
    EXPECT_THROW(evaluate_map(truth, distance, gt, far, config), InvalidInput);
}

// The ghost on the movers' paths: a car's boxes at two frames hold one of two ghost quads; only
// that one counts, whole.
TEST(MapMetrics, TheGhostOnTheMoversPathsIsTheGhostInsideTheirBoxes) {
    const FlatStreet street;
    const Mesh& truth = street.truth;
    const MeshDistance& distance = street.distance;
    const DriveCrop& crop = street.crop;
    MapEvaluationConfig config;
    config.sample_spacing = 0.1;
    Mesh ghost = truth;
    quad(ghost, 0, 4, 1, 3, 1.0);     // on the path: inside the car's boxes
    quad(ghost, -10, -8, 5, 7, 1.0);  // elsewhere: 4 m^2 of ghost off the path
    SweptVolume swept(0.2);
    for (double x : {0.0, 2.0}) {  // the car at two frames: its floor and roof, 2 x 2 m, joined into one part
        Mesh frame;
        quad(frame, x, x + 2, 1, 3, 0.3);
        quad(frame, x, x + 2, 1, 3, 1.5);
        frame.triangles.push_back({0, 4, 5});
        swept.add(frame);
    }
    EXPECT_EQ(swept.boxes(), 2u);
    EXPECT_TRUE(swept.contains({1.0, 2.0, 1.0}));
    EXPECT_TRUE(swept.contains({4.1, 2.0, 1.6}));   // within the pad
    EXPECT_FALSE(swept.contains({4.1, 2.0, 1.8}));  // above it
    EXPECT_FALSE(swept.contains({-9.0, 6.0, 1.0}));
    const MapMetrics with = evaluate_map(ghost, distance, gt_points(), crop, config, &swept);
    EXPECT_NEAR(with.ghost_area, 12.0, 0.6);
    EXPECT_NEAR(with.path_ghost_area, 8.0, 0.5);
    EXPECT_EQ(evaluate_map(ghost, distance, gt_points(), crop, config).path_ghost_area, 0.0);
    EXPECT_THROW(SweptVolume(-1.0), InvalidArgument);
}
