// Evaluation metrics: known answers (parallel planes, identical sets) and brute-force oracles.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/eval/report.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"

using namespace lidarsurf;

namespace {

// A flat square grid mesh at height z: (n+1)^2 vertices `step` apart, 2 n^2 triangles.
Mesh grid_mesh(int n, double step, double z) {
    Mesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) m.vertices.emplace_back(i * step, j * step, z);
    auto id = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
            m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return m;
}

double brute_nearest(const Eigen::Vector3d& q, const std::vector<Eigen::Vector3d>& set) {
    double best = 1e300;
    for (const auto& p : set) best = std::min(best, (p - q).norm());
    return best;
}

}  // namespace

TEST(Metrics, ParallelPlanesATenthApartGiveAeOfATenth) {
    const Mesh mesh = grid_mesh(20, 0.1, 0.0);
    std::vector<Eigen::Vector3d> gt;
    for (const auto& v : mesh.vertices) gt.push_back(v + Eigen::Vector3d(0, 0, 0.1));
    EvaluationConfig cfg;
    cfg.origin = {1, 1, 5};
    const EvaluationResult r = evaluate(mesh, gt, cfg);
    EXPECT_NEAR(r.vertex.p_to_gt.mean, 0.1, 1e-12);
    EXPECT_NEAR(r.vertex.p_to_gt.max, 0.1, 1e-12);
    EXPECT_NEAR(r.vertex.gt_to_p.mean, 0.1, 1e-12);
    EXPECT_NEAR(r.vertex.ae_sym, 0.1, 1e-12);
    EXPECT_NEAR(r.vertex.hd_sym, 0.1, 1e-12);
    EXPECT_DOUBLE_EQ(r.vertex.share_within_delta, 1.0);  // delta 0.2
    EXPECT_NEAR(r.surface.completeness, 0.1, 1e-12);     // exact distance to the plane
    EXPECT_NEAR(r.surface.gt_to_surface.max, 0.1, 1e-12);
    EXPECT_GE(r.surface.accuracy, 0.1 - 1e-12);          // a sample is at least 0.1 from GT
    EXPECT_LE(r.surface.accuracy, std::hypot(0.1, 0.05 * std::sqrt(2.0)) + 1e-12);
    EXPECT_DOUBLE_EQ(r.surface.recall, 1.0);             // threshold 0.1 is inclusive
}

TEST(Metrics, MeshEqualToGroundTruthScoresZeroError) {
    const Mesh mesh = grid_mesh(20, 0.1, 1.0);  // every surface point within 0.071 m of a vertex
    const EvaluationResult r = evaluate(mesh, mesh.vertices, EvaluationConfig{});
    EXPECT_EQ(r.vertex.p_to_gt.mean, 0.0);
    EXPECT_EQ(r.vertex.gt_to_p.max, 0.0);
    EXPECT_EQ(r.vertex.hd_sym, 0.0);
    EXPECT_NEAR(r.surface.completeness, 0.0, 1e-12);
    EXPECT_DOUBLE_EQ(r.surface.recall, 1.0);
    EXPECT_DOUBLE_EQ(r.surface.precision, 1.0);
    EXPECT_DOUBLE_EQ(r.surface.fscore, 1.0);
    EXPECT_EQ(r.vertex.curve_share.front(), 1.0);
}

TEST(Metrics, RandomSetsMatchBruteForce) {
    std::mt19937_64 rng(9);
    std::uniform_real_distribution<double> u(0, 4), n(-0.3, 0.3);
    Mesh mesh = grid_mesh(8, 0.5, 0.0);
    for (auto& v : mesh.vertices) v.z() = n(rng);  // a bumpy surface
    std::vector<Eigen::Vector3d> gt(500);
    for (auto& p : gt) p = {u(rng), u(rng), n(rng)};
    EvaluationConfig cfg;
    cfg.sample_spacing = 0.1;
    cfg.crop_to_gt_box = false;
    const EvaluationResult r = evaluate(mesh, gt, cfg);

    std::vector<double> dp, dg, dc;
    for (const auto& v : mesh.vertices) dp.push_back(brute_nearest(v, gt));
    for (const auto& g : gt) dg.push_back(brute_nearest(g, mesh.vertices));
    for (const auto& g : gt) {
        double best = 1e300;
        for (const auto& t : mesh.triangles)
            best = std::min(best, (closest_point_on_triangle(g, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]) - g).norm());
        dc.push_back(best);
    }
    auto mean = [](const std::vector<double>& v) { double s = 0; for (double x : v) s += x; return s / double(v.size()); };
    EXPECT_NEAR(r.vertex.p_to_gt.mean, mean(dp), 1e-12);
    EXPECT_DOUBLE_EQ(r.vertex.p_to_gt.max, *std::max_element(dp.begin(), dp.end()));
    EXPECT_NEAR(r.vertex.gt_to_p.mean, mean(dg), 1e-12);
    EXPECT_DOUBLE_EQ(r.vertex.gt_to_p.max, *std::max_element(dg.begin(), dg.end()));
    EXPECT_NEAR(r.vertex.ae_sym, 0.5 * (mean(dp) + mean(dg)), 1e-12);
    const double within = double(std::count_if(dp.begin(), dp.end(), [](double d) { return d <= 0.2; })) / double(dp.size());
    EXPECT_DOUBLE_EQ(r.vertex.share_within_delta, within);

    std::vector<double> clipped;
    for (double d : dc) clipped.push_back(std::min(d, cfg.truncation_completeness));
    EXPECT_NEAR(r.surface.completeness, mean(clipped), 1e-12);
    const double recall = double(std::count_if(dc.begin(), dc.end(), [](double d) { return d <= 0.1; })) / double(dc.size());
    EXPECT_DOUBLE_EQ(r.surface.recall, recall);

    // Same seed, same samples: the accuracy and precision oracles use them.
    const auto samples = sample_surface(mesh, cfg.sample_spacing, cfg.max_samples, cfg.seed);
    ASSERT_EQ(samples.size(), r.surface.samples);
    std::vector<double> ds;
    for (const auto& s : samples) ds.push_back(brute_nearest(s, gt));
    clipped.clear();
    for (double d : ds) clipped.push_back(std::min(d, cfg.truncation_accuracy));
    EXPECT_NEAR(r.surface.accuracy, mean(clipped), 1e-12);
    const double precision = double(std::count_if(ds.begin(), ds.end(), [](double d) { return d <= 0.1; })) / double(ds.size());
    EXPECT_DOUBLE_EQ(r.surface.precision, precision);
    EXPECT_NEAR(r.surface.fscore, 2 * precision * recall / (precision + recall), 1e-12);
}

TEST(Metrics, RangeCropAndRangeBins) {
    // A 40 m strip of ground along x, sensor at the origin; GT 5 cm above.
    Mesh mesh;
    for (int i = 0; i <= 400; ++i) {
        mesh.vertices.emplace_back(0.1 * i, 0, 0);
        mesh.vertices.emplace_back(0.1 * i, 0.1, 0);
    }
    for (std::uint32_t i = 0; i < 400; ++i) {
        mesh.triangles.push_back({2 * i, 2 * i + 2, 2 * i + 3});
        mesh.triangles.push_back({2 * i, 2 * i + 3, 2 * i + 1});
    }
    std::vector<Eigen::Vector3d> gt;
    for (const auto& v : mesh.vertices) gt.push_back(v + Eigen::Vector3d(0, 0, 0.05));
    EvaluationConfig cfg;
    cfg.max_range = 19.95;  // every kept vertex keeps its GT partner (GT is cropped too)
    const EvaluationResult r = evaluate(mesh, gt, cfg);
    std::size_t in = 0;
    for (const auto& v : mesh.vertices) in += v.norm() <= 19.95;
    EXPECT_EQ(r.mesh_vertices, in);
    ASSERT_EQ(r.vertex.by_range.size(), 4u);  // [0,5) ... [15,20)
    std::size_t total = 0;
    for (const auto& b : r.vertex.by_range) {
        total += b.count;
        if (b.count) {
            EXPECT_NEAR(b.mean, 0.05, 1e-12);
        }
    }
    EXPECT_EQ(total, in);
    cfg.max_range = 0.01;
    cfg.origin = {-100, 0, 0};
    EXPECT_THROW(evaluate(mesh, gt, cfg), InvalidInput);
}

TEST(Metrics, SurfaceSamplesAreOnTheMeshAreaWeightedAndSeeded) {
    Mesh mesh;  // two triangles, areas 0.5 and 2.0
    mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {10, 0, 0}, {12, 0, 0}, {10, 2, 0}};
    mesh.triangles = {{0, 1, 2}, {3, 4, 5}};
    const auto s = sample_surface(mesh, 0.01, 1'000'000, 3);
    EXPECT_EQ(s.size(), 25000u);  // ceil(2.5 / 0.01^2)
    const MeshDistance dist(mesh);
    std::size_t small = 0;
    for (const auto& p : s) {
        EXPECT_LT(dist.distance(p), 1e-12);
        small += p.x() < 5;
    }
    EXPECT_NEAR(double(small) / double(s.size()), 0.2, 0.01);  // 0.5 / 2.5, 4 sigma ~ 0.01
    EXPECT_EQ(sample_surface(mesh, 0.01, 1'000'000, 3), s);
    EXPECT_NE(sample_surface(mesh, 0.01, 1'000'000, 4), s);
    EXPECT_EQ(sample_surface(mesh, 0.01, 100, 3).size(), 100u);
}

TEST(Metrics, BadInputAndConfig) {
    const Mesh mesh = grid_mesh(2, 1.0, 0.0);
    EXPECT_THROW(evaluate(Mesh{}, mesh.vertices, EvaluationConfig{}), InvalidInput);
    EXPECT_THROW(evaluate(mesh, {}, EvaluationConfig{}), InvalidInput);
    EXPECT_THROW(evaluate(mesh, {{0, 0, std::nan("")}}, EvaluationConfig{}), InvalidInput);
    EvaluationConfig bad;
    bad.threshold = 0;
    EXPECT_THROW(bad.validate(), InvalidArgument);
    bad = {};
    bad.max_range = -1;
    EXPECT_THROW(bad.validate(), InvalidArgument);
    bad = {};
    bad.sample_spacing = std::nan("");
    EXPECT_THROW(bad.validate(), InvalidArgument);
}

TEST(Metrics, ReportsCarryTheNumbers) {
    const Mesh mesh = grid_mesh(4, 0.5, 0.0);
    std::vector<Eigen::Vector3d> gt;
    for (const auto& v : mesh.vertices) gt.push_back(v + Eigen::Vector3d(0, 0, 0.1));
    const EvaluationResult r = evaluate(mesh, gt, EvaluationConfig{});
    const std::string json = to_json(r), table = format_table(r);
    EXPECT_NE(json.find("\"ae_sym\": 0.1"), std::string::npos);
    EXPECT_NE(json.find("\"fscore\""), std::string::npos);
    EXPECT_EQ(std::count(json.begin(), json.end(), '{'), std::count(json.begin(), json.end(), '}'));
    EXPECT_NE(table.find("0.1000"), std::string::npos);
}
