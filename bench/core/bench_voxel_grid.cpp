// Stage 1: voxel statistics (Sec. III-A), points inserted one by one.
#include <benchmark/benchmark.h>

#include "bench_data.hpp"

namespace lidarsurf::bench {
namespace {

void BM_Insert(benchmark::State& state) {
    for (auto _ : state) benchmark::DoNotOptimize(town_grid().size());
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(town_scan().points.size()));
}
BENCHMARK(BM_Insert)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lidarsurf::bench
