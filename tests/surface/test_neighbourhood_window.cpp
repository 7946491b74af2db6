// The fast path's neighbourhood sums and vertex evaluation against the reference ones: the
// window's raw moments against merge_neighbourhood and merge_box (slabs) (itself checked against a direct computation
// in test_neighbourhood.cpp), and the windowed evaluate_vertex against the reference
// evaluate_vertex, for both eigen solvers, far from the world origin and across block borders.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/vertex_evaluator.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

// A wavy surface with noise, far from the world origin, spanning several blocks.
VoxelGrid wavy_grid(double alpha) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    std::normal_distribution<double> noise(0.0, 0.01);
    VoxelGrid grid(alpha);
    const Eigen::Vector3d offset(3.1e5, 4.2e6, 55.0);
    for (int i = 0; i < 30000; ++i) {
        const double x = u(rng), y = u(rng);
        grid.insert(offset + Eigen::Vector3d(x, y, 0.4 * std::sin(x) * std::cos(0.7 * y) + noise(rng)));
    }
    return grid;
}

VoxelKey vertex_block(const VoxelKey& v) { return BlockMap<std::int32_t>::block_of(v); }

// A vertex at random among the blocks that wavy_grid's surface crosses (several in x and y).
VoxelKey random_vertex(std::mt19937& rng) {
    std::uniform_int_distribution<int> c(-16, 16), cz(-4, 4);
    const int x = c(rng), y = c(rng);
    return {x, y, cz(rng)};
}

std::string describe(const VoxelKey& v, int k) {
    return "v=" + std::to_string(v.x()) + "," + std::to_string(v.y()) + "," + std::to_string(v.z()) + " k=" + std::to_string(k);
}

void expect_same_stats(const VoxelStats& a, const VoxelStats& b, double alpha, const std::string& what) {
    ASSERT_EQ(a.count, b.count) << what;
    if (a.count == 0) return;
    EXPECT_LT((a.mean - b.mean).norm(), 1e-12 * alpha * 100) << what;
    EXPECT_LT((a.scatter.full() - b.scatter.full()).norm(), 1e-9 * alpha * alpha * static_cast<double>(a.count)) << what;
}

}  // namespace

TEST(NeighbourhoodWindow, SumsEqualMergedStatistics) {
    const double alpha = 0.2;
    const VoxelGrid grid = wavy_grid(alpha);
    const PackedVoxels packed(grid);
    std::mt19937 rng(5);
    for (int max_level : {5, 12}) {  // 12 > 8: a window of 5x5x5 blocks
        for (int trial = 0; trial < 200; ++trial) {
            const VoxelKey v = random_vertex(rng);
            const NeighbourhoodWindow window(packed, vertex_block(v), max_level);
            Moments grown, slab;
            const Eigen::Vector3d p = v.cast<double>() * alpha;
            const int first_slab = 1 + trial % 4;  // the slab fallback starts growing at any level
            const SlabExtension e{(trial / 4) % 3, (trial / 12) % 2 * 3};  // radial slabs, along x, y, both or neither
            for (int k = 1; k <= max_level; ++k) {
                window.grow(v, k, grown);
                const VoxelStats reference = merge_neighbourhood(grid, v, k);
                const std::string what = describe(v, k);
                expect_same_stats(grown.to_stats(p), reference, alpha, what + " (grown)");
                expect_same_stats(window.box(v, k).to_stats(p), reference, alpha, what + " (box)");
                if (k < first_slab || k + std::max(e.x, e.y) > max_level) continue;
                if (k == first_slab)
                    slab = window.slab(v, k, e);
                else
                    window.grow_slab(v, k, slab, e);
                const VoxelStats slab_reference = merge_box(grid, slab_box(v, k, e));
                expect_same_stats(slab.to_stats(p), slab_reference, alpha, what + " (slab)");
                expect_same_stats(window.slab(v, k, e).to_stats(p), slab_reference, alpha, what + " (whole slab)");
            }
        }
    }
}

// One window moved from block to block with reset() (as the fast path reuses its few windows)
// sums what merge_neighbourhood does: no block looked up for a previous vertex block survives.
TEST(NeighbourhoodWindow, AResetWindowSumsItsNewBlock) {
    const double alpha = 0.2;
    const VoxelGrid grid = wavy_grid(alpha);
    const PackedVoxels packed(grid);
    std::mt19937 rng(7);
    NeighbourhoodWindow window(packed, VoxelKey::Zero(), 13);  // radius 2, as with the default's radial slabs
    std::size_t compared = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const VoxelKey v = random_vertex(rng);
        window.reset(vertex_block(v));
        const int k = 1 + trial % 13;
        const VoxelStats reference = merge_neighbourhood(grid, v, k);
        compared += reference.count > 0;
        expect_same_stats(window.box(v, k).to_stats(v.cast<double>() * alpha), reference, alpha, describe(v, k));
    }
    EXPECT_GT(compared, 150u);  // most boxes hold points: the comparison is not vacuous
}

TEST(NeighbourhoodWindow, RefusesABoxBeyondItsBlocks) {
    const VoxelGrid grid = wavy_grid(0.2);
    const PackedVoxels packed(grid);
    // Max level 5: one block on each side of vertex block 0, i.e. voxels [-8, 15] per axis.
    const NeighbourhoodWindow window(packed, VoxelKey::Zero(), 5);
    const VoxelKey first(0, 0, 0), last(7, 7, 7);  // the block's first and last vertex
    EXPECT_NO_THROW(window.box(first, 8));         // [-8, 7]
    EXPECT_THROW(window.box(first, 9), InvalidArgument);
    EXPECT_NO_THROW(window.slab(first, 5, {3, 0}));  // x in [-8, 7]
    EXPECT_THROW(window.slab(first, 5, {4, 0}), InvalidArgument);
    EXPECT_THROW(window.slab(first, 5, {0, 4}), InvalidArgument);
    EXPECT_NO_THROW(window.box(last, 9));  // [-2, 15]
    EXPECT_THROW(window.box(last, 10), InvalidArgument);
    EXPECT_NO_THROW(window.slab(last, 5, {4, 0}));  // x in [-2, 15]
    EXPECT_THROW(window.slab(last, 5, {5, 0}), InvalidArgument);
    Moments acc = window.slab(last, 2, {0, 6});
    EXPECT_THROW(window.grow_slab(last, 4, acc, {0, 6}), InvalidArgument);  // y up to 7 + 3 + 6 = 16
}

TEST(NeighbourhoodWindow, VertexEvaluationEqualsTheReference) {
    const double alpha = 0.2;
    const VoxelGrid grid = wavy_grid(alpha);
    const PackedVoxels packed(grid);
    const Eigen::Vector3d sensor = grid.to_local(grid.origin() + Eigen::Vector3d(0.5, -0.3, 2.0));
    std::size_t defined = 0, compared = 0;
    for (Mode mode : {Mode::AdaptiveGaussian, Mode::Adaptive, Mode::ConstantGaussian, Mode::Constant}) {
        SurfaceConfig config;
        config.mode = mode;
        config.k = 3;
        for (EigenSolver solver : {EigenSolver::Iterative, EigenSolver::ClosedForm})
            for (int z = -3; z <= 3; ++z)
                for (int y = -14; y <= 14; y += 2)
                    for (int x = -14; x <= 14; ++x) {
                        const VoxelKey v(x, y, z);
                        const NeighbourhoodWindow window(packed, vertex_block(v), config.max_reach());
                        const VertexSample fast = evaluate_vertex(window, v, config, sensor, solver);
                        const VertexSample ref = evaluate_vertex(grid, v, config, sensor);
                        ++compared;
                        ASSERT_EQ(fast.defined, ref.defined) << to_string(mode) << " v=" << v.transpose();
                        if (!ref.defined) continue;
                        ++defined;
                        EXPECT_EQ(fast.level, ref.level);
                        EXPECT_NEAR(fast.tsdf, ref.tsdf, 1e-6 * alpha);
                        EXPECT_NEAR(fast.confidence, ref.confidence, 1e-5 * std::max(1.0f, ref.confidence));
                        EXPECT_GT(fast.normal.dot(ref.normal), 1.0f - 1e-6f);
                    }
    }
    EXPECT_GT(defined, compared / 4);  // the comparison is not vacuous
}

// The windowed evaluation as the fast path runs it (windows of max_reach() listing cubes up to
// max_level(), the closed-form solver, the default's slabs), at every SIMD level this CPU has:
// the baseline code and the one compiled for AVX2 (core/simd.hpp) give the same samples, bit
// for bit (no FMA anywhere).
TEST(NeighbourhoodWindow, VertexEvaluationIsTheSameBitsAtEverySimdLevel) {
    const double alpha = 0.2;
    const VoxelGrid grid = wavy_grid(alpha);
    const PackedVoxels packed(grid);
    const Eigen::Vector3d sensor = grid.to_local(grid.origin() + Eigen::Vector3d(0.5, -0.3, 2.0));
    const std::vector<SimdLevel> levels = test::simd_levels();
    std::size_t defined = 0, compared = 0;
    for (Mode mode : {Mode::AdaptiveGaussian, Mode::Constant}) {
        SurfaceConfig config;
        config.mode = mode;
        for (int z = -3; z <= 3; ++z)
            for (int y = -14; y <= 14; y += 3)
                for (int x = -14; x <= 14; ++x) {
                    const VoxelKey v(x, y, z);
                    std::vector<VertexSample> samples;
                    for (SimdLevel level : levels) {
                        const test::ScopedSimdLevel scoped(level);
                        const NeighbourhoodWindow window(packed, vertex_block(v), config.max_reach(), config.max_level());
                        samples.push_back(evaluate_vertex(window, v, config, sensor, EigenSolver::ClosedForm));
                    }
                    for (std::size_t l = 1; l < levels.size(); ++l) {
                        const VertexSample &a = samples[0], &b = samples[l];
                        const std::string what = std::string(to_string(mode)) + " " + to_string(levels[l]) + " " + describe(v, 0);
                        ASSERT_EQ(a.defined, b.defined) << what;
                        ASSERT_EQ(a.level, b.level) << what;
                        ASSERT_EQ(std::memcmp(&a.tsdf, &b.tsdf, sizeof a.tsdf), 0) << what;
                        ASSERT_EQ(std::memcmp(&a.confidence, &b.confidence, sizeof a.confidence), 0) << what;
                        ASSERT_TRUE(a.normal == b.normal) << what;
                    }
                    ++compared;
                    defined += samples[0].defined;
                }
    }
    EXPECT_GT(defined, compared / 4);  // the comparison is not vacuous
}

// The voxel list (cubes up to cube_level) adds the very records add_shell adds, in its order: a
// window listing every level and one listing only H^1 (add_shell beyond) grow the same bits.
// The voxel-list sums against the block walk (add_shell, no list): bit for bit, with every list
// scan kernel this CPU runs (core/simd.hpp: SSE2 and AVX2 select the same voxels, in list order).
TEST(NeighbourhoodWindow, ListedCubesEqualTheBlockWalkBitForBit) {
    const double alpha = 0.2;
    const VoxelGrid grid = wavy_grid(alpha);
    const PackedVoxels packed(grid);
    for (SimdLevel level : test::simd_levels()) {
        const test::ScopedSimdLevel scoped(level);
        std::mt19937 rng(13);
        std::size_t nonempty = 0;
        for (int trial = 0; trial < 300; ++trial) {
            const VoxelKey v = random_vertex(rng);
            const NeighbourhoodWindow listed(packed, vertex_block(v), 13, 13), walked(packed, vertex_block(v), 13, 1);
            Moments a, b;
            for (int k = 1; k <= 13; ++k) {
                listed.grow(v, k, a);
                walked.grow(v, k, b);
                ASSERT_EQ(a.n, b.n) << describe(v, k) << " " << to_string(level);
                ASSERT_TRUE(a.s1 == b.s1 && a.s2 == b.s2) << describe(v, k) << " " << to_string(level);  // exact: same additions, same order
                const Moments whole_a = listed.box(v, k), whole_b = walked.box(v, k);
                ASSERT_TRUE(whole_a.n == whole_b.n && whole_a.s1 == whole_b.s1 && whole_a.s2 == whole_b.s2) << describe(v, k) << " " << to_string(level);
            }
            nonempty += a.n > 0;
        }
        EXPECT_GT(nonempty, 200u);
    }
}

// The slab walk ranks records with a byte table (SSE2, portable) or POPCNT (Avx2 level): the same
// voxels in the same order, so the same bits, whole slabs and rings, with and without extension.
TEST(NeighbourhoodWindow, SlabSumsAreTheSameBitsAtEverySimdLevel) {
    const double alpha = 0.2;
    const VoxelGrid grid = wavy_grid(alpha);
    const PackedVoxels packed(grid);
    const std::vector<SimdLevel> levels = test::simd_levels();
    std::mt19937 rng(23);
    std::size_t nonempty = 0;
    for (int trial = 0; trial < 200; ++trial) {
        VoxelKey v = random_vertex(rng);
        v.z() = trial % 5 - 2;  // a slab is two layers: within the surface's +-2 voxels
        const SlabExtension e{trial % 3 == 0 ? 8 : 0, trial % 3 == 1 ? 8 : 0};
        std::vector<Moments> whole(levels.size()), ring(levels.size());
        for (std::size_t l = 0; l < levels.size(); ++l) {
            const test::ScopedSimdLevel scoped(levels[l]);
            const NeighbourhoodWindow window(packed, vertex_block(v), 13, 5);
            whole[l] = window.slab(v, 3, e);
            ring[l] = whole[l];
            window.grow_slab(v, 4, ring[l], e);
            window.grow_slab(v, 5, ring[l], e);
        }
        for (std::size_t l = 1; l < levels.size(); ++l) {
            ASSERT_TRUE(whole[l].n == whole[0].n && whole[l].s1 == whole[0].s1 && whole[l].s2 == whole[0].s2) << describe(v, 3) << " " << to_string(levels[l]);
            ASSERT_TRUE(ring[l].n == ring[0].n && ring[l].s1 == ring[0].s1 && ring[l].s2 == ring[0].s2) << describe(v, 5) << " " << to_string(levels[l]);
        }
        // And the slab of the level in use against the merged statistics (the oracle).
        expect_same_stats(whole.back().to_stats(v.cast<double>() * alpha), merge_box(grid, slab_box(v, 3, e)), alpha, describe(v, 3));
        nonempty += whole[0].n > 0;
    }
    EXPECT_GT(nonempty, 60u);  // the surface lies in one or two of the five layer pairs drawn
}

// Windows of one vertex block sharing its list (the fast path's windows on several threads):
// whichever builds it, each sums what a window with its own list does, and the list is built once;
// the same with the shared list built in the windows' arenas (one each, as one per thread).
TEST(NeighbourhoodWindow, WindowsSharingTheirBlocksListSumTheSame) {
    const double alpha = 0.2;
    const VoxelGrid grid = wavy_grid(alpha);
    const PackedVoxels packed(grid);
    std::mt19937 rng(17);
    for (int trial = 0; trial < 100; ++trial) {
        const VoxelKey v = random_vertex(rng);
        const bool in_arenas = trial % 2 == 1;
        NeighbourhoodWindow::ListArena arena1, arena2;  // outlive `shared`
        NeighbourhoodWindow::SharedList shared;
        NeighbourhoodWindow first(packed, VoxelKey::Zero(), 5), second(packed, vertex_block(v), 5);
        first.reset(vertex_block(v));  // a reused window: reset() then share_list()
        first.share_list(&shared, in_arenas ? &arena1 : nullptr);
        second.share_list(&shared, in_arenas ? &arena2 : nullptr);
        const NeighbourhoodWindow alone(packed, vertex_block(v), 5);
        // Vertices of the same block in turn, through either window.
        for (int i = 0; i < 8; ++i) {
            const VoxelKey u = vertex_block(v) * 8 + VoxelKey(i, (3 * i) % 8, (5 * i) % 8);
            const NeighbourhoodWindow& w = (i + trial) % 2 ? first : second;
            for (int k = 1; k <= 5; ++k) {
                const Moments a = w.box(u, k), b = alone.box(u, k);
                ASSERT_TRUE(a.n == b.n && a.s1 == b.s1 && a.s2 == b.s2) << describe(u, k);
                expect_same_stats(a.to_stats(u.cast<double>() * alpha), merge_neighbourhood(grid, u, k), alpha, describe(u, k));
            }
        }
    }
}

// The arena hands out aligned, disjoint ranges that stay valid until it goes: small requests
// across many chunks and large ones (over a quarter chunk) on their own, interleaved. Each range is
// filled with its own byte, then all are checked after the last allocation.
TEST(NeighbourhoodWindow, ListArenaGivesAlignedDisjointMemory) {
    NeighbourhoodWindow::ListArena arena;
    std::mt19937 rng(23);
    std::uniform_int_distribution<std::size_t> small(1, 20000);
    struct Range {
        std::byte* at;
        std::size_t size;
        std::byte fill;
    };
    std::vector<Range> ranges;
    for (int i = 0; i < 600; ++i) {
        const std::size_t size = i % 50 == 7 ? std::size_t{1} << 20 : small(rng);  // 1 MiB: above a chunk
        auto* at = static_cast<std::byte*>(arena.allocate(size));
        ASSERT_NE(at, nullptr);
        ASSERT_EQ(reinterpret_cast<std::uintptr_t>(at) % alignof(std::max_align_t), 0u) << i;
        const auto fill = static_cast<std::byte>(i % 251);
        std::fill_n(at, size, fill);
        ranges.push_back({at, size, fill});
    }
    for (std::size_t i = 0; i < ranges.size(); ++i)
        ASSERT_EQ(std::count(ranges[i].at, ranges[i].at + ranges[i].size, ranges[i].fill), static_cast<std::ptrdiff_t>(ranges[i].size))
            << "range " << i << " was overwritten";
    // Disjoint, also as address intervals.
    auto address = [](const std::byte* p) { return reinterpret_cast<std::uintptr_t>(p); };
    std::sort(ranges.begin(), ranges.end(), [&](const Range& a, const Range& b) { return address(a.at) < address(b.at); });
    for (std::size_t i = 1; i < ranges.size(); ++i) EXPECT_GE(address(ranges[i].at), address(ranges[i - 1].at) + ranges[i - 1].size) << i;
}

// The level the adaptive loop starts from: against the counts of merge_neighbourhood, on sparse
// and on dense voxels (over 255 points each: the window counts with weights saturated at 255).
TEST(NeighbourhoodWindow, FirstCountedLevelIsTheFirstLevelWithNMinPoints) {
    const double alpha = 0.2;
    VoxelGrid dense(alpha);
    std::mt19937 rng(19);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 40000; ++i) {  // ~400 points per voxel in a 5 x 5 x 4 patch, a few sparse ones around
        const bool sparse = i % 100 == 0;
        const double span = sparse ? 3.0 : 1.0;
        dense.insert(Eigen::Vector3d(u(rng) * span - 0.5 * span, u(rng) * span - 0.5 * span, 0.8 * u(rng) - 0.4));
    }
    // Lone voxels with counts about the saturation, 3 voxels apart (their H^1 and H^2 hold only them).
    const int counts[] = {200, 254, 255, 256, 300, 600};
    for (int c = 0; c < 6; ++c)
        for (int i = 0; i < counts[c]; ++i)
            dense.insert(Eigen::Vector3d((-8.5 + 3 * c + 0.5 * u(rng)) * alpha, (8.3 + 0.4 * u(rng)) * alpha, 0.5 * alpha));
    const VoxelGrid wavy = wavy_grid(alpha);
    std::size_t checked = 0, by_level[4] = {};
    for (const VoxelGrid* grid : std::array<const VoxelGrid*, 2>{&wavy, &dense}) {
        const PackedVoxels packed(*grid);
        for (int z = -3; z <= 3; ++z)
            for (int y = -9; y <= 9; ++y)
                for (int x = -9; x <= 9; ++x) {
                    const VoxelKey v(x, y, z);
                    for (int cube_level : {5, 2, 1}) {
                        // Counted by each list scan kernel (the SSE2 and AVX2 ones saturate 16 or 32 byte lanes).
                        const SimdLevel level = test::simd_levels()[static_cast<std::size_t>(x + y + z + 30) % test::simd_levels().size()];
                        const test::ScopedSimdLevel scoped(level);
                        const NeighbourhoodWindow window(packed, vertex_block(v), 5, cube_level);
                        for (int n_min : {1, 10, 37, 255, 256, 1000}) {
                            int expected = 1;
                            if (n_min <= 255) {  // above, the window does not count: it starts at level 1
                                const int highest = std::min(3, cube_level + 1);
                                while (expected < highest &&
                                       merge_neighbourhood(*grid, v, expected).count < static_cast<std::uint64_t>(n_min))
                                    ++expected;
                            }
                            ASSERT_EQ(window.first_counted_level(v, n_min), expected) << describe(v, 0) << " n_min " << n_min << " cube_level " << cube_level;
                            ++checked;
                            ++by_level[expected];
                        }
                    }
                }
    }
    EXPECT_GT(checked, 10000u);
    for (int level = 1; level <= 3; ++level) EXPECT_GT(by_level[level], 100u) << "level " << level;  // every outcome occurs
}

TEST(NeighbourhoodWindow, RefusesInconsistentLevels) {
    const VoxelGrid grid = wavy_grid(0.2);
    const PackedVoxels packed(grid);
    EXPECT_THROW(NeighbourhoodWindow(packed, VoxelKey::Zero(), 5, 6), InvalidArgument);   // cube_level > max_level
    EXPECT_THROW(NeighbourhoodWindow(packed, VoxelKey::Zero(), 0), InvalidArgument);
    EXPECT_THROW(NeighbourhoodWindow(packed, VoxelKey::Zero(), 65), InvalidArgument);  // region coordinates would not fit a byte
    EXPECT_NO_THROW(NeighbourhoodWindow(packed, VoxelKey::Zero(), 64, 64));
}
