// Builds against an installed lidarsurf and reconstructs a small analytic plane.
#include <cstdio>

#include <lidarsurf/pipeline.hpp>
#include <lidarsurf/version.hpp>

int main() {
    lidarsurf::PointCloud cloud;
    for (int i = 0; i < 60; ++i)
        for (int j = 0; j < 60; ++j) cloud.points.emplace_back(0.05 * i, 0.05 * j, -1.0);
    const lidarsurf::Mesh mesh = lidarsurf::reconstruct(cloud, Eigen::Vector3d::Zero(), lidarsurf::ReconstructionConfig{});
    std::printf("lidarsurf %s: %zu vertices, %zu triangles\n", LIDARSURF_VERSION_STRING, mesh.vertices.size(), mesh.triangles.size());
    return mesh.triangles.empty() ? 1 : 0;
}
