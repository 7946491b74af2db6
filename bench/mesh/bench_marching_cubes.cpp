// Stage 4: marching cubes over the seeded cubes of the town frame.
#include <benchmark/benchmark.h>

#include "bench_data.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/surface/config.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"

namespace lidarsurf::bench {
namespace {

void BM_MarchingCubes(benchmark::State& state) {
    const VoxelGrid g = town_grid();
    const SeededTsdf s = compute_seeded_tsdf(g, SurfaceConfig{}, Eigen::Vector3d::Zero());
    for (auto _ : state) benchmark::DoNotOptimize(extract_mesh(s.field, s.cubes).triangles.size());
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(s.cubes.size()));
}
BENCHMARK(BM_MarchingCubes)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lidarsurf::bench

BENCHMARK_MAIN();
