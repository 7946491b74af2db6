// A peer for the accuracy benchmark: PCL 1.13's moving least squares (MLS) smoothing
// followed by greedy projection triangulation, the mesher many robotics users have from PCL. Run
// on a sequence, it writes the layout `lidarsurf benchmark --peers` reads:
//   OUT/pcl-mls-gp/NNNNNN.ply and OUT/pcl-mls-gp/times.txt ("frame seconds").
// Built only with -DLIDARSURF_BUILD_PCL_PEER=ON (PCL is a heavy dependency; see docs/benchmarks.md).
//
// Usage: lidarsurf_pcl_peer SEQ OUT [--frames N] [--stride S]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <pcl/features/normal_3d.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/surface/gp3.h>
#include <pcl/surface/mls.h>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/kitti_sequence.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "lidarsurf/io/point_reader.hpp"

namespace fs = std::filesystem;

namespace {

// Settings at the scale of a street scan (the PCL tutorial's are for a 0.2 m object):
constexpr double kMlsRadius = 0.3;        // MLS support, metres (1.5 voxels of lidarsurf's default)
constexpr double kTriangleRadius = 0.5;   // longest triangle edge, metres
constexpr double kMu = 2.5;               // edge limit relative to the local point spacing
constexpr int kMaxNeighbours = 100;

lidarsurf::Mesh mesh_frame(const lidarsurf::PointCloud& scan) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->reserve(scan.points.size());
    for (const auto& p : scan.points) cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())));

    // MLS: smoothed points with normals (polynomial order 2).
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    pcl::MovingLeastSquares<pcl::PointXYZ, pcl::PointNormal> mls;
    mls.setInputCloud(cloud);
    mls.setSearchMethod(tree);
    mls.setSearchRadius(kMlsRadius);
    mls.setPolynomialOrder(2);
    mls.setComputeNormals(true);
    pcl::PointCloud<pcl::PointNormal>::Ptr smoothed(new pcl::PointCloud<pcl::PointNormal>);
    mls.process(*smoothed);
    // Normals toward the sensor at the origin (the rule of the paper's Eq. 2).
    for (auto& p : smoothed->points)
        if (p.normal_x * -p.x + p.normal_y * -p.y + p.normal_z * -p.z < 0) {
            p.normal_x = -p.normal_x;
            p.normal_y = -p.normal_y;
            p.normal_z = -p.normal_z;
        }

    pcl::search::KdTree<pcl::PointNormal>::Ptr tree2(new pcl::search::KdTree<pcl::PointNormal>);
    tree2->setInputCloud(smoothed);
    pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
    gp3.setSearchRadius(kTriangleRadius);
    gp3.setMu(kMu);
    gp3.setMaximumNearestNeighbors(kMaxNeighbours);
    gp3.setMaximumSurfaceAngle(M_PI / 4);
    gp3.setMinimumAngle(M_PI / 18);
    gp3.setMaximumAngle(2 * M_PI / 3);
    gp3.setNormalConsistency(false);
    gp3.setInputCloud(smoothed);
    gp3.setSearchMethod(tree2);
    std::vector<pcl::Vertices> polygons;
    gp3.reconstruct(polygons);

    lidarsurf::Mesh mesh;
    mesh.vertices.reserve(smoothed->size());
    for (const auto& p : smoothed->points) mesh.vertices.emplace_back(p.x, p.y, p.z);
    for (const auto& poly : polygons)
        if (poly.vertices.size() == 3)
            mesh.triangles.push_back({static_cast<std::uint32_t>(poly.vertices[0]), static_cast<std::uint32_t>(poly.vertices[1]),
                                      static_cast<std::uint32_t>(poly.vertices[2])});
    return mesh;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s SEQ OUT [--frames N] [--stride S]\n", argv[0]);
        return 2;
    }
    long frames = 0, stride = 1;
    for (int i = 3; i + 1 < argc; i += 2) {
        const std::string opt = argv[i];
        const long value = std::strtol(argv[i + 1], nullptr, 10);
        if (opt == "--frames" && value >= 0) frames = value;
        else if (opt == "--stride" && value >= 1) stride = value;
        else {
            std::fprintf(stderr, "lidarsurf_pcl_peer: bad option %s %s\n", argv[i], argv[i + 1]);
            return 2;
        }
    }
    try {
        const lidarsurf::KittiSequence seq{argv[1]};
        const fs::path out = fs::path(argv[2]) / "pcl-mls-gp";
        fs::create_directories(out);
        std::ofstream times(out / "times.txt");
        const std::size_t count = seq.frame_count();
        long done = 0;
        for (std::size_t i = 0; i < count; i += static_cast<std::size_t>(stride)) {
            if (frames > 0 && done == frames) break;
            lidarsurf::PointCloud scan = lidarsurf::read_points(seq.scan(i));
            lidarsurf::drop_non_finite(scan);
            const auto t0 = std::chrono::steady_clock::now();
            const lidarsurf::Mesh mesh = mesh_frame(scan);
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            lidarsurf::write_mesh(mesh, out / (lidarsurf::KittiSequence::frame_name(i) + ".ply"));
            times << i << ' ' << seconds << '\n' << std::flush;
            std::printf("pcl: frame %zu: %zu triangles, %.2f s\n", i, mesh.triangles.size(), seconds);
            ++done;
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "lidarsurf_pcl_peer: %s\n", e.what());
        return 1;
    }
    return 0;
}
