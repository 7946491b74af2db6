// Builds against the installed lidarsurf::sim component: a simulated scan of the analytic scene,
// meshed by the reconstruction it depends on.
#include <cstdio>

#include <lidarsurf/pipeline.hpp>
#include <lidarsurf/sim/analytic_scene.hpp>
#include <lidarsurf/sim/sensor_model.hpp>

int main() {
    const lidarsurf::PointCloud scan =
        lidarsurf::sim::simulate_scan(lidarsurf::sim::AnalyticScene::demo(), lidarsurf::sim::SensorModel::hdl64(), Eigen::Vector3d::Zero(), 1);
    const lidarsurf::Mesh mesh = lidarsurf::reconstruct(scan, Eigen::Vector3d::Zero(), lidarsurf::ReconstructionConfig{});
    std::printf("lidarsurf::sim: %zu points, %zu triangles\n", scan.points.size(), mesh.triangles.size());
    return mesh.triangles.empty() ? 1 : 0;
}
