// The ring hold-out: rings recovered from the point order of a scan stored ring after ring (as
// KITTI stores its HDL-64E scans) agree with the beams the simulator fired; the distances agree
// with a brute-force closest-triangle search; a mesh of an exactly planar world leaves the odd
// rings on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/eval/ring_holdout.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/mesh/mesh_distance.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

double azimuth_deg(const Eigen::Vector3d& p) {
    const double a = std::atan2(p.y(), p.x()) * 180.0 / std::numbers::pi;
    return a < 0 ? a + 360 : a;
}

// The beam that fired each point, from its elevation: the simulator's noise is along the ray,
// so the elevation of a point seen from the origin is its beam's, whatever the noise.
std::vector<int> beams_of(const PointCloud& cloud, const sim::SensorModel& sensor) {
    std::vector<int> beams;
    for (const Eigen::Vector3d& p : cloud.points) {
        const double el = std::atan2(p.z(), std::hypot(p.x(), p.y())) * 180.0 / std::numbers::pi;
        int best = 0;
        for (int b = 1; b < static_cast<int>(sensor.elevations_deg.size()); ++b)
            if (std::fabs(sensor.elevations_deg[b] - el) < std::fabs(sensor.elevations_deg[best] - el)) best = b;
        beams.push_back(best);
    }
    return beams;
}

// The scan stored ring after ring, each ring sweeping the azimuth from `start_deg` in the
// direction `sign` (+1: counter-clockwise, as KITTI). `beam_of_point` receives each stored point's beam.
PointCloud ring_ordered(const PointCloud& cloud, const std::vector<int>& beams, double start_deg, double sign, std::vector<int>& beam_of_point) {
    std::vector<std::size_t> order(cloud.points.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    auto sweep = [&](std::size_t i) {
        const double a = std::fmod(sign * (azimuth_deg(cloud.points[i]) - start_deg) + 720.0, 360.0);
        return a;
    };
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        if (beams[a] != beams[b]) return beams[a] < beams[b];
        return sweep(a) < sweep(b);
    });
    PointCloud out;
    beam_of_point.clear();
    for (std::size_t i : order) {
        out.points.push_back(cloud.points[i]);
        beam_of_point.push_back(beams[i]);
    }
    return out;
}

const sim::SensorModel& hdl64() {
    static const sim::SensorModel s = sim::SensorModel::hdl64();
    return s;
}

PointCloud demo_scan(double noise) {
    sim::SensorModel s = hdl64();
    s.range_noise = noise;
    return sim::simulate_scan(sim::AnalyticScene::demo(), s, Eigen::Vector3d::Zero(), 3);
}

// Ring numbers as the split sees them: consecutive runs of one beam numbered 0, 1, ...
std::vector<std::uint16_t> runs(const std::vector<int>& beam_of_point) {
    std::vector<std::uint16_t> r(beam_of_point.size());
    for (std::size_t i = 1; i < r.size(); ++i) r[i] = static_cast<std::uint16_t>(r[i - 1] + (beam_of_point[i] != beam_of_point[i - 1]));
    return r;
}

}  // namespace

TEST(RingsFromOrder, RecoversTheBeamsOfASimulatedScanStoredRingAfterRing) {
    const PointCloud scan = demo_scan(0.02);
    const std::vector<int> beams = beams_of(scan, hdl64());
    for (const auto& [start, sign] : std::vector<std::pair<double, double>>{{0, 1}, {0, -1}, {137.5, 1}, {271, -1}}) {
        std::vector<int> beam_of_point;
        const PointCloud ordered = ring_ordered(scan, beams, start, sign, beam_of_point);
        const std::vector<std::uint16_t> rings = rings_from_order(ordered);
        EXPECT_EQ(rings, runs(beam_of_point)) << "start " << start << " sign " << sign;
        EXPECT_EQ(rings.back() + 1u, 64u);  // every beam of the HDL-64E hits the demo world
    }
}

TEST(RingsFromOrder, APointJustBehindTheStartStaysInItsRing) {
    const PointCloud scan = demo_scan(0.02);
    std::vector<int> beam_of_point;
    PointCloud ordered = ring_ordered(scan, beams_of(scan, hdl64()), 10.0, 1, beam_of_point);
    // The second point of every ring moved 0.3 degrees behind the start azimuth, behind the cut
    // (the last ring ends 0.18 degrees before it).
    for (std::size_t i = 1; i + 1 < ordered.points.size(); ++i) {
        if (beam_of_point[i] == beam_of_point[i - 1] && (i < 2 || beam_of_point[i - 1] != beam_of_point[i - 2])) {
            Eigen::Vector3d& p = ordered.points[i];
            const double r = std::hypot(p.x(), p.y()), a = (10.0 - 0.3) * std::numbers::pi / 180.0;
            p.x() = r * std::cos(a);
            p.y() = r * std::sin(a);
        }
    }
    EXPECT_EQ(rings_from_order(ordered), runs(beam_of_point));
}

TEST(RingsFromOrder, RefusesScansNotStoredRingAfterRing) {
    const PointCloud scan = demo_scan(0.02);  // the simulator's order: column after column
    EXPECT_THROW(rings_from_order(scan), InvalidInput);
    PointCloud shuffled = scan;
    std::mt19937 rng(5);
    std::shuffle(shuffled.points.begin(), shuffled.points.end(), rng);
    EXPECT_THROW(rings_from_order(shuffled), InvalidInput);
    EXPECT_THROW(rings_from_order(PointCloud{}), InvalidInput);
}

TEST(SplitRings, EvenAndOddRingsInFileOrder) {
    PointCloud c;
    for (int i = 0; i < 10; ++i) c.points.emplace_back(i, 0, 0);
    const std::vector<std::uint16_t> rings = {0, 0, 1, 1, 2, 3, 3, 3, 5, 5};
    const RingSplit s = split_rings(c, rings);
    EXPECT_EQ(s.rings, 5u);
    ASSERT_EQ(s.even.points.size(), 3u);
    ASSERT_EQ(s.odd.points.size(), 7u);
    EXPECT_EQ(s.even.points[2].x(), 4);
    EXPECT_EQ(s.odd.points[0].x(), 2);
    EXPECT_EQ(s.odd.points[6].x(), 9);
    EXPECT_THROW(split_rings(c, {0, 1}), InvalidInput);
    EXPECT_THROW(split_rings(c, std::vector<std::uint16_t>(10, 2)), InvalidInput);  // no odd ring
}

TEST(MeasureRingHoldout, DistancesToAPlaneByRangeBin) {
    Mesh square;  // z = 0 over [-50, 50]^2
    square.vertices = {{-50, -50, 0}, {50, -50, 0}, {50, 50, 0}, {-50, 50, 0}};
    square.triangles = {{0, 1, 2}, {0, 2, 3}};
    // Heights 0.01, 0.04, 0.07, 0.2 at ranges 5, 15, 25 (and one at 40 m, beyond the default range).
    std::vector<Eigen::Vector3d> held;
    for (double r : {5.0, 15.0, 25.0})
        for (double h : {0.01, 0.04, 0.07, 0.2}) held.emplace_back(r, 0, h);
    held.emplace_back(40, 0, 0.0);
    RingHoldoutConfig cfg;
    const RingHoldoutResult res = measure_ring_holdout(square, held, cfg);
    EXPECT_EQ(res.all.count, 12u);
    ASSERT_EQ(res.all.within.size(), 2u);
    EXPECT_DOUBLE_EQ(res.all.within[0], 0.5);   // 0.01, 0.04
    EXPECT_DOUBLE_EQ(res.all.within[1], 0.75);  // and 0.07
    EXPECT_NEAR(res.all.mean, (0.01 + 0.04 + 0.07 + 0.2) / 4, 1e-12);
    ASSERT_EQ(res.by_range.size(), 3u);
    for (const HoldoutDistances& b : res.by_range) {
        EXPECT_EQ(b.count, 4u);
        EXPECT_DOUBLE_EQ(b.within[0], 0.5);
    }
    EXPECT_EQ(res.by_range[2].lo, 20);
    EXPECT_EQ(res.by_range[2].hi, 30);
    cfg.max_range = 10;
    EXPECT_EQ(measure_ring_holdout(square, held, cfg).all.count, 4u);
    cfg.max_range = 1;
    EXPECT_THROW(measure_ring_holdout(square, held, cfg), InvalidInput);  // nothing within 1 m
    cfg.max_range = -1;
    EXPECT_THROW(measure_ring_holdout(square, held, cfg), InvalidArgument);
    EXPECT_THROW(measure_ring_holdout(Mesh{}, held, RingHoldoutConfig{}), InvalidInput);
}

// The whole check on a noise-free scan of the analytic demo world, stored ring after ring: the
// distances agree with a brute-force search over every triangle, and the odd rings, which lie
// exactly on the world's surfaces, lie on the mesh of the even rings within a fraction of a voxel.
TEST(RingHoldout, OddRingsOfAnExactWorldLieOnTheMeshOfTheEvenRings) {
    const PointCloud scan = demo_scan(0.0);
    std::vector<int> beam_of_point;
    const PointCloud ordered = ring_ordered(scan, beams_of(scan, hdl64()), 0, 1, beam_of_point);
    const ReconstructionConfig config;
    Mesh mesh;
    RingHoldoutConfig cfg;
    cfg.max_range = 15;  // the HDL-64E's even rings are at most 1.5 m apart on the ground there
    const RingHoldoutResult res = ring_holdout(ordered, [&](const PointCloud& even) { return mesh = reconstruct(even, Eigen::Vector3d::Zero(), config); }, cfg);
    EXPECT_EQ(res.rings, 64u);
    const RingSplit split = split_rings(ordered, runs(beam_of_point));
    EXPECT_EQ(res.reconstructed, split.even.points.size());
    EXPECT_EQ(res.held_out, split.odd.points.size());
    // Every 16th held-out point, measured again alone, against a search over every triangle.
    std::vector<Eigen::Vector3d> sample;
    for (std::size_t i = 0; i < split.odd.points.size(); i += 16) sample.push_back(split.odd.points[i]);
    const RingHoldoutResult sampled = measure_ring_holdout(mesh, sample, cfg);
    std::vector<double> brute;
    for (const Eigen::Vector3d& p : sample) {
        if (p.norm() > cfg.max_range) continue;
        double best = INFINITY;
        for (const auto& t : mesh.triangles)
            best = std::min(best, (closest_point_on_triangle(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]) - p).norm());
        brute.push_back(best);
    }
    ASSERT_EQ(sampled.all.count, brute.size());
    const auto n = static_cast<double>(brute.size());
    const double within = static_cast<double>(std::count_if(brute.begin(), brute.end(), [](double d) { return d <= 0.05; })) / n;
    EXPECT_DOUBLE_EQ(sampled.all.within[0], within);
    double mean = 0;
    for (double d : brute) mean += d / n;
    EXPECT_NEAR(sampled.all.mean, mean, 1e-9);
    const double alpha = config.voxel_size;
    EXPECT_LT(res.all.median, 0.1 * alpha);
    EXPECT_LT(res.all.p90, 0.5 * alpha);
}

TEST(ReadRings, TheRingFieldOfNuScenesRecords) {
    const test::TempDir dir("rings");
    const auto path = dir / "rings.bin";
    {
        std::ofstream f(path, std::ios::binary);
        const float rec[3][5] = {{1, 2, 3, 9, 0}, {NAN, 0, 0, 9, 7}, {4, 5, 6, 9, 31}};
        f.write(reinterpret_cast<const char*>(rec), sizeof rec);
    }
    PointReadOptions o;
    o.bin_fields = 5;
    o.ring_field = 4;
    PointCloud c = read_points(path, o);
    EXPECT_EQ(c.rings, (std::vector<std::uint16_t>{0, 7, 31}));
    EXPECT_EQ(drop_non_finite(c), 1u);
    EXPECT_EQ(c.rings, (std::vector<std::uint16_t>{0, 31}));  // the rings follow the points
    EXPECT_EQ(c.points[1].x(), 4);
    o.ring_field = 3;  // intensity 9 is a whole number: read as a ring
    EXPECT_EQ(read_points(path, o).rings, (std::vector<std::uint16_t>{9, 9, 9}));
    o.ring_field = 5;
    EXPECT_THROW(read_points(path, o), InvalidArgument);
    o.ring_field = 2;  // z: not a field after x, y, z
    EXPECT_THROW(read_points(path, o), InvalidArgument);
    {
        std::ofstream f(path, std::ios::binary);
        const float rec[5] = {1, 2, 3, 9, 2.5f};
        f.write(reinterpret_cast<const char*>(rec), sizeof rec);
    }
    o.ring_field = 4;
    EXPECT_THROW(read_points(path, o), FormatError);
    o.bin_fields = 4;
    o.ring_field = -1;
    std::filesystem::remove(path);
}

// On real KITTI frames (skipped without ../shared/data): 64 rings of about 2,000 points each,
// stored from the top beam down (their median elevations fall ring after ring).
TEST(RingsFromOrder, RealKittiFramesHold64RingsTopDown) {
    const std::filesystem::path dir = std::filesystem::path(LIDARSURF_SHARED_DATA) / "kitti";
    if (!std::filesystem::exists(dir / "000000.bin")) GTEST_SKIP() << "no real KITTI frame in " << dir;
    for (const char* name : {"000000.bin", "000001.bin", "000002.bin"}) {
        const PointCloud c = read_points(dir / name);
        const std::vector<std::uint16_t> rings = rings_from_order(c);
        ASSERT_EQ(rings.back(), 63) << name;
        std::map<int, std::vector<double>> el;
        for (std::size_t i = 0; i < rings.size(); ++i)
            el[rings[i]].push_back(std::atan2(c.points[i].z(), std::hypot(c.points[i].x(), c.points[i].y())));
        double previous = INFINITY;
        for (auto& [ring, e] : el) {
            EXPECT_GT(e.size(), 1000u) << name << " ring " << ring;
            EXPECT_LT(e.size(), 2300u) << name << " ring " << ring;
            std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
            EXPECT_LT(e[e.size() / 2], previous) << name << " ring " << ring;
            previous = e[e.size() / 2];
        }
    }
}
