#include <gtest/gtest.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"

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

ReconstructionConfig config_for(Mode mode, int k) {
    ReconstructionConfig c;
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
    ReconstructionConfig c = config_for(Mode::Adaptive, 5);
    c.n_min = 251;  // 250 points in all
    EXPECT_FALSE(evaluate_vertex(g, {0, 0, 0}, c, kSensor).defined);
}

TEST(Config, ValidateRejectsAbsurdParameters) {
    ReconstructionConfig ok;
    EXPECT_NO_THROW(ok.validate());
    auto bad = [](auto mutate) {
        ReconstructionConfig c;
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
