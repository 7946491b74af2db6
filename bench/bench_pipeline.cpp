// Google Benchmark micro-benchmarks per stage on the simulated demo scan.
#include <benchmark/benchmark.h>

#include "lidarsurf/core/voxel_grid.hpp"
#include "lidarsurf/mesh/marching_cubes.hpp"
#include "lidarsurf/sim/analytic_scene.hpp"
#include "lidarsurf/sim/sensor_model.hpp"
#include "lidarsurf/surface/seeded_surface.hpp"
#include "lidarsurf/surface/tsdf_field.hpp"

using namespace lidarsurf;

namespace {

const PointCloud& scan() {
    static const PointCloud c = sim::simulate_scan(sim::AnalyticScene::demo(), sim::SensorModel::hdl64(), Eigen::Vector3d::Zero(), 1);
    return c;
}
VoxelGrid make_grid() {
    VoxelGrid g(0.2);
    for (const auto& p : scan().points) g.insert(p);
    return g;
}

void BM_Insert(benchmark::State& state) {
    for (auto _ : state) benchmark::DoNotOptimize(make_grid().size());
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scan().points.size()));
}
BENCHMARK(BM_Insert)->Unit(benchmark::kMillisecond);

void BM_CandidateVertices(benchmark::State& state) {
    const VoxelGrid g = make_grid();
    for (auto _ : state) benchmark::DoNotOptimize(candidate_vertices(g, 5).size());
}
BENCHMARK(BM_CandidateVertices)->Unit(benchmark::kMillisecond);

void BM_Tsdf(benchmark::State& state) {
    const VoxelGrid g = make_grid();
    for (auto _ : state) benchmark::DoNotOptimize(compute_tsdf(g, ReconstructionConfig{}, Eigen::Vector3d::Zero()).size());
}
BENCHMARK(BM_Tsdf)->Unit(benchmark::kMillisecond);

// The fast path (issue 5): the seeded search with lazy vertex evaluation, against BM_Tsdf above
// (the reference evaluates every candidate vertex).
void BM_SeededTsdf(benchmark::State& state) {
    const VoxelGrid g = make_grid();
    for (auto _ : state) benchmark::DoNotOptimize(compute_seeded_tsdf(g, ReconstructionConfig{}, Eigen::Vector3d::Zero()).cubes.size());
}
BENCHMARK(BM_SeededTsdf)->Unit(benchmark::kMillisecond);

void BM_SeededMarchingCubes(benchmark::State& state) {
    const VoxelGrid g = make_grid();
    const SeededTsdf s = compute_seeded_tsdf(g, ReconstructionConfig{}, Eigen::Vector3d::Zero());
    for (auto _ : state) benchmark::DoNotOptimize(extract_mesh(s.field, s.cubes).triangles.size());
}
BENCHMARK(BM_SeededMarchingCubes)->Unit(benchmark::kMillisecond);

void BM_MarchingCubes(benchmark::State& state) {
    const VoxelGrid g = make_grid();
    const TsdfField f = compute_tsdf(g, ReconstructionConfig{}, Eigen::Vector3d::Zero());
    for (auto _ : state) benchmark::DoNotOptimize(extract_mesh(f).triangles.size());
}
BENCHMARK(BM_MarchingCubes)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
