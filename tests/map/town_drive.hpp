#pragma once
// A short drive through the project's town (6 HDL-64E scans over 120 m, in the world frame) and
// triangles compared whatever the vertex numbering: the live mesh's and the live view's tests.
#include <algorithm>
#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "lidarsurf/mesh/mesh.hpp"
#include "lidarsurf/sim/procedural_scene.hpp"
#include "lidarsurf/sim/simulator.hpp"

namespace lidarsurf::test {

// A short drive through the town: each frame's scan in the world frame, and where it was seen from.
struct Scan {
    std::vector<Eigen::Vector3d> points;
    Eigen::Vector3d from;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // the sensor's
};
inline const std::vector<Scan>& town_drive() {
    static const std::vector<Scan> scans = [] {
        sim::SceneConfig scene;
        scene.length = 120;
        sim::SimulatorConfig sc;
        sc.frames = 6;
        sc.gt_beams = 0;
        const sim::Simulator simulator(sim::make_world(scene), sc);
        std::vector<Scan> out;
        for (std::size_t i = 0; i < simulator.frame_count(); ++i) {
            const sim::SimulatedFrame f = simulator.frame(i);
            Scan s{{}, f.pose.translation(), f.pose};
            for (const Eigen::Vector3d& p : f.scan.points) s.points.push_back(f.pose * p);
            out.push_back(std::move(s));
        }
        return out;
    }();
    return scans;
}

// A triangle as its three corners, rotated to start at the smallest (the orientation kept): the
// same triangle whatever the vertex numbering of the mesh it comes from.
using Corner = std::array<double, 3>;
using Triangle = std::array<Corner, 3>;
inline std::vector<Triangle> triangles_of(const Mesh& m) {
    std::vector<Triangle> out;
    out.reserve(m.triangles.size());
    for (const auto& t : m.triangles) {
        Triangle tri;
        for (int k = 0; k < 3; ++k) {
            const Eigen::Vector3d& p = m.vertices[t[static_cast<std::size_t>(k)]];
            tri[static_cast<std::size_t>(k)] = {p.x(), p.y(), p.z()};
        }
        std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
        out.push_back(tri);
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace lidarsurf::test
