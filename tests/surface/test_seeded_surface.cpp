// The seeded surface: the cube search on a hand-made field (analytic answer), and the fast path
// (lazy evaluation) against the reference (every candidate evaluated, then searched): the same
// mesh on several scans in every mode.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <map>
#include <set>
#include <span>
#include <tuple>

#include <tbb/task_arena.h>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/pipeline.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/simulator.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

// Field on the vertices of [lo, hi]^3 with value z - plane (a horizontal surface).
void add_slab(TsdfField& f, int lo, int hi, double plane) {
    for (int z = lo; z <= hi; ++z)
        for (int y = lo; y <= hi; ++y)
            for (int x = lo; x <= hi; ++x) {
                VertexSample s;
                s.defined = true;
                s.tsdf = static_cast<float>(z - plane);
                f.insert({x, y, z}, s);
            }
}

using lidarsurf::test::expect_same_mesh;
using lidarsurf::test::fast_and_reference;

// A rough terrain: terraces at different heights, rocks (boxes) and trees (cylinders).
sim::AnalyticScene offroad() {
    sim::AnalyticScene s;
    s.grounds.push_back({-1.9, 0, 0, 30, 30});
    s.grounds.push_back({-1.5, 12, 6, 5, 6});
    s.grounds.push_back({-1.2, -10, -8, 4, 5});
    s.boxes.push_back({{4, -3, -1.9}, {5.2, -1.8, -1.1}});
    s.boxes.push_back({{-6, 5, -1.9}, {-4.5, 7, -0.4}});
    for (int i = 0; i < 6; ++i) s.cylinders.push_back({-15.0 + 6 * i, 10.0 - 3 * i, 0.25, -1.9, 2.5});
    return s;
}

}  // namespace

TEST(SeededSurface, KeepsOnlyTheComponentTouchingTheData) {
    TsdfField field;
    field.voxel_size = 1.0;
    add_slab(field, 0, 4, 1.5);    // a surface through the cubes with z = 1, x, y in [0, 3]
    add_slab(field, 10, 14, 11.5); // the same, far from any data
    VoxelGrid grid(1.0, Eigen::Vector3d::Zero());
    grid.insert({1.5, 1.5, 1.5});  // voxel (1, 1, 1): a cube of the first surface
    const auto cubes = seeded_cubes(field, grid, 0);
    std::set<std::tuple<int, int, int>> got, want;
    for (const auto& c : cubes) got.insert({c.x(), c.y(), c.z()});
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) want.insert({x, y, 1});
    EXPECT_EQ(got, want);
    EXPECT_TRUE(std::is_sorted(cubes.begin(), cubes.end(), [](const VoxelKey& a, const VoxelKey& b) {
        return std::tie(a.z(), a.y(), a.x()) < std::tie(b.z(), b.y(), b.x());
    }));
    // A seed away from both surfaces reaches nothing; a dilation of 1 around it still does not.
    VoxelGrid far(1.0, Eigen::Vector3d::Zero());
    far.insert({6.5, 6.5, 6.5});
    EXPECT_TRUE(seeded_cubes(field, far, 1).empty());
    // A dilation of 5 around (6,6,6) includes cube (10,10,11) of the second surface ...
    EXPECT_EQ(seeded_cubes(field, far, 5).size(), 32u);  // and cubes (1..3, 1..3, 1) of the first
    // The mesh of the kept cubes is the first surface only.
    const Mesh mesh = extract_mesh(field, cubes);
    ASSERT_FALSE(mesh.empty());
    for (const auto& v : mesh.vertices) EXPECT_NEAR(v.z(), 1.5, 1e-9);
}

TEST(SeededSurface, FastPathGivesTheReferenceMeshInEveryMode) {
    struct Scan {
        std::string name;
        sim::AnalyticScene scene;
        Eigen::Vector3d origin;
    };
    const std::vector<Scan> scans = {{"demo", sim::AnalyticScene::demo(), Eigen::Vector3d::Zero()},
                                     {"offroad", offroad(), Eigen::Vector3d(1.0, -2.0, 0.3)}};
    for (const Scan& scan : scans) {
        const PointCloud cloud = sim::simulate_scan(scan.scene, sim::SensorModel::hdl64(), scan.origin, 5);
        for (Mode mode : {Mode::AdaptiveGaussian, Mode::Adaptive, Mode::ConstantGaussian, Mode::Constant}) {
            // The adaptive modes also without the slab fallback (`--slab 0`: the paper's level
            // loop, the configuration README offers where a robot needs more time margin).
            for (const bool slabs : {true, false}) {
                ReconstructionConfig c;
                c.mode = mode;
                c.k = 3;
                if (!slabs) {
                    if (!c.adaptive()) continue;
                    c.slab_from_level = 0;
                }
                const std::string what = scan.name + " " + std::string(to_string(mode)) + (slabs ? "" : ", no slab fallback");
                const auto m = fast_and_reference(cloud, c, scan.origin);
                ASSERT_GT(m.fast.triangles.size(), 1000u) << what;
                expect_same_mesh(m.fast, m.reference, what);
                // The fast path evaluates far fewer vertices than the full candidate set.
                EXPECT_LT(m.fast_summary.candidate_vertices, m.reference_summary.candidate_vertices) << what;
            }
        }
    }
}

// Bridges (docs/method.md, "Bridges") on a sparse sensor: a VLP-16 scan of the rough terrain, whose
// rings on the ground lie metres apart. The fast path finds the reference mesh (the reference
// evaluates each corner of the cubes its own serial search visits, since bridged vertices lie
// beyond H^{k_max} of the data, where compute_tsdf has no candidate), the bridged surface carries a
// confidence below tau, and it lies on the true ground.
TEST(SeededSurface, BridgesAreTheSameInBothSearches) {
    const Eigen::Vector3d origin(1.0, -2.0, 0.3);
    const sim::AnalyticScene scene = offroad();
    const PointCloud cloud = sim::simulate_scan(scene, sim::SensorModel::vlp16(), origin, 5);
    const ReconstructionConfig c;
    ASSERT_TRUE(c.bridges());
    const auto m = fast_and_reference(cloud, c, origin);
    ASSERT_GT(m.fast.triangles.size(), 1000u);
    expect_same_mesh(m.fast, m.reference, "offroad vlp16");
    std::size_t bridged = 0, near_ground = 0;
    for (std::size_t i = 0; i < m.fast.vertices.size(); ++i) {
        if (m.fast.confidence[i] >= c.tau) continue;
        ++bridged;
        near_ground += scene.distance(m.fast.vertices[i]) <= 0.5 * c.voxel_size;
    }
    EXPECT_GT(bridged, m.fast.vertices.size() / 20) << "the rings of a VLP-16 are bridged";
    EXPECT_GT(near_ground, bridged * 9 / 10) << "bridged vertices lie on the true surface";
    // Without bridges the mesh is smaller.
    ReconstructionConfig off = c;
    off.bridge_reach = 0;
    EXPECT_LT(fast_and_reference(cloud, off, origin).fast.triangles.size(), m.fast.triangles.size() * 9 / 10);
}

// The cube search against a plain flood fill over the reference field (std::set, the signs of each
// face's four corners counted directly): from the occupied voxels' cubes, a cube with its 8 corners
// defined and both signs among them is active and leads through each face whose corners have both
// signs; a seed whose corners share one sign leads to the 8 cubes around each corner with
// |TSDF| <= 1e-6 alpha (zero counts as positive).
TEST(SeededSurface, TheSearchIsAFloodFillThroughCrossedFaces) {
    const Eigen::Vector3d origin(1.0, -2.0, 0.3);
    const PointCloud cloud = sim::simulate_scan(offroad(), sim::SensorModel::hdl64(), origin, 5);
    ReconstructionConfig c;
    c.bridge_reach = 0;  // compute_tsdf's candidates hold no bridge (BridgesAreTheSameInBothSearches)
    VoxelGrid grid(c.voxel_size, origin);
    for (const Eigen::Vector3d& p : cloud.points) grid.insert(p);
    const TsdfField field = compute_tsdf(grid, c, origin);
    const double eps = 1e-6 * c.voxel_size;
    auto key_of = [](const VoxelKey& k) { return std::make_tuple(k.x(), k.y(), k.z()); };
    std::set<std::tuple<int, int, int>> visited, active;
    std::vector<VoxelKey> queue;
    auto visit = [&](const VoxelKey& cube) {
        if (visited.insert(key_of(cube)).second) queue.push_back(cube);
    };
    for (const VoxelKey& k : grid.keys()) visit(k);
    const std::size_t seeds = queue.size();
    for (std::size_t i = 0; i < queue.size(); ++i) {
        const VoxelKey cube = queue[i];
        std::array<const VertexSample*, 8> s{};
        bool defined = true;
        for (int n = 0; n < 8; ++n) defined = defined && (s[static_cast<std::size_t>(n)] = field.find(cube + VoxelKey(n & 1, (n >> 1) & 1, n >> 2)));
        if (!defined) continue;
        auto negative = [&](int n) { return s[static_cast<std::size_t>(n)]->tsdf < 0; };
        int negatives = 0;
        for (int n = 0; n < 8; ++n) negatives += negative(n);
        if (negatives == 0 || negatives == 8) {
            if (i >= seeds) continue;
            for (int n = 0; n < 8; ++n)
                if (std::abs(s[static_cast<std::size_t>(n)]->tsdf) <= eps)
                    for (int m = 0; m < 8; ++m) visit(cube + VoxelKey(n & 1, (n >> 1) & 1, n >> 2) - VoxelKey(m & 1, (m >> 1) & 1, m >> 2));
            continue;
        }
        active.insert(key_of(cube));
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                int face_negatives = 0;  // corners with bit `axis` equal to `side`
                for (int n = 0; n < 8; ++n) face_negatives += ((n >> axis) & 1) == side && negative(n);
                if (face_negatives == 0 || face_negatives == 4) continue;
                VoxelKey next = cube;
                next[axis] += side ? 1 : -1;
                visit(next);
            }
    }
    const std::vector<VoxelKey> cubes = seeded_cubes(field, grid, 0);
    ASSERT_GT(active.size(), 1000u);
    std::set<std::tuple<int, int, int>> found;
    for (const VoxelKey& k : cubes) found.insert(key_of(k));
    EXPECT_EQ(found.size(), cubes.size()) << "a cube listed twice";
    EXPECT_TRUE(found == active) << found.size() << " cubes found, " << active.size() << " by the flood fill";
    // And the fast path, which runs the same search while it evaluates, finds them too.
    EXPECT_EQ(compute_seeded_tsdf(grid, c, origin).cubes, cubes);
}

// Seeds dilated by d cubes: the fast path finds the seeds' corners per block (occupancy dilated
// by [-d, d + 1], across block borders when d + 1 > 8 - 1) and still gives the reference mesh.
TEST(SeededSurface, FastPathGivesTheReferenceMeshWithDilatedSeeds) {
    const Eigen::Vector3d origin(1.0, -2.0, 0.3);
    const PointCloud cloud = sim::simulate_scan(offroad(), sim::SensorModel::hdl64(), origin, 5);
    for (int dilation : {1, 8}) {
        ReconstructionConfig c;
        c.seed_dilation = dilation;
        const auto m = fast_and_reference(cloud, c, origin);
        ASSERT_GT(m.fast.triangles.size(), 1000u) << dilation;
        expect_same_mesh(m.fast, m.reference, "seed dilation " + std::to_string(dilation));
    }
}

// A simulated HDL-64 frame of the procedural town (the benchmark's scene): the fast path's
// windowed sums and closed-form eigen solver give the reference mesh on a real-size scan too.
TEST(SeededSurface, FastPathGivesTheReferenceMeshOnATownFrame) {
    sim::SimulatorConfig sc;
    sc.gt_beams = 0;
    const sim::Simulator simulator(sim::make_world(sim::SceneConfig{}), sc);
    const PointCloud cloud = simulator.frame(37).scan;  // sensor frame
    ASSERT_GT(cloud.points.size(), 100000u);
    for (Mode mode : {Mode::AdaptiveGaussian, Mode::Constant}) {
        ReconstructionConfig c;
        c.mode = mode;
        const auto m = fast_and_reference(cloud, c, Eigen::Vector3d::Zero());
        ASSERT_GT(m.fast.triangles.size(), 20000u);
        expect_same_mesh(m.fast, m.reference, std::string("town ") + std::string(to_string(mode)));
    }
}

TEST(SeededSurface, DataOnALatticePlaneIsStillMeshed) {
    // Noise-free points exactly on a lattice plane: the TSDF is zero on that plane and, zero
    // counting as positive, the surface crosses the cubes *below* the occupied voxels.
    PointCloud cloud;
    for (int i = 0; i < 60; ++i)
        for (int j = 0; j < 60; ++j) cloud.points.emplace_back(0.05 * i, 0.05 * j, -1.0);
    ReconstructionConfig c;
    const auto m = fast_and_reference(cloud, c, Eigen::Vector3d::Zero());
    ASSERT_GT(m.fast.triangles.size(), 100u);
    expect_same_mesh(m.fast, m.reference, "lattice plane");
    for (const auto& v : m.fast.vertices) EXPECT_NEAR(v.z(), -1.0, 1e-6);
}

// A plane across the lattice (normal (1, 1, 1) / sqrt(3)) fused from two viewpoints: a cube it
// crosses near a corner has its farthest corner up to sqrt(3) voxels from it, so the truncation
// along the normal keeps every such corner and the patch comes out whole: no hole inside it, every
// vertex on the plane.
TEST(SeededSurface, AnObliquePlaneFusedFromTwoViewpointsHasNoHoles) {
    const Eigen::Vector3d n = Eigen::Vector3d::Ones().normalized();
    const Eigen::Vector3d u = Eigen::Vector3d(1, -1, 0).normalized(), w = n.cross(u);
    const Eigen::Vector3d centre(0.37, 0.21, 0.13);  // off the lattice
    ReconstructionConfig c;
    Reconstructor rec(c, centre + 6 * n);
    for (int view = 0; view < 2; ++view) {
        std::vector<Eigen::Vector3d> points;
        for (int i = -40; i <= 40; ++i)
            for (int j = -40; j <= 40; ++j)
                if ((i + j + view) % 2 == 0) points.push_back(centre + 0.05 * i * u + 0.05 * j * w);
        rec.integrate(points, centre + 6 * n + (view == 0 ? 3.0 : -3.0) * u);
    }
    const Mesh mesh = rec.extract_mesh();
    ASSERT_GT(mesh.triangles.size(), 500u);
    for (const Eigen::Vector3d& v : mesh.vertices) EXPECT_NEAR(n.dot(v - centre), 0.0, 0.02);
    // Boundary edges only along the patch's border (2 m from its centre in the plane).
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    for (const auto& t : mesh.triangles)
        for (int i = 0; i < 3; ++i) ++edges[{std::min(t[i], t[(i + 1) % 3]), std::max(t[i], t[(i + 1) % 3])}];
    std::size_t inside = 0;
    for (const auto& [e, count] : edges) {
        const Eigen::Vector3d mid = 0.5 * (mesh.vertices[e.first] + mesh.vertices[e.second]) - centre;
        if (count == 1 && std::max(std::fabs(u.dot(mid)), std::fabs(w.dot(mid))) < 2.0 - 3 * c.voxel_size) ++inside;
    }
    EXPECT_EQ(inside, 0u);
}

// The seed wave evaluates each seed cube's all-even corner first and the other corners only for
// the cubes where it is defined. One isolated voxel with fewer than N_min points: every corner is
// undefined (Eq. 1 fails at every level), so exactly one vertex (its all-even corner) is evaluated
// instead of its 8 corners, and nothing is meshed.
TEST(SeededSurface, ASeedCubeWithAnUndefinedCornerCostsOneVertex) {
    for (const Eigen::Vector3d& at : {Eigen::Vector3d(0.05, 0.05, 0.05), Eigen::Vector3d(-0.31, 0.47, -1.13)}) {
        VoxelGrid grid(0.2, Eigen::Vector3d::Zero());
        for (int i = 0; i < 3; ++i) grid.insert(at + Eigen::Vector3d(0.01 * i, 0.02 * i, 0.0));
        ASSERT_EQ(grid.size(), 1u);
        const SeededTsdf seeded = compute_seeded_tsdf(grid, ReconstructionConfig{}, Eigen::Vector3d(0, 0, 2));
        EXPECT_EQ(seeded.evaluated, 1u) << at.transpose();
        EXPECT_TRUE(seeded.cubes.empty());
        EXPECT_EQ(seeded.field.size(), 0u);
    }
}

// The fast path's threads claim vertices as they need them, so the evaluation order varies from
// run to run; the result must not. For 1, 2 and 3 threads: the same evaluated count, the same
// field (keys and samples, to the bit, in the same order) and the same cubes, and every field
// vertex appears once (a vertex is evaluated by one thread only).
TEST(SeededSurface, TheFieldDoesNotDependOnTheThreadCount) {
    const Eigen::Vector3d origin(1.0, -2.0, 0.3);
    const PointCloud cloud = sim::simulate_scan(offroad(), sim::SensorModel::hdl64(), origin, 5);
    VoxelGrid grid(0.2);
    grid.insert(std::span<const Eigen::Vector3d>(cloud.points));
    const ReconstructionConfig c;
    std::vector<SeededTsdf> runs;
    for (int threads : {1, 2, 3}) {
        tbb::task_arena arena(threads);
        runs.push_back(arena.execute([&] { return compute_seeded_tsdf(grid, c, origin); }));
    }
    const SeededTsdf& first = runs.front();
    ASSERT_GT(first.cubes.size(), 1000u);
    std::set<std::tuple<int, int, int>> distinct;
    for (const VoxelKey& k : first.field.keys()) distinct.insert({k.x(), k.y(), k.z()});
    EXPECT_EQ(distinct.size(), first.field.size());
    // The order (the waves' order varies with the threads' timing, so the field fixes its own):
    // blocks by key in z, y, x order, then the offset within the block.
    using Slots = BlockMap<std::int32_t>;
    for (std::size_t i = 1; i < first.field.size(); ++i) {
        const VoxelKey &a = first.field.keys()[i - 1], &b = first.field.keys()[i];
        const VoxelKey ba = Slots::block_of(a), bb = Slots::block_of(b);
        const auto block_a = std::make_tuple(ba.z(), ba.y(), ba.x()), block_b = std::make_tuple(bb.z(), bb.y(), bb.x());
        ASSERT_TRUE(block_a < block_b || (block_a == block_b && Slots::offset_of(a) < Slots::offset_of(b))) << i;
    }
    for (std::size_t r = 1; r < runs.size(); ++r) {
        EXPECT_EQ(runs[r].evaluated, first.evaluated) << r + 1 << " threads";
        EXPECT_EQ(runs[r].cubes, first.cubes) << r + 1 << " threads";
        ASSERT_EQ(runs[r].field.keys(), first.field.keys()) << r + 1 << " threads";
        for (std::size_t i = 0; i < first.field.size(); ++i) {
            const VertexSample &a = runs[r].field.samples()[i], &b = first.field.samples()[i];
            ASSERT_EQ(std::memcmp(&a.tsdf, &b.tsdf, sizeof a.tsdf), 0) << i;
            ASSERT_EQ(a.level, b.level) << i;
            ASSERT_EQ(a.normal, b.normal) << i;
            // Looking a key up gives its own sample.
            ASSERT_EQ(runs[r].field.find(first.field.keys()[i]), &runs[r].field.samples()[i]) << i;
        }
    }
}

// The phase times (SeededTiming) are disjoint parts of the call: none is negative, the seed wave
// (where a lidar frame's vertices are mostly evaluated) takes time, and together they do not
// exceed the call's wall time measured from outside.
TEST(SeededSurface, PhaseTimesArePartsOfTheCall) {
    const Eigen::Vector3d origin(1.0, -2.0, 0.3);
    const PointCloud cloud = sim::simulate_scan(offroad(), sim::SensorModel::hdl64(), origin, 5);
    VoxelGrid grid(0.2);
    grid.insert(std::span<const Eigen::Vector3d>(cloud.points));
    const auto t0 = std::chrono::steady_clock::now();
    const SeededTsdf s = compute_seeded_tsdf(grid, ReconstructionConfig{}, origin);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const SeededTiming& t = s.timing;
    for (double phase : {t.setup, t.seed_wave, t.later_waves, t.serial, t.field}) EXPECT_GE(phase, 0.0);
    EXPECT_GT(t.seed_wave, 0.0);
    EXPECT_LE(t.setup + t.seed_wave + t.later_waves + t.serial + t.field, wall);
}

// SearchRegion::around against a brute-force Chebyshev distance to the core blocks' cubes.
TEST(SearchRegion, AroundHoldsExactlyTheCubesWithinTheHalo) {
    const std::vector<VoxelKey> core{{0, 0, 0}, {1, 0, 0}, {-2, 3, -1}};
    for (int halo : {0, 1, 3, 8, 11, 20}) {
        const SearchRegion region = SearchRegion::around(core, halo);
        for (int z = -24; z < 16; ++z)
            for (int y = -10; y < 40; ++y)
                for (int x = -30; x < 24; ++x) {
                    int best = 1 << 20;
                    for (const VoxelKey& b : core) {
                        int d = 0;
                        for (int a = 0; a < 3; ++a) {
                            const int c = VoxelKey(x, y, z)[a], lo = 8 * b[a], hi = lo + 7;
                            d = std::max(d, c < lo ? lo - c : (c > hi ? c - hi : 0));
                        }
                        best = std::min(best, d);
                    }
                    ASSERT_EQ(region.contains({x, y, z}), best <= halo) << x << " " << y << " " << z << " halo " << halo;
                }
    }
}

// A search kept to a region finds the unrestricted search's cubes inside it (a subset), with the
// same values at their corners; a region holding every block finds all of them.
TEST(SeededSurface, ARegionSearchIsTheUnrestrictedSearchInsideIt) {
    sim::SimulatorConfig sc;
    sc.gt_beams = 0;
    const sim::Simulator simulator(sim::make_world(sim::SceneConfig{}), sc);
    const PointCloud cloud = simulator.frame(37).scan;
    const ReconstructionConfig c;
    VoxelGrid grid(c.voxel_size);
    grid.insert(cloud.points);
    const SeededTsdf all = compute_seeded_tsdf(grid, c, Eigen::Vector3d::Zero());
    // The blocks within 12 m of the sensor.
    std::vector<VoxelKey> near;
    for (const VoxelKey& b : grid.index().block_keys())
        if ((grid.to_world((b.cast<double>() * 8 + Eigen::Vector3d::Constant(4)) * c.voxel_size)).norm() < 12) near.push_back(b);
    ASSERT_GT(near.size(), 100u);
    const SearchRegion region = SearchRegion::around(near, 2);
    const SeededTsdf part = compute_seeded_tsdf(grid, c, Eigen::Vector3d::Zero(), EigenSolver::ClosedForm, nullptr, &region);
    std::set<std::tuple<int, int, int>> cubes;
    for (const VoxelKey& k : all.cubes) cubes.insert({k.x(), k.y(), k.z()});
    std::size_t inside = 0;
    for (const VoxelKey& k : all.cubes) inside += region.contains(k);
    ASSERT_GT(part.cubes.size(), 0.99 * static_cast<double>(inside));
    for (const VoxelKey& k : part.cubes) {
        ASSERT_TRUE(region.contains(k));
        ASSERT_EQ(cubes.count({k.x(), k.y(), k.z()}), 1u) << "a cube the unrestricted search does not find";
        for (int corner = 0; corner < 8; ++corner) {
            const VoxelKey v = k + corner_offset(corner);
            ASSERT_TRUE(part.field.find(v) && all.field.find(v));
            ASSERT_EQ(part.field.find(v)->tsdf, all.field.find(v)->tsdf);
        }
    }
    // Every block, and every cube a surface can reach from them (a vertex is defined within
    // max_reach of a voxel): the same cubes.
    const SearchRegion whole = SearchRegion::around(grid.index().block_keys(), c.max_reach() + 1);
    const SeededTsdf every = compute_seeded_tsdf(grid, c, Eigen::Vector3d::Zero(), EigenSolver::ClosedForm, nullptr, &whole);
    EXPECT_EQ(every.cubes, all.cubes);
    EXPECT_THROW(compute_seeded_tsdf(grid, c, Eigen::Vector3d::Zero(), EigenSolver::ClosedForm, &all.field, &whole), InvalidArgument);
}
