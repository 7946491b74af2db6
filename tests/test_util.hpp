#pragma once
// Helpers shared by the tests: brute-force statistics and mesh topology checks.
#include <algorithm>
#include <array>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <unistd.h>

#include "lidarsurf/core/simd.hpp"
#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/pipeline.hpp"

namespace lidarsurf::test {

/// Every SimdLevel this build can run on this CPU (core/simd.hpp), narrowest first.
inline std::vector<SimdLevel> simd_levels() { return available_simd_levels(); }
/// Runs the scope at `level`, then restores the level in force before.
class ScopedSimdLevel {
public:
    explicit ScopedSimdLevel(SimdLevel level) : before_(simd_level()) { set_simd_level(level); }
    ~ScopedSimdLevel() { set_simd_level(before_); }
    ScopedSimdLevel(const ScopedSimdLevel&) = delete;
    ScopedSimdLevel& operator=(const ScopedSimdLevel&) = delete;

private:
    SimdLevel before_;
};

/// Two-pass mean and population covariance: the oracle for the incremental statistics.
struct DirectStats {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
};
inline DirectStats direct_stats(const std::vector<Eigen::Vector3d>& pts) {
    DirectStats s;
    for (const auto& p : pts) s.mean += p;
    s.mean /= static_cast<double>(pts.size());
    for (const auto& p : pts) s.cov += (p - s.mean) * (p - s.mean).transpose();
    s.cov /= static_cast<double>(pts.size());
    return s;
}

struct Topology {
    std::size_t boundary_edges = 0;     ///< undirected edges used by one triangle
    std::size_t nonmanifold_edges = 0;  ///< undirected edges used by three or more
    std::size_t misoriented_edges = 0;  ///< directed edges used twice (inconsistent winding)
    long euler = 0;                     ///< V - E + F over referenced vertices
};
inline Topology topology(const Mesh& m) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> undirected, directed;
    std::vector<bool> used(m.vertices.size(), false);
    for (const auto& t : m.triangles)
        for (int i = 0; i < 3; ++i) {
            const auto a = t[i], b = t[(i + 1) % 3];
            used[a] = true;
            ++directed[{a, b}];
            ++undirected[{std::min(a, b), std::max(a, b)}];
        }
    Topology topo;
    for (const auto& [e, n] : undirected) {
        if (n == 1) ++topo.boundary_edges;
        if (n > 2) ++topo.nonmanifold_edges;
    }
    for (const auto& [e, n] : directed)
        if (n > 1) ++topo.misoriented_edges;
    const long v = std::count(used.begin(), used.end(), true);
    topo.euler = v - static_cast<long>(undirected.size()) + static_cast<long>(m.triangles.size());
    return topo;
}

inline Eigen::Vector3d triangle_normal(const Mesh& m, const std::array<std::uint32_t, 3>& t) {
    return (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
}

/// A fresh empty directory under the system temp dir, removed with what it holds when the
/// object goes (a test leaves nothing behind).
class TempDir {
public:
    explicit TempDir(const std::string& name) {
        static int counter = 0;
        path_ = std::filesystem::temp_directory_path() /
                ("lidarsurf_test_" + name + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ignored;
        std::filesystem::remove_all(path_, ignored);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }
    operator const std::filesystem::path&() const { return path_; }
    std::filesystem::path operator/(const std::filesystem::path& p) const { return path_ / p; }
    std::string string() const { return path_.string(); }

private:
    std::filesystem::path path_;
};

/// The fast path against the reference: the same triangles, vertices within 1e-6 m.
inline void expect_same_mesh(const Mesh& a, const Mesh& b, const std::string& what) {
    ASSERT_EQ(a.vertices.size(), b.vertices.size()) << what;
    ASSERT_EQ(a.triangles.size(), b.triangles.size()) << what;
    for (std::size_t i = 0; i < a.vertices.size(); ++i) ASSERT_LT((a.vertices[i] - b.vertices[i]).norm(), 1e-6) << what;
    EXPECT_EQ(a.triangles, b.triangles) << what;
}

/// One scan reconstructed twice with the same configuration: through the fast path and through
/// the reference path, each with its reconstruction's summary.
struct FastAndReference {
    Mesh fast, reference;
    ReconstructionSummary fast_summary, reference_summary;
};
inline FastAndReference fast_and_reference(const PointCloud& cloud, const ReconstructionConfig& config, const Eigen::Vector3d& origin) {
    Reconstructor fast(config, origin), reference(config, origin);
    fast.integrate(cloud);
    reference.integrate(cloud);
    FastAndReference r;
    r.fast = fast.extract_mesh(Evaluation::Fast);
    r.reference = reference.extract_mesh(Evaluation::Reference);
    r.fast_summary = fast.summary();
    r.reference_summary = reference.summary();
    return r;
}

/// The same computation done another way (thread counts, incremental extractions): bit for bit.
inline void expect_identical(const Mesh& m, const Mesh& expected, const std::string& what) {
    ASSERT_EQ(m.vertices.size(), expected.vertices.size()) << what;
    ASSERT_EQ(m.triangles.size(), expected.triangles.size()) << what;
    for (std::size_t i = 0; i < m.vertices.size(); ++i) ASSERT_EQ(m.vertices[i], expected.vertices[i]) << what;
    for (std::size_t i = 0; i < m.triangles.size(); ++i) ASSERT_EQ(m.triangles[i], expected.triangles[i]) << what;
    EXPECT_EQ(m.normals, expected.normals) << what;
    EXPECT_EQ(m.confidence, expected.confidence) << what;
}

// The mesh's open edges (in one triangle only), as pairs of positions, the smaller first.
using PositionEdge = std::pair<std::array<double, 3>, std::array<double, 3>>;
inline std::set<PositionEdge> open_edges(const Mesh& m) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
    for (const auto& t : m.triangles)
        for (int e = 0; e < 3; ++e) ++uses[std::minmax(t[e], t[(e + 1) % 3])];
    auto at = [&](std::uint32_t v) { return std::array<double, 3>{m.vertices[v].x(), m.vertices[v].y(), m.vertices[v].z()}; };
    std::set<PositionEdge> out;
    for (const auto& [edge, count] : uses)
        if (count == 1) out.insert(std::minmax(at(edge.first), at(edge.second)));
    return out;
}

}  // namespace lidarsurf::test
