// Stage 1: voxel statistics (Sec. III-A): points inserted one by one, and the batch insert
// (parallel keys and per-voxel updates; the pipeline's path) on one thread and on all.
#include <benchmark/benchmark.h>

#include <span>

#include <tbb/task_arena.h>

#include "bench_data.hpp"

namespace lidarsurf::bench {
namespace {

void BM_Insert(benchmark::State& state) {
    for (auto _ : state) benchmark::DoNotOptimize(town_grid().size());
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(town_scan().points.size()));
}
BENCHMARK(BM_Insert)->Unit(benchmark::kMillisecond);

// Argument: threads (0 = all).
void BM_InsertBatch(benchmark::State& state) {
    const auto& points = town_scan().points;
    tbb::task_arena arena(state.range(0) > 0 ? static_cast<int>(state.range(0)) : tbb::task_arena::automatic);
    for (auto _ : state)
        arena.execute([&] {
            VoxelGrid g(0.2);
            g.insert(std::span<const Eigen::Vector3d>(points));
            benchmark::DoNotOptimize(g.size());
        });
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points.size()));
}
BENCHMARK(BM_InsertBatch)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace lidarsurf::bench
