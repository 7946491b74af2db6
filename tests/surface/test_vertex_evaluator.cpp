#include <gtest/gtest.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/core/packed_voxels.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"
#include "test_util.hpp"

#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>

using namespace lidarsurf;

namespace {

// Crafted world (alpha = 0.2, local origin at 0): points on the plane z = 0.05, sensor above.
//  - strip A: 10x5 points in voxel (0,0,0), x in [0.01, 0.19], y in [0.13, 0.19]: 50 points,
//    narrow in y (lambda2 = 4.5e-4, lambda2/lambda1 = 0.14: still a plane) and 0.16 m from vertex
//    (0,0,0) along y, so its Gaussian rejects the vertex (Mahalanobis^2 ~ 60) although
//    |H^1| = 50 >= N_min.
//  - strip B: 40x5 points in voxels (-2..1,-2,0), x in [-0.39, 0.39], y in [-0.39, -0.36]: only
//    H^2 and larger see it. H^2 then spreads ~0.2 m in both x and y (lambda2/lambda1 ~ 0.9) around
//    (0.02, -0.27), and the vertex lies inside its Gaussian (pdf ~ 1.6 >> tau).
VoxelGrid crafted_grid() {
    VoxelGrid fresh(0.2, Eigen::Vector3d::Zero());
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 5; ++j) fresh.insert({0.01 + 0.02 * i, 0.13 + 0.015 * j, 0.05});
    for (int i = 0; i < 40; ++i)
        for (int j = 0; j < 5; ++j) fresh.insert({-0.39 + 0.02 * i, -0.39 + 0.0075 * j, 0.05});
    return fresh;
}

SurfaceConfig config_for(Mode mode, int k) {
    SurfaceConfig c;
    c.mode = mode;
    c.k = k;
    c.validate();
    return c;
}

const Eigen::Vector3d kSensor(0.1, 0.0, 10.0);

TEST(VertexEvaluator, CraftedLocalOriginIsTheWorldOrigin) {
    const VoxelGrid g = crafted_grid();
    EXPECT_EQ(g.origin(), Eigen::Vector3d::Zero());
    EXPECT_EQ(g.size(), 5u);
}

TEST(VertexEvaluator, EachModeChoosesTheExpectedLevel) {
    const VoxelGrid g = crafted_grid();
    const VoxelKey v(0, 0, 0);
    const VertexSample angc = evaluate_vertex(g, v, config_for(Mode::AdaptiveGaussian, 5), kSensor);
    ASSERT_TRUE(angc.defined);
    EXPECT_EQ(angc.level, 2);  // GC rejects H^1 (strip A alone), accepts H^2
    const VertexSample an = evaluate_vertex(g, v, config_for(Mode::Adaptive, 5), kSensor);
    ASSERT_TRUE(an.defined);
    EXPECT_EQ(an.level, 1);  // Eq. (1) alone is met at k = 1
    EXPECT_FALSE(evaluate_vertex(g, v, config_for(Mode::ConstantGaussian, 1), kSensor).defined);
    const VertexSample cngc2 = evaluate_vertex(g, v, config_for(Mode::ConstantGaussian, 2), kSensor);
    ASSERT_TRUE(cngc2.defined);
    EXPECT_EQ(cngc2.level, 2);
    const VertexSample cn1 = evaluate_vertex(g, v, config_for(Mode::Constant, 1), kSensor);
    ASSERT_TRUE(cn1.defined);
    EXPECT_EQ(cn1.level, 1);
}

TEST(VertexEvaluator, TsdfIsSignedDistanceToThePlane) {
    const VoxelGrid g = crafted_grid();
    // All points lie on z = 0.05 and the sensor is above: n = +z, TSDF(v) = v_z - 0.05.
    for (int z = -1; z <= 2; ++z) {
        const VertexSample s = evaluate_vertex(g, {0, 0, z}, config_for(Mode::Adaptive, 5), kSensor);
        ASSERT_TRUE(s.defined) << z;
        EXPECT_NEAR(s.tsdf, 0.2 * z - 0.05, 1e-6);
        EXPECT_NEAR(s.normal.z(), 1.0f, 1e-6f);
    }
}

TEST(VertexEvaluator, NoPointsWithinKMaxLeavesTheVertexUndefined) {
    const VoxelGrid g = crafted_grid();
    EXPECT_FALSE(evaluate_vertex(g, {20, 0, 0}, config_for(Mode::Adaptive, 5), kSensor).defined);
    // N_min above the number of points: never defined.
    SurfaceConfig c = config_for(Mode::Adaptive, 5);
    c.n_min = 251;  // 250 points in all
    EXPECT_FALSE(evaluate_vertex(g, {0, 0, 0}, c, kSensor).defined);
}

TEST(VertexEvaluator, ThicknessGuardRejectsAStepAndKeepsANoisyPlane) {
    // A level's merged statistics of two parallel planes h apart, half the points on each: the
    // spread across them is sqrt(lambda3) = h / 2 (direct oracle below). The guard at t voxels
    // rejects it when h / 2 > t * alpha and keeps a single plane with 2 cm noise.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.4, 0.4);
    std::normal_distribution<double> noise(0.0, 0.02);
    auto stats_of = [&](double h, double sigma) {
        VoxelStats st;
        std::vector<Eigen::Vector3d> pts;
        for (int i = 0; i < 400; ++i) {
            const Eigen::Vector3d p(u(rng), u(rng), (i % 2 ? h : 0.0) + (sigma > 0 ? noise(rng) : 0.0));
            st.add(p);
            pts.push_back(p);
        }
        const auto direct = test::direct_stats(pts);
        return std::make_pair(st, std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(direct.cov).eigenvalues()[0]));
    };
    SurfaceConfig c;  // alpha 0.2, max_thickness 0.6 voxels = 0.12 m
    const Eigen::Vector3d v(0, 0, 0.1), sensor(0, 0, 5);
    const auto [step, step_thickness] = stats_of(0.3, 0);
    EXPECT_NEAR(step_thickness, 0.15, 5e-3);  // h / 2, less a slight tilt the random x, y allow
    EXPECT_FALSE(evaluate_level(step, 2, v, c, sensor, degenerate_lambda2(0.2), EigenSolver::Iterative).defined);
    const auto [flat, flat_thickness] = stats_of(0.0, 0.02);
    EXPECT_LT(flat_thickness, 0.03);
    EXPECT_TRUE(evaluate_level(flat, 2, v, c, sensor, degenerate_lambda2(0.2), EigenSolver::Iterative).defined);
    // Off (0), as in the paper: the step is a plane like any other.
    c.max_thickness = 0;
    EXPECT_TRUE(evaluate_level(step, 2, v, c, sensor, degenerate_lambda2(0.2), EigenSolver::Iterative).defined);
    // Just above and below the measured thickness.
    c.max_thickness = 1.05 * step_thickness / 0.2;
    EXPECT_TRUE(evaluate_level(step, 2, v, c, sensor, degenerate_lambda2(0.2), EigenSolver::Iterative).defined);
    c.max_thickness = 0.95 * step_thickness / 0.2;
    EXPECT_FALSE(evaluate_level(step, 2, v, c, sensor, degenerate_lambda2(0.2), EigenSolver::Iterative).defined);
}

// A crafted street (alpha = 0.2, local origin 0): two scan rings on the ground z = 0.05, lines
// along y at x = 0.05 and 1.25, and the side of a car body in the plane x = 0.9, z in [0.45, 1.5].
VoxelGrid crafted_street() {
    VoxelGrid g(0.2, Eigen::Vector3d::Zero());
    for (int i = 0; i <= 200; ++i)
        for (double x : {0.05, 1.25}) g.insert({x, -2.0 + 0.02 * i, 0.05});
    for (int i = 0; i <= 40; ++i)
        for (int j = 0; j <= 21; ++j) g.insert({0.9, -1.0 + 0.05 * i, 0.45 + 0.05 * j});
    return g;
}

// The slab fallback on a crafted street (alpha = 0.2, local origin 0, sensor at (-3, 0, 1.7)):
// two scan rings on the ground z = 0.05, lines along y at x = 0.05 and 1.25 (1.2 m apart, as
// rings some 15 m from an HDL-64), and the side of a raised object (a car body) in the plane
// x = 0.9, z in [0.45, 1.5]. Vertex v = (3, 0, 1), at (0.6, 0, 0.2), lies 0.15 m above the
// ground between the rings, under the car's edge. Its cubes: H^1 empty; H^2 a strip of the car
// only (a line: no plane); H^3..H^5 the car with one or both rings (no plane, or an oblique one across
// the ground and the car). Its slabs
// (z in [0, 0.4)) never reach the car: S^3 holds one ring (a line), S^4 both, so with the
// fallback v is defined at level 4 by the ground's plane: TSDF 0.15 m, normal +z.
TEST(VertexEvaluator, SlabFallbackFindsTheGroundBesideARaisedObject) {
    const VoxelGrid g = crafted_street();
    const VoxelKey v(3, 0, 1);
    const Eigen::Vector3d sensor(-3.0, 0.0, 1.7);
    SurfaceConfig c;  // the default: slab fallback from level 3, here with square slabs
    c.slab_radial_extension = 0;
    const VertexSample s = evaluate_vertex(g, v, c, sensor);
    ASSERT_TRUE(s.defined);
    EXPECT_EQ(s.level, 4);
    EXPECT_NEAR(s.tsdf, 0.15, 1e-6);
    EXPECT_NEAR(s.normal.z(), 1.0f, 1e-5f);
    // The fast path's windowed evaluation agrees, with either eigen solver.
    const PackedVoxels packed(g);
    const NeighbourhoodWindow window(packed, BlockMap<std::int32_t>::block_of(v), c.max_reach());
    for (EigenSolver solver : {EigenSolver::Iterative, EigenSolver::ClosedForm}) {
        const VertexSample fast = evaluate_vertex(window, v, c, sensor, solver);
        ASSERT_TRUE(fast.defined);
        EXPECT_EQ(fast.level, 4);
        EXPECT_NEAR(fast.tsdf, 0.15, 1e-6);
    }
    // Without the fallback, H^3 (ring 0 and the car's lowest 0.35 m) passes the guards with a plane
    // across both: oblique, and on the wrong side of v (true TSDF +0.15 m).
    c.slab_from_level = 0;
    for (const VertexSample& o : {evaluate_vertex(g, v, c, sensor), evaluate_vertex(window, v, c, sensor, EigenSolver::ClosedForm)}) {
        ASSERT_TRUE(o.defined);
        EXPECT_EQ(o.level, 3);
        EXPECT_LT(o.normal.z(), std::cos(20.0 * 3.141592653589793 / 180.0));
        EXPECT_LT(o.tsdf, 0.0f);
    }
    // From level 5 on, S^5 (both rings) defines it at level 5; the cubes H^3, H^4 are not tried.
    c.slab_from_level = 5;
    const VertexSample late = evaluate_vertex(g, v, c, sensor);
    ASSERT_TRUE(late.defined);
    EXPECT_EQ(late.level, 5);
    EXPECT_NEAR(late.tsdf, 0.15, 1e-6);
    // No slab level within k_max: v keeps trying cubes, as without the fallback.
    c.slab_from_level = 6;
    const VertexSample none = evaluate_vertex(g, v, c, sensor);
    ASSERT_TRUE(none.defined);
    EXPECT_EQ(none.level, 3);
    EXPECT_LT(none.tsdf, 0.0f);
    // The constant modes have one level: no fallback.
    c = SurfaceConfig{};
    c.mode = Mode::ConstantGaussian;
    c.k = 4;
    EXPECT_FALSE(evaluate_vertex(g, v, c, sensor).defined);
}

// Radial slabs on the same street. The sensor at (-3, 0, 1.7) sees v along x, across the rings:
// with an extension of 3 voxels (the session-11 default), S^3 spans x in [-0.6, 1.8) and holds
// both rings, so v is defined one level earlier than with square slabs. Seen along y instead (sensor at
// (0.6, -5, 1.7)), the slabs extend along the rings, S^3 holds one ring (a line) and v is defined
// at level 4 as with square slabs. Both paths agree.
TEST(VertexEvaluator, RadialSlabsReachTheNextRingAcrossTheScanLines) {
    const VoxelGrid g = crafted_street();
    const VoxelKey v(3, 0, 1);
    const Eigen::Vector3d position(0.6, 0.0, 0.2);
    SurfaceConfig c;
    c.slab_radial_extension = 3;
    c.bridge_reach = 0;  // the slabs alone
    const PackedVoxels packed(g);
    const NeighbourhoodWindow window(packed, BlockMap<std::int32_t>::block_of(v), c.max_reach());
    ASSERT_EQ(c.max_reach(), c.k_max + 3);
    struct Case {
        Eigen::Vector3d sensor;
        int level;
    };
    for (const Case& k : {Case{{-3.0, 0.0, 1.7}, 3}, Case{{0.6, -5.0, 1.7}, 4}}) {
        const SlabExtension e = radial_extension(position, k.sensor, c.slab_radial_extension);
        EXPECT_EQ(e.x, k.level == 3 ? 3 : 0);
        EXPECT_EQ(e.y, k.level == 3 ? 0 : 3);
        for (const VertexSample& s : {evaluate_vertex(g, v, c, k.sensor), evaluate_vertex(window, v, c, k.sensor, EigenSolver::Iterative),
                                      evaluate_vertex(window, v, c, k.sensor, EigenSolver::ClosedForm)}) {
            ASSERT_TRUE(s.defined) << k.sensor.transpose();
            EXPECT_EQ(s.level, k.level) << k.sensor.transpose();
            EXPECT_NEAR(s.tsdf, 0.15, 1e-6);
            EXPECT_NEAR(s.normal.z(), 1.0f, 1e-5f);
        }
    }
}

// Bridges on a crafted ground (alpha = 0.2, local origin 0, sensor at (-10, 0.1, 1.7)): two scan
// rings, lines along y on the plane z = 0.05 + 0.1 x (a 5.7 degree slope) at x = 0.05 and 5.05,
// 5 m apart as the rings of a VLP-16 some 15 m out. Vertex v = (13, 0, 2), at (2.6, 0, 0.4), lies
// midway, 2.5 m from either ring: beyond every cube and slab (H^5 and the radial slabs reach
// 2.6 m but never both rings), so no level defines it. Its bridge boxes (x in [-1.6, 2.6) and
// [2.6, 8.6), y in [-1, 1), z in [0, 0.8)) hold one ring each: defined by their plane, with the
// exact signed distance (0.4 - 0.31) cos(5.7 deg) and a confidence below tau.
TEST(VertexEvaluator, BridgesJoinTwoRingsThatAgree) {
    const Eigen::Vector3d sensor(-10.0, 0.1, 1.7);
    auto ground_z = [](double x) { return 0.05 + 0.1 * x; };
    auto street = [&](bool second_ring_raised, bool one_line) {
        VoxelGrid g(0.2, Eigen::Vector3d::Zero());
        for (int i = 0; i <= 200; ++i) {
            const double y = -2.0 + 0.02 * i;
            if (one_line) {  // one ring crossing both boxes instead: a line along x
                g.insert({-1.5 + 0.05 * i, 0.3, ground_z(-1.5 + 0.05 * i)});
                continue;
            }
            g.insert({0.05, y, ground_z(0.05)});
            g.insert({5.05, y, ground_z(5.05) + (second_ring_raised ? 0.3 : 0.0)});
        }
        return g;
    };
    const VoxelKey v(13, 0, 2);
    const Eigen::Vector3d position = v.cast<double>() * 0.2;
    const Eigen::Vector3d n = Eigen::Vector3d(-0.1, 0, 1).normalized();
    const double truth = n.dot(position - Eigen::Vector3d(0, 0, ground_z(0)));
    SurfaceConfig c;
    auto both_paths = [&](const VoxelGrid& g, const SurfaceConfig& config) {
        const PackedVoxels packed(g);
        const NeighbourhoodWindow window(packed, BlockMap<std::int32_t>::block_of(v), config.max_reach());
        return std::array<VertexSample, 3>{evaluate_vertex(g, v, config, sensor), evaluate_vertex(window, v, config, sensor, EigenSolver::Iterative),
                                           evaluate_vertex(window, v, config, sensor, EigenSolver::ClosedForm)};
    };
    for (const VertexSample& s : both_paths(street(false, false), c)) {
        ASSERT_TRUE(s.defined);
        EXPECT_NEAR(s.tsdf, truth, 1e-6);
        EXPECT_NEAR(s.normal.z(), n.z(), 1e-6);
        EXPECT_LT(s.confidence, c.tau) << "a bridge is inferred surface";
        EXPECT_GT(s.confidence, 0.0f);
    }
    // Without bridges, or in AN (no Eq. (3) to mark the inferred surface), nothing defines v.
    SurfaceConfig off = c;
    off.bridge_reach = 0;
    for (const VertexSample& s : both_paths(street(false, false), off)) EXPECT_FALSE(s.defined);
    off = c;
    off.mode = Mode::Adaptive;
    for (const VertexSample& s : both_paths(street(false, false), off)) EXPECT_FALSE(s.defined);
    // Too short a reach: the far ring is not in the far box.
    off = c;
    off.bridge_reach = 6;  // x up to 2.6 + (5 + 6) 0.2 = 4.8 m
    for (const VertexSample& s : both_paths(street(false, false), off)) EXPECT_FALSE(s.defined);
    // Rings that disagree (the far one 0.3 m above the slope: a curb, an object's foot) are not
    // one surface; one ring crossing both boxes is a line.
    for (const VertexSample& s : both_paths(street(true, false), c)) EXPECT_FALSE(s.defined);
    for (const VertexSample& s : both_paths(street(false, true), c)) EXPECT_FALSE(s.defined);
    // A grid fused from viewpoints (a map) has no bridges.
    VoxelGrid fused = street(false, false);
    fused.enable_viewpoints(sensor);
    EXPECT_FALSE(evaluate_vertex(fused, v, c, sensor).defined);
}

TEST(Config, PaperTurnsEveryGuardOff) {
    for (Mode mode : {Mode::AdaptiveGaussian, Mode::Adaptive, Mode::ConstantGaussian, Mode::Constant}) {
        const SurfaceConfig p = SurfaceConfig::paper(mode);
        EXPECT_NO_THROW(p.validate());
        EXPECT_EQ(p.mode, mode);
        EXPECT_EQ(p.min_planarity, 0);
        EXPECT_EQ(p.max_thickness, 0);
        EXPECT_EQ(p.slab_from_level, 0);
        EXPECT_EQ(p.bridge_reach, 0);
        EXPECT_EQ(p.truncation_voxels, 0);
        EXPECT_FALSE(p.seeded_surface);
        EXPECT_FALSE(p.snap_to_plane);
        EXPECT_EQ(p.min_component_triangles, 0);
        // The paper's parameters are untouched.
        EXPECT_EQ(p.voxel_size, 0.2);
        EXPECT_EQ(p.tau, 0.2);
        EXPECT_EQ(p.n_min, 10);
        EXPECT_EQ(p.k_max, 5);
    }
    SurfaceConfig c;
    c.voxel_size = 0.1;
    c.make_paper_literal();
    EXPECT_EQ(c.voxel_size, 0.1);
    EXPECT_FALSE(c.snap_to_plane);
}

TEST(Config, ValidateRejectsAbsurdParameters) {
    SurfaceConfig ok;
    EXPECT_NO_THROW(ok.validate());
    auto bad = [](auto mutate) {
        SurfaceConfig c;
        mutate(c);
        return c;
    };
    EXPECT_THROW(bad([](auto& c) { c.voxel_size = 0; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.voxel_size = std::nan(""); }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.tau = 0; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.tau = -1; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.n_min = 0; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.k_max = 0; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.k_max = 1000; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.k = 0; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.max_thickness = -0.1; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.max_thickness = std::nan(""); }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.min_component_triangles = -1; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.slab_from_level = 1; }).validate(), InvalidArgument);  // H^1 failing is the single ring
    EXPECT_THROW(bad([](auto& c) { c.slab_from_level = -1; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.slab_from_level = 33; }).validate(), InvalidArgument);
    EXPECT_NO_THROW(bad([](auto& c) { c.slab_from_level = 0; }).validate());
    EXPECT_THROW(bad([](auto& c) { c.slab_radial_extension = -1; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.slab_radial_extension = 33; }).validate(), InvalidArgument);
    EXPECT_NO_THROW(bad([](auto& c) { c.slab_radial_extension = 0; }).validate());
    EXPECT_THROW(bad([](auto& c) { c.bridge_reach = -1; }).validate(), InvalidArgument);
    EXPECT_THROW(bad([](auto& c) { c.bridge_reach = 65; }).validate(), InvalidArgument);
    EXPECT_NO_THROW(bad([](auto& c) { c.bridge_reach = 0; }).validate());
    // The neighbourhoods' reach: the bridges' in AN+GC, the slabs' extension only where slabs are
    // tried; k_max + the bridges' reach is capped at the windows' 64 voxels.
    SurfaceConfig r;
    EXPECT_EQ(r.max_reach(), r.k_max + r.bridge_reach);
    r.bridge_reach = 64;
    EXPECT_EQ(r.bridge_extent(), 64 - r.k_max);
    EXPECT_EQ(r.max_reach(), 64);
    r.mode = Mode::Adaptive;  // bridges are AN+GC's (their confidence is below tau)
    EXPECT_FALSE(r.bridges());
    EXPECT_EQ(r.max_reach(), r.k_max + r.slab_radial_extension);
    r.mode = Mode::AdaptiveGaussian;
    r.bridge_reach = 0;
    EXPECT_EQ(r.max_reach(), r.k_max + r.slab_radial_extension);
    r.slab_from_level = 0;
    EXPECT_EQ(r.max_reach(), r.k_max);
    r = SurfaceConfig{};
    r.mode = Mode::ConstantGaussian;
    EXPECT_EQ(r.max_reach(), r.k);
    EXPECT_EQ(SurfaceConfig::paper().max_reach(), SurfaceConfig::paper().k_max);
    EXPECT_EQ(parse_mode("AN+GC"), Mode::AdaptiveGaussian);
    EXPECT_EQ(parse_mode("cn"), Mode::Constant);
    EXPECT_THROW(parse_mode("imls"), InvalidArgument);
    // The defaults are the paper's (Sec. IV-A).
    EXPECT_EQ(ok.voxel_size, 0.2);
    EXPECT_EQ(ok.tau, 0.2);
    EXPECT_EQ(ok.n_min, 10);
    EXPECT_EQ(ok.k_max, 5);
    EXPECT_EQ(ok.mode, Mode::AdaptiveGaussian);
}

}  // namespace

// The fast path's invariant pre-check against the eigenvalues (the oracle): on random
// covariances from lines to blobs, whatever it rejects the eigenvalue tests reject too, and it
// does reject most clear lines and clearly thick blobs (so it is not a no-op).
TEST(VertexEvaluator, InvariantPreCheckOnlyRejectsWhatTheEigenvaluesReject) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> angle(0.0, 6.283185307179586), unit(0.0, 1.0);
    SurfaceConfig c;  // default guards: planarity 0.05, thickness 0.6 voxels
    const double t2 = std::pow(c.max_thickness * c.voxel_size, 2);
    int rejected = 0, lines = 0, lines_rejected = 0;
    for (int i = 0; i < 20000; ++i) {
        // Random orientation, eigenvalues spanning 1e-6 .. 1 m^2 with every ratio.
        const Eigen::Matrix3d q = (Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitY()) *
                                   Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitX())).toRotationMatrix();
        const double l1 = std::pow(10.0, -3.0 * unit(rng)), l2 = l1 * std::pow(10.0, -4.0 * unit(rng)), l3 = l2 * std::pow(10.0, -4.0 * unit(rng));
        VoxelStats s;
        s.count = 50;
        s.scatter = SymmetricMatrix3::upper_of(50.0 * q * Eigen::Vector3d(l1, l2, l3).asDiagonal() * q.transpose());
        const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(s.covariance()).eigenvalues();
        const bool exact = ev[1] < c.min_planarity * ev[2] || ev[0] > t2;
        const bool pre = rejected_by_invariants(s, c);
        if (pre) {
            ++rejected;
            ASSERT_TRUE(exact) << "l = " << l1 << " " << l2 << " " << l3;
        }
        if (l2 < 0.002 * l1) {
            ++lines;
            lines_rejected += pre;
        }
    }
    EXPECT_GT(rejected, 1000);
    EXPECT_GT(lines_rejected, lines * 9 / 10);
    // Guards off (the paper's modes): never rejects.
    VoxelStats blob;
    blob.count = 50;
    blob.scatter = SymmetricMatrix3::upper_of(50.0 * Eigen::Matrix3d(Eigen::Vector3d(1.0, 1e-9, 1e-9).asDiagonal()));
    EXPECT_TRUE(rejected_by_invariants(blob, c));
    EXPECT_FALSE(rejected_by_invariants(blob, SurfaceConfig::paper(Mode::AdaptiveGaussian)));
}
