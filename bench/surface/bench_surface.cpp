// Stages 2-3: neighbourhood statistics, plane + confidence, and the whole TSDF, each as the
// reference and as the fast path, on the vertices of the town frame's seeded surface.
#include <benchmark/benchmark.h>

#include <map>
#include <tuple>

#include "bench_data.hpp"
#include "lidarsurf/surface/neighbourhood.hpp"
#include "lidarsurf/surface/neighbourhood_window.hpp"
#include "lidarsurf/surface/plane_eigen.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"

namespace lidarsurf::bench {
namespace {

const VoxelGrid& grid() {
    static const VoxelGrid g = town_grid();
    return g;
}
// A sample of the vertices the fast path evaluates: the defined ones of its field.
const std::vector<VoxelKey>& vertices() {
    static const std::vector<VoxelKey> v = [] {
        const SeededTsdf s = compute_seeded_tsdf(grid(), SurfaceConfig{}, Eigen::Vector3d::Zero());
        std::vector<VoxelKey> out;
        for (std::size_t i = 0; i < s.field.keys().size(); i += 7) out.push_back(s.field.keys()[i]);
        return out;
    }();
    return v;
}

// H^1..H^5 of each vertex, shell by shell: Chan merges through the grid (reference) ...
void BM_NeighbourhoodReference(benchmark::State& state) {
    for (auto _ : state)
        for (const VoxelKey& v : vertices()) {
            VoxelStats acc;
            for (int k = 1; k <= 5; ++k) grow_neighbourhood(grid(), v, k, acc);
            benchmark::DoNotOptimize(acc.count);
        }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(vertices().size()));
}
BENCHMARK(BM_NeighbourhoodReference)->Unit(benchmark::kMillisecond);

// ... and raw moments through a NeighbourhoodWindow (fast path): Arg 0 walks the window's blocks
// for every shell above H^1 (the pre-session-16 sums), Arg 1 reads the cube voxel list, one per
// vertex block shared by that block's windows and built on first use, as compute_seeded_tsdf does.
void BM_NeighbourhoodWindow(benchmark::State& state) {
    const PackedVoxels packed(grid());
    const bool listed = state.range(0) == 1;
    for (auto _ : state) {
        std::map<std::tuple<int, int, int>, NeighbourhoodWindow::SharedList> lists;  // nodes stay in place
        for (const VoxelKey& v : vertices()) {
            const VoxelKey b = BlockMap<std::int32_t>::block_of(v);
            NeighbourhoodWindow w(packed, b, 5, listed ? 5 : 1);
            if (listed) w.share_list(&lists[{b.x(), b.y(), b.z()}]);
            Moments acc;
            for (int k = 1; k <= 5; ++k) w.grow(v, k, acc);
            benchmark::DoNotOptimize(acc.n);
        }
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(vertices().size()));
    state.SetLabel(listed ? "voxel list" : "block walk");
}
BENCHMARK(BM_NeighbourhoodWindow)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Plane (Eq. 1-2) + Gaussian confidence (Eq. 3) on H^3 of each vertex, per eigen solver.
void BM_PlaneAndConfidence(benchmark::State& state) {
    const auto solver = static_cast<EigenSolver>(state.range(0));
    std::vector<VoxelStats> stats;
    for (const VoxelKey& v : vertices()) stats.push_back(merge_neighbourhood(grid(), v, 3));
    const SurfaceConfig c;
    for (auto _ : state)
        for (std::size_t i = 0; i < stats.size(); ++i)
            benchmark::DoNotOptimize(evaluate_level(stats[i], 3, vertices()[i].cast<double>() * 0.2, c, Eigen::Vector3d::Zero(),
                                                    degenerate_lambda2(0.2), solver));
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(stats.size()));
    state.SetLabel(solver == EigenSolver::Iterative ? "iterative" : "closed form");
}
BENCHMARK(BM_PlaneAndConfidence)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The closed-form eigen solver alone on the covariances of H^3 of each vertex: one call per
// matrix (0) against four matrices per call in AVX2 lanes (1; four calls below the Avx2 level).
void BM_PlaneEigen(benchmark::State& state) {
    std::vector<Eigen::Matrix3d> covariances;
    for (const VoxelKey& v : vertices())
        if (const VoxelStats s = merge_neighbourhood(grid(), v, 3); s.count >= 3) covariances.push_back(s.covariance());
    covariances.resize(covariances.size() / 4 * 4);
    const bool lanes = state.range(0) != 0;
    for (auto _ : state) {
        if (lanes)
            for (std::size_t i = 0; i < covariances.size(); i += 4)
                benchmark::DoNotOptimize(plane_eigen4({covariances[i], covariances[i + 1], covariances[i + 2], covariances[i + 3]}));
        else
            for (const Eigen::Matrix3d& c : covariances) benchmark::DoNotOptimize(plane_eigen(c));
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(covariances.size()));
    state.SetLabel(lanes ? "four lanes" : "one by one");
}
BENCHMARK(BM_PlaneEigen)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The whole TSDF stage: every candidate vertex (reference) vs the seeded fast path.
void BM_TsdfReference(benchmark::State& state) {
    for (auto _ : state) benchmark::DoNotOptimize(compute_tsdf(grid(), SurfaceConfig{}, Eigen::Vector3d::Zero()).size());
}
BENCHMARK(BM_TsdfReference)->Unit(benchmark::kMillisecond)->Iterations(2);

void BM_TsdfFast(benchmark::State& state) {
    for (auto _ : state)
        benchmark::DoNotOptimize(compute_seeded_tsdf(grid(), SurfaceConfig{}, Eigen::Vector3d::Zero()).cubes.size());
}
BENCHMARK(BM_TsdfFast)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lidarsurf::bench
