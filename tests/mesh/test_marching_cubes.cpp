#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <tuple>
#include <random>

#include <tbb/task_arena.h>

#include "lidarsurf/mesh/marching_cubes.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

TsdfField sample_field(double alpha, int half, const std::function<double(const Eigen::Vector3d&)>& f) {
    TsdfField field;
    field.voxel_size = alpha;
    for (int z = -half; z <= half; ++z)
        for (int y = -half; y <= half; ++y)
            for (int x = -half; x <= half; ++x) {
                const Eigen::Vector3d p = alpha * Eigen::Vector3d(x, y, z);
                VertexSample s;
                s.defined = true;
                s.tsdf = static_cast<float>(f(p));
                s.level = 1;
                s.normal = p.normalized().cast<float>();
                field.insert({x, y, z}, s);
            }
    return field;
}

TEST(MarchingCubes, SphereIsAccurateClosedManifoldAndOutward) {
    const double alpha = 0.1, r = 1.03;
    const Eigen::Vector3d centre(0.013, -0.021, 0.007);  // off-lattice
    const TsdfField field = sample_field(alpha, 14, [&](const Eigen::Vector3d& p) { return (p - centre).norm() - r; });
    const Mesh mesh = extract_mesh(field);
    ASSERT_GT(mesh.triangles.size(), 1000u);
    for (const auto& v : mesh.vertices) EXPECT_LT(std::fabs((v - centre).norm() - r), 0.05 * alpha);
    const auto topo = test::topology(mesh);
    EXPECT_EQ(topo.boundary_edges, 0u);
    EXPECT_EQ(topo.nonmanifold_edges, 0u);
    EXPECT_EQ(topo.misoriented_edges, 0u);
    EXPECT_EQ(topo.euler, 2);  // a sphere
    for (const auto& t : mesh.triangles) {
        const Eigen::Vector3d c = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0;
        const Eigen::Vector3d n = test::triangle_normal(mesh, t);
        EXPECT_GT(n.norm(), 0.0);                    // no zero-area triangle
        EXPECT_GT(n.dot(c - centre), 0.0);           // front face toward the positive (outer) side
    }
    // Welded: no two vertices at the same place.
    std::vector<Eigen::Vector3d> sorted = mesh.vertices;
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3); });
    for (std::size_t i = 1; i < sorted.size(); ++i) EXPECT_GT((sorted[i] - sorted[i - 1]).norm(), 1e-9);
    ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
    ASSERT_EQ(mesh.levels.size(), mesh.vertices.size());
}

TEST(MarchingCubes, SnappedVerticesLieOnTheNearerEndsPlane) {
    // A tilted plane n.p = d, given at every lattice vertex as (tsdf, normal): the plane of each
    // lattice vertex is the plane itself, so snapped vertices lie on it to rounding, and snapping
    // moves vertices only (same triangles).
    const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
    const double d = 0.037, alpha = 0.2;
    TsdfField field = sample_field(alpha, 6, [&](const Eigen::Vector3d& p) { return n.dot(p) - d; });
    std::vector<VoxelKey> keys = field.keys();
    TsdfField tilted;
    tilted.voxel_size = alpha;
    for (const VoxelKey& k : keys) {
        VertexSample s = *field.find(k);
        s.normal = n.cast<float>();
        tilted.insert(k, s);
    }
    const Mesh a = extract_mesh(tilted, VertexPlacement::Interpolated);
    const Mesh b = extract_mesh(tilted, VertexPlacement::SnappedToPlane);
    ASSERT_GT(a.triangles.size(), 50u);
    EXPECT_EQ(a.triangles, b.triangles);
    for (const auto& v : b.vertices) EXPECT_NEAR(n.dot(v), d, 1e-6);  // float normals and values
}

TEST(MarchingCubes, SnappingOntoTangentPlanesKeepsASphereAccurate) {
    // Exact sphere SDF with radial normals: each lattice vertex's plane is the tangent plane at its
    // closest sphere point, so a snapped vertex is off the sphere by at most the sagitta over one
    // cube diagonal, (sqrt(3) alpha)^2 / (2 r).
    const double alpha = 0.1, r = 1.03;
    const TsdfField field = sample_field(alpha, 14, [&](const Eigen::Vector3d& p) { return p.norm() - r; });
    const Mesh mesh = extract_mesh(field, VertexPlacement::SnappedToPlane);
    ASSERT_GT(mesh.triangles.size(), 1000u);
    const double sagitta = 3 * alpha * alpha / (2 * r);
    for (const auto& v : mesh.vertices) EXPECT_LT(std::fabs(v.norm() - r), sagitta);
    const auto topo = test::topology(mesh);
    EXPECT_EQ(topo.boundary_edges, 0u);
    EXPECT_EQ(topo.euler, 2);
}

TEST(MarchingCubes, RandomFieldsGiveClosedConsistentlyOrientedSurfaces) {
    // Random values exercise every cube configuration and both face ambiguities; a positive border
    // makes every component closed. Properties checked: no boundary, manifold edges, coherent winding.
    std::mt19937 rng(1234);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 20; ++trial) {
        const int half = 4;
        TsdfField field;
        field.voxel_size = 1.0;
        for (int z = -half; z <= half; ++z)
            for (int y = -half; y <= half; ++y)
                for (int x = -half; x <= half; ++x) {
                    VertexSample s;
                    s.defined = true;
                    const bool border = std::abs(x) == half || std::abs(y) == half || std::abs(z) == half;
                    double v = border ? 0.5 + 0.5 * std::fabs(u(rng)) : u(rng);
                    if (std::fabs(v) < 1e-3) v = 1e-3;  // keep away from exact zeros (collapsed vertices)
                    s.tsdf = static_cast<float>(v);
                    s.normal = {0, 0, 1};
                    field.insert({x, y, z}, s);
                }
        const Mesh mesh = extract_mesh(field);
        ASSERT_FALSE(mesh.triangles.empty());
        const auto topo = test::topology(mesh);
        EXPECT_EQ(topo.boundary_edges, 0u) << "trial " << trial;
        EXPECT_EQ(topo.nonmanifold_edges, 0u) << "trial " << trial;
        EXPECT_EQ(topo.misoriented_edges, 0u) << "trial " << trial;
    }
}

TEST(MarchingCubes, PlaneThroughLatticeZerosHasNoDegenerateTriangles) {
    // f = z exactly zero on a lattice layer: crossings collapse onto lattice vertices.
    const TsdfField field = sample_field(0.5, 3, [](const Eigen::Vector3d& p) { return p.z(); });
    const Mesh mesh = extract_mesh(field);
    ASSERT_FALSE(mesh.triangles.empty());
    for (const auto& t : mesh.triangles) {
        EXPECT_NE(t[0], t[1]);
        EXPECT_NE(t[1], t[2]);
        EXPECT_NE(t[0], t[2]);
        EXPECT_GT(test::triangle_normal(mesh, t).norm(), 1e-9);
    }
    for (const auto& v : mesh.vertices) EXPECT_NEAR(v.z(), 0.0, 1e-12);
}

TEST(MarchingCubes, CubesWithAnUndefinedCornerAreSkipped) {
    TsdfField full = sample_field(0.25, 4, [](const Eigen::Vector3d& p) { return p.z() - 0.1; });
    TsdfField half;
    half.voxel_size = 0.25;
    for (std::size_t i = 0; i < full.size(); ++i)
        if (full.keys()[i].x() <= 0) half.insert(full.keys()[i], full.samples()[i]);
    const Mesh mesh = extract_mesh(half);
    ASSERT_FALSE(mesh.triangles.empty());
    for (const auto& v : mesh.vertices) EXPECT_LE(v.x(), 1e-12);
    EXPECT_LT(extract_mesh(half).triangles.size(), extract_mesh(full).triangles.size());
}

}  // namespace

// The cube list is meshed in parallel runs (one welding table each, joined in order); the result
// must not depend on the number of runs (set by the thread count): the same vertices and
// triangles in the same order, a closed welded sphere, and the same geometry as one serial pass
// (a list that is not sorted by z is meshed in one run).
TEST(MarchingCubes, ParallelRunsGiveTheSerialMeshWhateverTheThreadCount) {
    const double alpha = 0.1, r = 4.1;
    const Eigen::Vector3d centre(0.013, -0.021, 0.007);
    TsdfField field;
    field.voxel_size = alpha;
    std::vector<VoxelKey> cubes;
    const int half = 43;
    for (int z = -half; z <= half; ++z)
        for (int y = -half; y <= half; ++y)
            for (int x = -half; x <= half; ++x) {
                const Eigen::Vector3d p = alpha * Eigen::Vector3d(x, y, z);
                const double f = (p - centre).norm() - r;
                if (std::fabs(f) > 2 * alpha) continue;  // a narrow band around the sphere
                VertexSample s;
                s.defined = true;
                s.tsdf = static_cast<float>(f);
                s.level = 1;
                s.normal = (p - centre).normalized().cast<float>();
                field.insert({x, y, z}, s);
                cubes.emplace_back(x, y, z);  // (z, y, x) order
            }
    ASSERT_GT(cubes.size(), 8u * 4096u);  // enough for several runs per thread
    auto mesh_with = [&](int threads, const std::vector<VoxelKey>& list) {
        tbb::task_arena arena(threads);
        Mesh m;
        arena.execute([&] { m = extract_mesh(field, list); });
        return m;
    };
    const Mesh one = mesh_with(1, cubes);
    const auto topo = test::topology(one);
    EXPECT_EQ(topo.boundary_edges, 0u);
    EXPECT_EQ(topo.nonmanifold_edges, 0u);
    EXPECT_EQ(topo.euler, 2);
    for (int threads : {2, 3}) {
        const Mesh m = mesh_with(threads, cubes);
        ASSERT_EQ(m.vertices.size(), one.vertices.size()) << threads;
        ASSERT_EQ(m.triangles.size(), one.triangles.size()) << threads;
        for (std::size_t i = 0; i < m.vertices.size(); ++i) ASSERT_EQ(m.vertices[i], one.vertices[i]) << threads;
        for (std::size_t i = 0; i < m.triangles.size(); ++i) ASSERT_EQ(m.triangles[i], one.triangles[i]) << threads;
    }
    std::vector<VoxelKey> reversed(cubes.rbegin(), cubes.rend());
    const Mesh serial = mesh_with(2, reversed);
    ASSERT_EQ(serial.vertices.size(), one.vertices.size());
    ASSERT_EQ(serial.triangles.size(), one.triangles.size());
    auto sorted = [](std::vector<Eigen::Vector3d> v) {
        std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3); });
        return v;
    };
    EXPECT_EQ(sorted(serial.vertices), sorted(one.vertices));
}

// extract_meshes: each group's mesh is extract_mesh() of that group alone, whatever the threads
// (the shared welding tables are emptied between groups).
TEST(MarchingCubes, GroupsAreMeshedAsIfAlone) {
    const TsdfField field = sample_field(0.1, 20, [](const Eigen::Vector3d& p) { return p.norm() - 1.33; });
    std::vector<VoxelKey> cubes;
    for (const VoxelKey& k : field.keys())
        if (k.x() < 20 && k.y() < 20 && k.z() < 20) cubes.push_back(k);
    // Groups: the cubes of each 8^3 block, blocks in the order of their first cube.
    std::map<std::tuple<int, int, int>, std::vector<VoxelKey>> by_block;
    for (const VoxelKey& k : cubes) {
        const VoxelKey b = BlockMap<std::int32_t>::block_of(k);
        by_block[{b.z(), b.y(), b.x()}].push_back(k);
    }
    std::vector<VoxelKey> grouped;
    std::vector<std::size_t> starts{0};
    std::vector<std::vector<VoxelKey>> groups;
    for (const auto& [key, list] : by_block) {
        grouped.insert(grouped.end(), list.begin(), list.end());
        starts.push_back(grouped.size());
        groups.push_back(list);
    }
    ASSERT_GT(groups.size(), 8u);
    for (int threads : {1, 2}) {
        tbb::task_arena arena(threads);
        std::vector<Mesh> meshes;
        arena.execute([&] { meshes = extract_meshes(field, grouped, starts); });
        ASSERT_EQ(meshes.size(), groups.size());
        std::size_t triangles = 0;
        for (std::size_t g = 0; g < groups.size(); ++g) {
            test::expect_identical(meshes[g], extract_mesh(field, groups[g]), "group " + std::to_string(g));
            triangles += meshes[g].triangles.size();
        }
        EXPECT_EQ(triangles, extract_mesh(field, grouped).triangles.size());
    }
}
