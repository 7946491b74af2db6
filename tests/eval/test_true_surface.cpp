#include <gtest/gtest.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/true_surface.hpp"

using namespace lidarsurf;

namespace {

// The square [x0, x1] x [0, 4] at height z as two triangles.
Mesh square(double x0, double x1, double z) {
    Mesh m;
    m.vertices = {{x0, 0, z}, {x1, 0, z}, {x1, 4, z}, {x0, 4, z}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}};
    return m;
}

// Ground-truth points on a 2 cm grid of the square [0, 4]^2 at z = 0 (cell centres).
std::vector<Eigen::Vector3d> gt_points() {
    std::vector<Eigen::Vector3d> g;
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 200; ++j) g.emplace_back(0.01 + 0.02 * i, 0.01 + 0.02 * j, 0.0);
    return g;
}

TEST(TrueSurface, TheTruthItselfIsPerfect) {
    const Mesh truth = square(0, 4, 0);
    const MeshDistance surface(truth);
    const TrueSurfaceMetrics m = evaluate_true_surface(truth, surface, gt_points(), EvaluationConfig{});
    EXPECT_GT(m.samples, 1000u);
    EXPECT_NEAR(m.error.mean, 0, 1e-12);
    EXPECT_NEAR(m.error.max, 0, 1e-12);
    EXPECT_NEAR(m.vertex_error.max, 0, 1e-12);
    EXPECT_NEAR(m.completeness.max, 0, 1e-12);
    EXPECT_DOUBLE_EQ(m.precision, 1);
    EXPECT_DOUBLE_EQ(m.recall, 1);
    EXPECT_DOUBLE_EQ(m.fscore, 1);
}

TEST(TrueSurface, AnOffsetMeshIsOffByTheOffsetInBothDirections) {
    const MeshDistance surface(square(0, 4, 0));
    const Mesh lifted = square(0, 4, 0.05);
    EvaluationConfig c;
    const TrueSurfaceMetrics m = evaluate_true_surface(lifted, surface, gt_points(), c);
    EXPECT_NEAR(m.error.mean, 0.05, 1e-9);
    EXPECT_NEAR(m.error.max, 0.05, 1e-9);
    EXPECT_NEAR(m.vertex_error.mean, 0.05, 1e-9);
    EXPECT_NEAR(m.completeness.median, 0.05, 1e-9);
    EXPECT_DOUBLE_EQ(m.fscore, 1);  // within 0.1 m
    c.threshold = 0.04;
    const TrueSurfaceMetrics strict = evaluate_true_surface(lifted, surface, gt_points(), c);
    EXPECT_DOUBLE_EQ(strict.precision, 0);
    EXPECT_DOUBLE_EQ(strict.recall, 0);
    EXPECT_DOUBLE_EQ(strict.fscore, 0);
}

TEST(TrueSurface, HalfAMeshHasHalfTheRecallAndFullPrecision) {
    const MeshDistance surface(square(0, 4, 0));
    const TrueSurfaceMetrics m = evaluate_true_surface(square(0, 2, 0), surface, gt_points(), EvaluationConfig{});
    EXPECT_DOUBLE_EQ(m.precision, 1);
    // GT points with x <= 2.1 are within 0.1 m of the half square: 105 of 200 columns.
    EXPECT_NEAR(m.recall, 105.0 / 200.0, 1e-12);
    EXPECT_NEAR(m.fscore, 2 * m.recall / (1 + m.recall), 1e-12);
    // A GT point at x = 3.99 is 1.99 m from the half square.
    EXPECT_NEAR(m.completeness.max, 1.99, 1e-9);
}

TEST(TrueSurface, EvaluateGivesTheSameMetricsFromItsOwnSamples) {
    // evaluate(..., truth) reuses protocol 2's samples and GT-to-mesh distances: same numbers as
    // the stand-alone evaluation (sums may differ in the last bits by order).
    const MeshDistance surface(square(0, 4, 0));
    const Mesh half = square(0, 2, 0.05);
    EvaluationConfig c;
    c.max_range = 3.0;
    const TrueSurfaceMetrics a = evaluate_true_surface(half, surface, gt_points(), c);
    const EvaluationResult r = evaluate(half, gt_points(), c, surface);
    ASSERT_TRUE(r.truth.has_value());
    EXPECT_FALSE(evaluate(half, gt_points(), c).truth.has_value());
    const TrueSurfaceMetrics& b = *r.truth;
    EXPECT_EQ(a.samples, b.samples);
    EXPECT_NEAR(a.error.mean, b.error.mean, 1e-12);
    EXPECT_NEAR(a.vertex_error.mean, b.vertex_error.mean, 1e-12);
    EXPECT_NEAR(a.completeness.mean, b.completeness.mean, 1e-12);
    EXPECT_NEAR(a.completeness.p90, b.completeness.p90, 1e-12);
    EXPECT_DOUBLE_EQ(a.precision, b.precision);
    EXPECT_DOUBLE_EQ(a.recall, b.recall);
    EXPECT_DOUBLE_EQ(a.fscore, b.fscore);
}

TEST(TrueSurface, RangeCropAndBadInput) {
    const MeshDistance surface(square(0, 4, 0));
    EvaluationConfig c;
    c.origin = Eigen::Vector3d(0, 0, 0);
    c.max_range = 1.0;  // only the corner near the origin
    const TrueSurfaceMetrics m = evaluate_true_surface(square(0, 4, 0.05), surface, gt_points(), c);
    EXPECT_NEAR(m.error.mean, 0.05, 1e-9);
    EXPECT_LT(m.samples, 2000u);  // ~pi/4 m^2 of 16 m^2 at one sample per 25 cm^2: ~314
    EXPECT_THROW(evaluate_true_surface(Mesh{}, surface, gt_points(), EvaluationConfig{}), InvalidInput);
    c.origin = Eigen::Vector3d(100, 100, 100);
    EXPECT_THROW(evaluate_true_surface(square(0, 4, 0), surface, gt_points(), c), InvalidInput);
}

}  // namespace
