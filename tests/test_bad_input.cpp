// The bad-input matrix of docs/reliability.md at the library level: each row gives a typed
// exception (never a crash, a hang or a giant allocation) or, for degenerate but well-formed
// clouds, an empty mesh the caller can detect. tests/cli/test_bad_input.sh checks the same rows
// through the CLI (message and exit code).
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <string>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/point_reader.hpp"
#include "lidarsurf/pipeline.hpp"
#include "test_scans.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

enum class Expect { Format, Input, Argument, Resource, Io, Other };

const char* name_of(Expect e) {
    switch (e) {
        case Expect::Format: return "FormatError";
        case Expect::Input: return "InvalidInput";
        case Expect::Argument: return "InvalidArgument";
        case Expect::Resource: return "ResourceLimit";
        case Expect::Io: return "IoError";
        case Expect::Other: return "another lidarsurf::Error";
    }
    return "?";
}

Expect class_of(const Error& e) {
    if (dynamic_cast<const ResourceLimit*>(&e)) return Expect::Resource;
    if (dynamic_cast<const FormatError*>(&e)) return Expect::Format;
    if (dynamic_cast<const InvalidInput*>(&e)) return Expect::Input;
    if (dynamic_cast<const InvalidArgument*>(&e)) return Expect::Argument;
    if (dynamic_cast<const IoError*>(&e)) return Expect::Io;
    return Expect::Other;
}

// Runs `f` and checks it throws exactly the expected lidarsurf error class, with a message
// containing `words`. Another exception type escapes and fails the test.
void expect_error(const std::function<void()>& f, Expect e, const std::string& words, const std::string& row) {
    SCOPED_TRACE(row);
    try {
        f();
        ADD_FAILURE() << "no exception, expected " << name_of(e);
    } catch (const Error& x) {
        EXPECT_STREQ(name_of(class_of(x)), name_of(e)) << x.what();
        EXPECT_NE(std::string(x.what()).find(words), std::string::npos) << x.what();
    }
}

std::string f32(float x) { return std::string(reinterpret_cast<const char*>(&x), sizeof x); }

struct FileRow {
    const char* row;
    const char* extension;
    std::string content;
    const char* words;  // a fragment of the expected message
};

using test::demo_scan;

}  // namespace

TEST(BadInput, MalformedFilesGiveFormatErrors) {
    const std::string ply_head = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    const std::string pcd_head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA binary\n";
    std::string nine_floats;
    for (int i = 0; i < 9; ++i) nine_floats += f32(static_cast<float>(i));
    const std::vector<FileRow> rows = {
        {"empty bin", ".bin", "", "empty"},
        {"empty ply", ".ply", "", "empty"},
        {"empty pcd", ".pcd", "", "empty"},
        {"empty xyz", ".xyz", "", "empty"},
        {"truncated bin (not whole records)", ".bin", nine_floats + "abc", "not a multiple"},
        {"truncated binary ply", ".ply", ply_head + nine_floats.substr(0, 30), "at most"},
        {"truncated binary pcd", ".pcd", pcd_head + nine_floats.substr(0, 30), "PCD"},
        {"truncated ascii ply", ".ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 5\n", "PLY"},
        {"ply without end_header", ".ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "end_header"},
        {"wrong magic ply", ".ply", "plyx\nformat ascii 1.0\nend_header\n", "not a PLY"},
        {"wrong magic pcd", ".pcd", "hello\nworld\n", "PCD"},
        {"wrong ply format", ".ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "format"},
        {"ply without z", ".ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n", "lacks x, y or z"},
        {"ply count above the data", ".ply", "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n", "PLY"},
        {"pcd POINTS above the data", ".pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\nPOINTS 4\nDATA ascii\n1 2 3\n", "PCD"},
        {"ply claims 4e9 points", ".ply", "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n" + nine_floats, "at most"},
        {"pcd claims 3e9 points", ".pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3000000000\nHEIGHT 1\nPOINTS 3000000000\nDATA binary\n" + nine_floats, "PCD"},
        {"text with a word", ".xyz", "1 2 3\n4 5 six\n", "line 2"},
        {"text with two columns", ".xyz", "1 2\n3 4\n", "xyz"},
    };
    const test::TempDir dir("bad_input");
    int i = 0;
    for (const auto& r : rows) {
        const auto path = dir / (std::to_string(i++) + r.extension);
        std::ofstream(path, std::ios::binary) << r.content;
        expect_error([&] { read_points(path); }, Expect::Format, r.words, r.row);
    }
    std::filesystem::remove_all(dir);
}

TEST(BadInput, ParametersOutOfRangeAreRefused) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const std::vector<std::pair<const char*, std::function<void(ReconstructionConfig&)>>> rows = {
        {"voxel size", [](auto& c) { c.voxel_size = 0; }},
        {"voxel size", [](auto& c) { c.voxel_size = -1; }},
        {"voxel size", [nan](auto& c) { c.voxel_size = nan; }},
        {"voxel size", [](auto& c) { c.voxel_size = 1e-9; }},
        {"tau", [](auto& c) { c.tau = 0; }},
        {"tau", [](auto& c) { c.tau = -1; }},
        {"tau", [nan](auto& c) { c.tau = nan; }},
        {"k_max", [](auto& c) { c.k_max = 0; }},
        {"k_max", [](auto& c) { c.k_max = kMaxNeighbourhoodLevel + 1; }},
        {"k_max", [](auto& c) { c.k_max = INT_MAX; }},
        {"n_min", [](auto& c) { c.n_min = 0; }},
        {"max memory", [](auto& c) { c.max_memory_mb = 0; }},
        {"max memory", [nan](auto& c) { c.max_memory_mb = nan; }},
    };
    for (const auto& [words, set] : rows) {
        ReconstructionConfig c;
        set(c);
        expect_error([&] { Reconstructor(c, Eigen::Vector3d::Zero()); }, Expect::Argument, words, words);
    }
    expect_error([] { Reconstructor(ReconstructionConfig{}, Eigen::Vector3d(0, std::nan(""), 0)); }, Expect::Argument, "sensor",
                 "sensor origin NaN");
}

TEST(BadInput, DegenerateCloudsGiveAnEmptyMeshOrATypedError) {
    const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
    const Eigen::Vector3d o = Eigen::Vector3d::Zero();
    expect_error([&] { reconstruct(PointCloud{}, o, {}); }, Expect::Input, "no points", "no point at all");
    expect_error([&] { reconstruct(PointCloud{{{nan, 0, 0}, {inf, 1, 1}, {0, -inf, 2}}}, o, {}); }, Expect::Input, "no finite point",
                 "nothing left after dropping NaN/Inf");
    // Well-formed but without any plane: no triangle, no crash (the CLI reports it, exit 3).
    std::vector<Eigen::Vector3d> line, same(500, Eigen::Vector3d(1, 2, 3));
    for (int i = 0; i < 500; ++i) line.emplace_back(0.01 * i, 0.02 * i, 0.005 * i);
    EXPECT_TRUE(reconstruct(PointCloud{same}, o, {}).triangles.empty()) << "all points identical";
    EXPECT_TRUE(reconstruct(PointCloud{line}, o, {}).triangles.empty()) << "collinear points";
    EXPECT_TRUE(reconstruct(PointCloud{{Eigen::Vector3d(5, 5, 1)}}, o, {}).triangles.empty()) << "a single point";
    // NaN and Inf points among good ones are dropped and counted.
    PointCloud mixed = demo_scan();
    mixed.points.insert(mixed.points.begin() + 10, {{nan, 1, 2}, {inf, 0, 0}, {0, 0, -inf}});
    ReconstructionSummary summary;
    EXPECT_FALSE(reconstruct(mixed, o, {}, &summary).triangles.empty());
    EXPECT_EQ(summary.points_dropped, 3u);
    EXPECT_NE(summary.to_string().find("dropped 3 non-finite"), std::string::npos);
}

TEST(BadInput, CoordinatesAt1e7MetresGiveTheSameMesh) {
    // UTM northings reach 1e7 m: the grid's local origin (a lattice point) keeps every decision.
    const Eigen::Vector3d shift(1.0e7, -1.0e7, 250.0);  // multiples of the voxel size
    PointCloud far = demo_scan();
    for (auto& p : far.points) p += shift;
    const Mesh near_mesh = reconstruct(demo_scan(), Eigen::Vector3d::Zero(), {});
    const Mesh far_mesh = reconstruct(far, shift, {});
    ASSERT_FALSE(near_mesh.triangles.empty());
    ASSERT_EQ(far_mesh.triangles.size(), near_mesh.triangles.size());
    ASSERT_EQ(far_mesh.vertices.size(), near_mesh.vertices.size());
    double worst = 0;
    for (std::size_t i = 0; i < near_mesh.vertices.size(); ++i)
        worst = std::max(worst, (far_mesh.vertices[i] - shift - near_mesh.vertices[i]).norm());
    EXPECT_LT(worst, 1e-6) << "metres";
    EXPECT_EQ(far_mesh.triangles, near_mesh.triangles);
}

TEST(BadInput, ABatchOverTheBudgetLeavesTheReconstructorAsItWas) {
    // The oracle: a Reconstructor with no budget that never saw the refused batch.
    const PointCloud scan = demo_scan();
    PointCloud half, rest;
    for (std::size_t i = 0; i < scan.points.size(); ++i) (i % 2 ? rest : half).points.push_back(scan.points[i]);
    Reconstructor oracle(ReconstructionConfig{}, Eigen::Vector3d::Zero());
    oracle.integrate(half);
    oracle.integrate(rest);
    const double grid_mb = static_cast<double>(oracle.grid().memory_bytes()) / 1048576.0;
    const Mesh expected = oracle.extract_mesh();

    ReconstructionConfig c;
    c.max_memory_mb = std::ceil(3 * grid_mb) + 40;  // the scan fits, with its extraction
    Reconstructor r(c, Eigen::Vector3d::Zero());
    r.integrate(half);
    const std::size_t voxels = r.grid().size(), points = r.grid().point_count();
    // 300k points scattered over a kilometre: a voxel each, far past the budget.
    PointCloud scattered;
    std::uint64_t state = 7;
    auto uniform = [&state] { return static_cast<double>((state = state * 6364136223846793005ULL + 1442695040888963407ULL) >> 11) * 0x1p-53; };
    for (int i = 0; i < 300000; ++i) scattered.points.emplace_back(1000 * uniform() - 500, 1000 * uniform() - 500, 20 * uniform());
    expect_error([&] { r.integrate(scattered); }, Expect::Resource, "nothing of this chunk was integrated", "a batch over the budget");
    EXPECT_EQ(r.grid().size(), voxels);
    EXPECT_EQ(r.grid().point_count(), points);
    r.integrate(rest);  // a later batch that fits is taken
    const Mesh mesh = r.extract_mesh();
    EXPECT_EQ(mesh.triangles, expected.triangles);
    EXPECT_EQ(mesh.vertices.size(), expected.vertices.size());
}

TEST(BadInput, MemoryBudgetRefusesWithTheEstimate) {
    ReconstructionConfig c;
    c.max_memory_mb = 2;  // the demo scan's grid alone is larger
    expect_error([&] { reconstruct(demo_scan(), Eigen::Vector3d::Zero(), c); }, Expect::Resource, "MiB, above the memory budget of 2 MiB",
                 "budget below the grid");
    // A budget the grid fits in but the extraction does not: refused before any TSDF work.
    Reconstructor r(ReconstructionConfig{}, Eigen::Vector3d::Zero());
    r.integrate(demo_scan());
    const double grid_mb = static_cast<double>(kProcessBaselineBytes + r.grid().memory_bytes()) / 1048576.0;
    const double extraction_mb = static_cast<double>(estimate_extraction_bytes(r.grid(), r.config(), Evaluation::Fast)) / 1048576.0;
    ASSERT_GT(extraction_mb, 1.0);
    c.max_memory_mb = std::ceil(grid_mb + 0.5 * extraction_mb);
    Reconstructor tight(c, Eigen::Vector3d::Zero());
    tight.integrate(demo_scan());
    expect_error([&] { tight.extract_mesh(); }, Expect::Resource, "the surface extraction would need about", "budget below the extraction");
    c.max_memory_mb = std::ceil(grid_mb + extraction_mb) + 1;
    Reconstructor enough(c, Eigen::Vector3d::Zero());
    enough.integrate(demo_scan());
    EXPECT_FALSE(enough.extract_mesh().triangles.empty());
    // The reference path dilates every voxel by k_max: its estimate is the larger one.
    EXPECT_GT(estimate_extraction_bytes(r.grid(), r.config(), Evaluation::Reference), static_cast<std::size_t>(extraction_mb * 1048576.0));
}

// A part of a map meshed apart (fuse's squares, tiles) is checked against what its search can
// reach, not against the whole grid: a budget between the two meshes the part and refuses the
// whole. A region holding every block counts what the whole grid counts.
TEST(BadInput, MemoryBudgetOfAPartCountsThePart) {
    // A road 400 m long and 4 m wide seen from 1.7 m above its start, a point every 10 cm.
    PointCloud road;
    for (int i = 0; i < 4000; ++i)
        for (int j = 0; j < 40; ++j) road.points.emplace_back(0.1 * i, -2.0 + 0.1 * j, -1.7 + 0.002 * ((i * 7 + j * 3) % 5));
    Reconstructor r(ReconstructionConfig{}, Eigen::Vector3d::Zero());
    r.integrate(road);
    const VoxelGrid& grid = r.grid();
    const std::size_t whole = estimate_extraction_bytes(grid, r.config(), Evaluation::Fast);
    const SearchRegion all = SearchRegion::around(grid.index().block_keys(), 0);
    EXPECT_EQ(estimate_extraction_bytes(grid, r.config(), Evaluation::Fast, SIZE_MAX, &all), whole);
    // The blocks of the road's first 10 m, and the cubes within 2 of them.
    std::vector<VoxelKey> near;
    for (const VoxelKey& b : grid.index().block_keys())
        if (grid.to_world((b.cast<double>() * 8 + Eigen::Vector3d::Constant(4)) * grid.voxel_size()).x() < 10) near.push_back(b);
    ASSERT_GT(near.size(), 10u);
    const SearchRegion region = SearchRegion::around(near, 2);
    const std::size_t part = estimate_extraction_bytes(grid, r.config(), Evaluation::Fast, SIZE_MAX, &region);
    ASSERT_LT(part, whole / 2) << "the part reaches a fraction of the scan's blocks";
    ReconstructionConfig c;
    c.max_memory_mb = std::ceil(static_cast<double>(kProcessBaselineBytes + r.map_bytes() + (part + whole) / 2) / 1048576.0);
    Reconstructor tight(c, Eigen::Vector3d::Zero());
    tight.integrate(road);
    expect_error([&] { tight.extract_mesh(); }, Expect::Resource, "the surface extraction would need about", "the whole map over the budget");
    EXPECT_FALSE(tight.extract_mesh(region, [](const VoxelKey&) { return true; }).triangles.empty()) << "the part fits";
}
